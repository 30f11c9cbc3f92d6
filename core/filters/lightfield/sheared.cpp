#include "filters/lightfield/sheared.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>

#include "filters/lightfield/lightfield_info.h"
#include "kernels/lightfield_input.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

const FilterInfo& ShearedFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "sheared";
    i.summary = "Fast 4D sheared filter over light-field samples (deep EXR): soft shadows, depth of field, "
                "indirect light, factored into four 1D steps";
    i.reference = "Yan et al. 2015, eq. 9-15; sec. 5 (16 bins, 32-pixel cap, slope smoothing, axis-aligned fallback)";
    i.params = with_preparation_params({lf::max_width_param(), lf::residual_k_param(), lf::residual_radius_param(),
                                        lf::step_back_param(), lf::step_back_radius_param(), lf::lens_light_param(),
                                        lf::bins_param(), lf::fallback_param(),
                                        lf::mu_param(true), lf::smooth_radius_param(), lf::bounds_radius_param(), lf::reject_param(),
                                        lf::normal_degrees_param()},
                                       PrepSteps::none());
    lf::light_field_info(i);
    return i;
  }();
  return info;
}

std::vector<std::string> ShearedFilter::own_unused() const {
  std::vector<std::string> u = Filter::own_unused();
  unused_when(params_.get_enum("fallback") != "aaf", "mu", "with fallback=own", u);
  unused_when(!params_.get_bool("reject"), "normal_degrees", "with reject=false", u);
  return u;
}

namespace {

// Bins over [-bmax, bmax]: centre(i) = -bmax + (i + 0.5) delta.
struct Bins {
  int n;
  float bmax, delta, inv_delta;
  Bins(int n_, float bmax_) : n(n_), bmax(bmax_), delta(2 * bmax_ / float(n_)), inv_delta(float(n_) / (2 * bmax_)) {}
  float centre(int i) const { return -bmax + (float(i) + 0.5f) * delta; }
};

// Two bins and their weights (a weight of 0 for a bin outside the range, index clamped).
struct Tent {
  int a = 0, b = 0;
  float wa = 0, wb = 0;
};

// Reading at v: linear between centres, 0 beyond the outer centres (fading over half a bin).
Tent read_tent(const Bins& bins, float v) {
  Tent t;
  const float pos = (v + bins.bmax) * bins.inv_delta - 0.5f;
  if (!(pos > -1.0f && pos < float(bins.n))) return t;
  const float f = std::floor(pos);
  const float u = pos - f;
  t.a = int(f);
  t.b = t.a + 1;
  t.wa = 1 - u;
  t.wb = u;
  if (t.a < 0) {
    t.a = 0;
    t.wa = 0;
  }
  if (t.b > bins.n - 1) {
    t.b = bins.n - 1;
    t.wb = 0;
  }
  return t;
}

// Scattering a coordinate v: linear between centres, clamped to the outer bins.
Tent scatter_tent(const Bins& bins, float v) {
  Tent t;
  float pos = (v + bins.bmax) * bins.inv_delta - 0.5f;
  if (!(pos >= 0)) pos = 0;  // NaN too
  if (pos > float(bins.n - 1)) pos = float(bins.n - 1);
  const float f = std::floor(pos);
  t.a = int(f);
  t.b = std::min(t.a + 1, bins.n - 1);
  t.wb = pos - f;
  t.wa = 1 - t.wb;
  return t;
}

}  // namespace

void sheared_lightfield(const LightField& lf, const lf::Options& o, const Roi& roi, int nthreads, Image& out,
                        lf::Counts* counts) {
  if (out.width() != lf.width || out.height() != lf.height || out.channels() < 3)
    throw Error(Errc::Internal, "sheared: the output is not the light field's size");
  lf::Counts c;
  const std::vector<lf::Rule> rules = lf::pixel_rules(lf, o, lf::Mode::Sheared, roi, &c);
  const lf::WeightY wy(lf);
  const lf::Displacement disp(lf);  // 1b, 2b: exact x_i from world positions when present
  const lf::Rejection rej(lf, o);
  const int w = lf.width, h = lf.height;
  const std::size_t n = lf.pixels(), spp = std::size_t(lf.spp());
  const int B = std::max(2, o.bins);
  const Bins bins(B, lf.effect == LightFieldEffect::Gi ? 2 * lf.y_range : lf.y_range + 2 * lf.sigma_y);
  const int cap = std::max(0, o.max_width / 2);
  const std::size_t B4 = std::size_t(B) * 4;
  const Roi r1all = roi.grown(2 * cap + 2, w, h);  // every pixel 1a may serve

  // Step 1a, the groups: the distinct y2 values of a pixel's samples, in increasing order.
  std::vector<std::uint32_t> groups(n, 0);
  parallel_rows(r1all.y0, r1all.y1, nthreads, [&](int y) {
    std::vector<float> v(spp);
    for (int x = r1all.x0; x < r1all.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
      std::copy(lf.y2.begin() + std::ptrdiff_t(p * spp), lf.y2.begin() + std::ptrdiff_t((p + 1) * spp), v.begin());
      std::sort(v.begin(), v.end());
      groups[p] = std::uint32_t(std::unique(v.begin(), v.end()) - v.begin());
    }
  });
  std::vector<std::size_t> row_groups(std::size_t(h) + 1, 0);  // prefix over rows
  for (int y = 0; y < h; ++y) {
    std::size_t s = 0;
    for (int x = 0; x < w; ++x) s += groups[std::size_t(y) * std::size_t(w) + std::size_t(x)];
    row_groups[std::size_t(y) + 1] = row_groups[std::size_t(y)] + s;
  }
  // Gaussian w_y at the bin centres by a recurrence over the bins (two exp per sample, not B):
  // w_{b+1} = w_b exp(2 u delta k) exp(-(2b+1) delta^2 k), u = y1 - centre(0), k = 1/(2 sigma_y^2),
  // in double while every factor stays far inside its range (else exp per bin).
  const double k2 = wy.inv2sy2, dlt = bins.delta;
  std::vector<double> step(std::size_t(B), 1.0);
  for (int bi = 0; bi + 1 < B; ++bi) step[std::size_t(bi)] = std::exp(-double(2 * bi + 1) * dlt * dlt * k2);
  std::vector<float> wyy(std::size_t(B) * std::size_t(B));  // w_y(centre(b2) - centre(c)) at [b2 * B + c]
  for (int b2 = 0; b2 < B; ++b2)
    for (int cc = 0; cc < B; ++cc) wyy[std::size_t(b2 * B + cc)] = wy(bins.centre(b2) - bins.centre(cc));

  // Bands of output rows, so that p (1a) and q (2a) of a band's rows grown by 2 cap + 2 and
  // cap + 1 fit in o.band_bytes (at least one row per band); the rows they share with the next
  // band are computed again there (same values: each pixel's steps read only the light field).
  auto band_rois = [&](int y0, int y1, Roi* r1, Roi* r2) {
    *r2 = Roi{roi.x0, y0, roi.x1, y1}.grown(cap + 1, w, h);
    *r1 = r2->grown(cap + 1, w, h);
  };
  auto band_bytes = [&](int y0, int y1) {
    Roi r1, r2;
    band_rois(y0, y1, &r1, &r2);
    return (row_groups[std::size_t(r1.y1)] - row_groups[std::size_t(r1.y0)]) * B4 * sizeof(float) +
           std::size_t(r2.height()) * std::size_t(w) * B4 * sizeof(float);
  };
  std::atomic<std::size_t> zero{0};
  std::vector<std::size_t> gofs;
  std::vector<float> gy2, pre, qv;
  for (int y0 = roi.y0; y0 < roi.y1;) {
    int y1 = y0 + 1;
    while (y1 < roi.y1 && band_bytes(y0, y1 + 1) <= o.band_bytes) ++y1;
    Roi r1, r2;
    band_rois(y0, y1, &r1, &r2);
    const std::size_t base1 = std::size_t(r1.y0) * std::size_t(w), n1 = std::size_t(r1.height()) * std::size_t(w);
    const std::size_t base2 = std::size_t(r2.y0) * std::size_t(w), n2 = std::size_t(r2.height()) * std::size_t(w);
    gofs.assign(n1 + 1, 0);
    for (std::size_t i = 0; i < n1; ++i) {
      const int x = int((base1 + i) % std::size_t(w));
      gofs[i + 1] = gofs[i] + (x >= r1.x0 && x < r1.x1 ? groups[base1 + i] : 0);
    }
    gy2.assign(gofs[n1], 0.0f);
    pre.assign(gofs[n1] * B4, 0.0f);  // [group][bin][r, g, b, weight]

    // Step 1a: p_Q(b, y2) at the bin centres, per group.
    parallel_rows(r1.y0, r1.y1, nthreads, [&](int y) {
      std::vector<std::size_t> idx(spp);
      std::vector<double> acc(B4), wb(static_cast<std::size_t>(B));
      for (int x = r1.x0; x < r1.x1; ++x) {
        const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
        std::iota(idx.begin(), idx.end(), p * spp);
        std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return lf.y2[a] < lf.y2[b]; });
        std::size_t g = gofs[p - base1];
        for (std::size_t i = 0; i < spp;) {
          std::size_t e = i;
          while (e < spp && lf.y2[idx[e]] == lf.y2[idx[i]]) ++e;
          gy2[g] = lf.y2[idx[i]];
          std::fill(acc.begin(), acc.end(), 0.0);
          for (std::size_t m = i; m < e; ++m) {
            const std::size_t k = idx[m];
            const double u = double(lf.y1[k]) - double(bins.centre(0));
            if (!wy.box && u * u * k2 < 600 && 2 * std::fabs(u) * dlt * k2 < 600) {
              double wk = std::exp(-u * u * k2);
              const double a = std::exp(2 * u * dlt * k2);
              for (int bi = 0; bi < B; ++bi) {
                wb[std::size_t(bi)] = wk;
                wk *= a * step[std::size_t(bi)];
              }
              for (int bi = 0; bi < B; ++bi)  // the light's edge (WeightY)
                if (!(std::fabs(lf.y1[k] - bins.centre(bi)) <= wy.range)) wb[std::size_t(bi)] = 0;
            } else {
              for (int bi = 0; bi < B; ++bi) wb[std::size_t(bi)] = wy(lf.y1[k] - bins.centre(bi));
            }
            const double f0 = lf.r[k], f1 = lf.g[k], f2 = lf.b[k];
            for (int bi = 0; bi < B; ++bi) {
              const double wk = wb[std::size_t(bi)];
              double* d = acc.data() + std::size_t(bi) * 4;
              d[0] += wk * f0;
              d[1] += wk * f1;
              d[2] += wk * f2;
              d[3] += wk;
            }
          }
          float* dst = pre.data() + g * B4;
          for (std::size_t j = 0; j < B4; ++j) dst[j] = float(acc[j]);
          ++g;
          i = e;
        }
      }
    });

    // Steps 1b and 2a: q per pixel of r2, [bin][r, g, b, weight].
    qv.assign(n2 * B4, 0.0f);
    parallel_rows(r2.y0, r2.y1, nthreads, [&](int y) {
      std::vector<double> g(B4);
      for (int x = r2.x0; x < r2.x1; ++x) {
        const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
        const lf::Rule& r = rules[p];
        std::fill(g.begin(), g.end(), 0.0);
        const float ux = r.r1 > 0 ? lf.e1x[p] / r.len1 : 0.0f, uy = r.r1 > 0 ? lf.e1y[p] / r.len1 : 0.0f;
        const float pixel_world = 1.0f / std::min(r.len1, r.len2);
        for (int j = -r.r1; j <= r.r1; ++j) {
          int qx, qy;
          if (!lf::step_pixel(x, y, ux, uy, j, w, h, &qx, &qy)) continue;
          const std::size_t q = std::size_t(qy) * std::size_t(w) + std::size_t(qx);
          const float t = disp.along(p, q, 0, r.r1 > 0 ? float(j) / r.len1 : 0.0f);
          if (rej.rejects(p, q, std::fabs(t), pixel_world)) continue;
          const float wx = lf::weight_x(t * t, r.inv2sx2);
          const Tent T = read_tent(bins, -r.eta * t);
          if (wx == 0 || (T.wa == 0 && T.wb == 0)) continue;
          const double fa = double(wx) * T.wa, fb = double(wx) * T.wb;
          for (std::size_t gi = gofs[q - base1]; gi < gofs[q - base1 + 1]; ++gi) {
            const Tent S = scatter_tent(bins, gy2[gi]);
            const float* pa = pre.data() + gi * B4 + std::size_t(T.a) * 4;
            const float* pb = pre.data() + gi * B4 + std::size_t(T.b) * 4;
            double* ga = g.data() + std::size_t(S.a) * 4;
            double* gb = g.data() + std::size_t(S.b) * 4;
            for (int ch = 0; ch < 4; ++ch) {
              const double v = fa * pa[ch] + fb * pb[ch];
              ga[ch] += S.wa * v;
              gb[ch] += S.wb * v;
            }
          }
        }
        float* dst = qv.data() + (p - base2) * B4;
        for (int cc = 0; cc < B; ++cc) {
          double s[4] = {0, 0, 0, 0};
          for (int b2 = 0; b2 < B; ++b2) {
            const double k = wyy[std::size_t(b2 * B + cc)];
            if (k == 0) continue;
            for (int ch = 0; ch < 4; ++ch) s[ch] += k * g[std::size_t(b2) * 4 + std::size_t(ch)];
          }
          for (int ch = 0; ch < 4; ++ch) dst[cc * 4 + ch] = float(s[ch]);
        }
      }
    });

    // Step 2b.
    parallel_rows(y0, y1, nthreads, [&](int y) {
      std::size_t zero_row = 0;
      for (int x = roi.x0; x < roi.x1; ++x) {
        const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
        const lf::Rule& r = rules[p];
        float* o3 = out.pixel(x, y);
        if (r.own_output) {
          lf::own_mean(lf, wy, p, o3);
          continue;
        }
        const float ux = r.r2 > 0 ? lf.e2x[p] / r.len2 : 0.0f, uy = r.r2 > 0 ? lf.e2y[p] / r.len2 : 0.0f;
        const float pixel_world = 1.0f / std::min(r.len1, r.len2);
        double s[4] = {0, 0, 0, 0};
        for (int j = -r.r2; j <= r.r2; ++j) {
          int qx, qy;
          if (!lf::step_pixel(x, y, ux, uy, j, w, h, &qx, &qy)) continue;
          const std::size_t q = std::size_t(qy) * std::size_t(w) + std::size_t(qx);
          const float t = disp.along(p, q, 1, r.r2 > 0 ? float(j) / r.len2 : 0.0f);
          if (rej.rejects(p, q, std::fabs(t), pixel_world)) continue;
          const float wx = lf::weight_x(t * t, r.inv2sx2);
          const Tent T = read_tent(bins, -r.eta * t);
          const double fa = double(wx) * T.wa, fb = double(wx) * T.wb;
          const float* qa = qv.data() + (q - base2) * B4 + std::size_t(T.a) * 4;
          const float* qb = qv.data() + (q - base2) * B4 + std::size_t(T.b) * 4;
          for (int ch = 0; ch < 4; ++ch) s[ch] += fa * qa[ch] + fb * qb[ch];
        }
        bool ok = s[3] > 0 && std::isfinite(s[3]);
        for (int ch = 0; ch < 3 && ok; ++ch) ok = std::isfinite(s[ch] / s[3]);
        if (!ok) {
          ++zero_row;
          lf::own_mean(lf, wy, p, o3);
          continue;
        }
        for (int ch = 0; ch < 3; ++ch) o3[ch] = float(s[ch] / s[3]);
      }
      zero += zero_row;
    });
    y0 = y1;
  }
  c.zero_weight = zero.load();
  if (counts) *counts = c;
}

void ShearedFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  (void)colour;
  for (std::string& n : lf::run_on_frame(frame, info().name, lf::options_from(params_), roi, nthreads, out, &sheared_lightfield, true))
    note(std::move(n));
}

}  // namespace mcr
