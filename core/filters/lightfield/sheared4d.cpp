#include "filters/lightfield/sheared4d.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "filters/lightfield/lightfield_info.h"
#include "kernels/lightfield_input.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

const FilterInfo& Sheared4dFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "sheared4d";
    i.summary = "Brute-force 4D sheared filter over light-field samples (deep EXR): soft shadows, depth of field, "
                "indirect light; the slow reference of 'sheared'";
    i.reference = "Yan et al. 2015, eq. 3-5, 9; sec. 5 (slope smoothing, axis-aligned fallback)";
    i.params = with_preparation_params({lf::max_width_param(), lf::residual_k_param(), lf::residual_radius_param(),
                                        lf::step_back_param(), lf::step_back_radius_param(), lf::lens_light_param(),
                                        lf::fallback_param(), lf::mu_param(true),
                                        lf::smooth_radius_param(), lf::bounds_radius_param(), lf::reject_param(), lf::normal_degrees_param()},
                                       PrepSteps::none());
    lf::light_field_info(i);
    return i;
  }();
  return info;
}

std::vector<std::string> Sheared4dFilter::own_unused() const {
  std::vector<std::string> u = Filter::own_unused();
  unused_when(params_.get_enum("fallback") != "aaf", "mu", "with fallback=own", u);
  unused_when(!params_.get_bool("reject"), "normal_degrees", "with reject=false", u);
  return u;
}

void sheared4d_lightfield(const LightField& lf, const lf::Options& o, const Roi& roi, int nthreads, Image& out,
                          lf::Counts* counts) {
  if (out.width() != lf.width || out.height() != lf.height || out.channels() < 3)
    throw Error(Errc::Internal, "sheared4d: the output is not the light field's size");
  lf::Counts c;
  const std::vector<lf::Rule> rules = lf::pixel_rules(lf, o, lf::Mode::Sheared, roi, &c);
  const lf::WeightY wy(lf);
  const lf::Rejection rej(lf, o);
  const lf::Displacement disp(lf);
  const int w = lf.width, h = lf.height;
  const std::size_t spp = std::size_t(lf.spp());
  std::atomic<std::size_t> zero{0};
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    std::size_t zero_row = 0;
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
      const lf::Rule& r = rules[p];
      float* o3 = out.pixel(x, y);
      if (r.own_output) {
        lf::own_mean(lf, wy, p, o3);
        continue;
      }
      const float e1x = lf.e1x[p], e1y = lf.e1y[p], e2x = lf.e2x[p], e2y = lf.e2y[p];
      const float det = e1x * e2y - e1y * e2x;
      // (d1, d2) = M (dx, dy), M the inverse of [e1 e2].
      const float m11 = e2y / det, m12 = -e2x / det, m21 = -e1y / det, m22 = e1x / det;
      const float bx = float(r.r1) * std::fabs(e1x) / r.len1 + float(r.r2) * std::fabs(e2x) / r.len2;
      const float by = float(r.r1) * std::fabs(e1y) / r.len1 + float(r.r2) * std::fabs(e2y) / r.len2;
      const int rx = int(std::ceil(bx)), ry = int(std::ceil(by));
      const float pixel_world = 1.0f / std::min(r.len1, r.len2);
      double s[3] = {0, 0, 0}, ws = 0;
      for (int qy = std::max(0, y - ry); qy <= std::min(h - 1, y + ry); ++qy)
        for (int qx = std::max(0, x - rx); qx <= std::min(w - 1, x + rx); ++qx) {
          const float dx = float(qx - x), dy = float(qy - y);
          const float l1 = m11 * dx + m12 * dy, l2 = m21 * dx + m22 * dy;
          // The window is the screen's parallelogram; the weights take the exact displacement.
          if (std::fabs(l1) * r.len1 > float(r.r1) + 1e-3f || std::fabs(l2) * r.len2 > float(r.r2) + 1e-3f) continue;
          const std::size_t q = std::size_t(qy) * std::size_t(w) + std::size_t(qx);
          const float d1 = disp.along(p, q, 0, l1), d2 = disp.along(p, q, 1, l2);
          if (rej.rejects(p, q, std::sqrt(d1 * d1 + d2 * d2), pixel_world)) continue;
          const float wx = lf::weight_x(d1 * d1 + d2 * d2, r.inv2sx2);
          if (wx == 0) continue;
          const float a1 = r.eta * d1, a2 = r.eta * d2;
          for (std::size_t k = q * spp; k < (q + 1) * spp; ++k) {
            const double wk = double(wx) * double(wy(lf.y1[k] + a1)) * double(wy(lf.y2[k] + a2));
            s[0] += wk * lf.r[k];
            s[1] += wk * lf.g[k];
            s[2] += wk * lf.b[k];
            ws += wk;
          }
        }
      bool ok = ws > 0 && std::isfinite(ws);
      for (int ch = 0; ch < 3 && ok; ++ch) ok = std::isfinite(s[ch] / ws);
      if (!ok) {
        ++zero_row;
        lf::own_mean(lf, wy, p, o3);
        continue;
      }
      for (int ch = 0; ch < 3; ++ch) o3[ch] = float(s[ch] / ws);
    }
    zero += zero_row;
  });
  c.zero_weight = zero.load();
  if (counts) *counts = c;
}

void Sheared4dFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  (void)colour;
  for (std::string& n : lf::run_on_frame(frame, info().name, lf::options_from(params_), roi, nthreads, out, &sheared4d_lightfield, true))
    note(std::move(n));
}

}  // namespace mcr
