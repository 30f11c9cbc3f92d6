#include "filters/lightfield/aaf.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "filters/lightfield/lightfield_info.h"
#include "kernels/lightfield_input.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

const FilterInfo& AafFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "aaf";
    i.summary = "Axis-aligned filtering of light-field samples (deep EXR): each pixel's samples integrated over y, "
                "then a spatial Gaussian from the slope bounds";
    i.reference = "Mehta et al. 2012 (sigma_x from the minimum slope, mu); Yan et al. 2015 sec. 3.1, 5";
    i.params = with_preparation_params({lf::max_width_param(), lf::residual_k_param(), lf::residual_radius_param(),
                                        lf::step_back_param(), lf::step_back_radius_param(), lf::lens_light_param(),
                                        lf::mu_param(false), lf::smooth_radius_param(), lf::bounds_radius_param(),
                                        lf::reject_param(), lf::normal_degrees_param()},
                                       PrepSteps::none());
    lf::light_field_info(i);
    return i;
  }();
  return info;
}

std::vector<std::string> AafFilter::own_unused() const {
  std::vector<std::string> u = Filter::own_unused();
  unused_when(!params_.get_bool("reject"), "normal_degrees", "with reject=false", u);
  return u;
}

namespace {

// One normalised Gaussian pass along axis (ex, ey) of every pixel of `region`: dst = sum
// w_x(t_j) src(Q_j) / sum w_x(t_j); false when every weight was 0 (dst = src then).
bool pass_along(const LightField& lf, const lf::Rule& r, const lf::Rejection& rej, int x, int y, bool first,
                const std::vector<float>& src, float* dst) {
  const int w = lf.width, h = lf.height;
  const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
  const int rad = first ? r.r1 : r.r2;
  const float len = first ? r.len1 : r.len2;
  const float ux = rad > 0 ? (first ? lf.e1x[p] : lf.e2x[p]) / len : 0.0f;
  const float uy = rad > 0 ? (first ? lf.e1y[p] : lf.e2y[p]) / len : 0.0f;
  const float pixel_world = 1.0f / std::min(r.len1, r.len2);
  double s[3] = {0, 0, 0}, ws = 0;
  for (int j = -rad; j <= rad; ++j) {
    int qx, qy;
    if (!lf::step_pixel(x, y, ux, uy, j, w, h, &qx, &qy)) continue;
    const std::size_t q = std::size_t(qy) * std::size_t(w) + std::size_t(qx);
    const float t = lf::Displacement(lf).along(p, q, first ? 0 : 1, rad > 0 ? float(j) / len : 0.0f);
    if (rej.rejects(p, q, std::fabs(t), pixel_world)) continue;
    const double wx = lf::weight_x(t * t, r.inv2sx2);
    for (int ch = 0; ch < 3; ++ch) s[ch] += wx * src[q * 3 + std::size_t(ch)];
    ws += wx;
  }
  bool ok = ws > 0 && std::isfinite(ws);
  for (int ch = 0; ch < 3 && ok; ++ch) ok = std::isfinite(s[ch] / ws);
  for (int ch = 0; ch < 3; ++ch) dst[ch] = ok ? float(s[ch] / ws) : src[p * 3 + std::size_t(ch)];
  return ok;
}

}  // namespace

void aaf_lightfield(const LightField& lf, const lf::Options& o, const Roi& roi, int nthreads, Image& out,
                    lf::Counts* counts) {
  if (out.width() != lf.width || out.height() != lf.height || out.channels() < 3)
    throw Error(Errc::Internal, "aaf: the output is not the light field's size");
  lf::Counts c;
  const std::vector<lf::Rule> rules = lf::pixel_rules(lf, o, lf::Mode::AxisAligned, roi, &c);
  const lf::WeightY wy(lf);
  const lf::Rejection rej(lf, o);
  const int w = lf.width, h = lf.height;
  const std::size_t n = lf.pixels();
  const int cap = std::max(0, o.max_width / 2);
  const Roi r2 = roi.grown(cap + 1, w, h);  // the first pass: the pixels the second reads
  const Roi r1 = r2.grown(cap + 1, w, h);   // the own means: the pixels the first reads
  std::vector<float> own(n * 3, 0.0f), first(n * 3, 0.0f);
  parallel_rows(r1.y0, r1.y1, nthreads, [&](int y) {
    for (int x = r1.x0; x < r1.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
      lf::own_mean(lf, wy, p, own.data() + p * 3);
    }
  });
  parallel_rows(r2.y0, r2.y1, nthreads, [&](int y) {
    for (int x = r2.x0; x < r2.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
      pass_along(lf, rules[p], rej, x, y, true, own, first.data() + p * 3);
    }
  });
  std::atomic<std::size_t> zero{0};
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    std::size_t zero_row = 0;
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
      float* o3 = out.pixel(x, y);
      if (rules[p].own_output) {
        for (int ch = 0; ch < 3; ++ch) o3[ch] = own[p * 3 + std::size_t(ch)];
        continue;
      }
      if (!pass_along(lf, rules[p], rej, x, y, false, first, o3)) {
        ++zero_row;
        for (int ch = 0; ch < 3; ++ch) o3[ch] = own[p * 3 + std::size_t(ch)];
      }
    }
    zero += zero_row;
  });
  c.zero_weight = zero.load();
  if (counts) *counts = c;
}

void AafFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  (void)colour;
  for (std::string& n : lf::run_on_frame(frame, info().name, lf::options_from(params_), roi, nthreads, out, &aaf_lightfield, false))
    note(std::move(n));
}

}  // namespace mcr
