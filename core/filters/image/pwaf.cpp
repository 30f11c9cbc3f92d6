#include "filters/image/pwaf.h"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "image/luminance.h"
#include "kernels/feature_activity.h"
#include "kernels/noise_variance.h"
#include "kernels/planes.h"
#include "kernels/pwaf_window.h"
#include "prepare/outliers.h"
#include "util/error.h"
#include "util/median.h"
#include "util/parallel.h"

namespace mcr {

namespace {

constexpr double kFloatMax = double(std::numeric_limits<float>::max());
// Exponents are clamped here so that sums of huge terms stay finite (no inf - inf).
constexpr double kMaxExponent = 1e300;

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// A geometric feature pass and its Gaussian's 1 / (2 sigma^2).
struct Feature {
  const Image* image = nullptr;  // nullptr: the weight is dropped
  double inv2s2 = 0;             // sigma in the feature's units (scaled, for positions)
};

// Reads the first 3 channels of a feature pixel (the last one repeated if fewer); false when
// one is not finite.
bool feature_at(const Image& im, int x, int y, float v[3]) {
  const float* p = im.pixel(x, y);
  const int nc = im.channels();
  for (int c = 0; c < 3; ++c) v[c] = p[std::min(c, nc - 1)];
  return finite3(v);
}

// The non-zero distances between horizontally and vertically adjacent finite pixels whose
// first pixel lies in `rows` (the pair below a row's pixel is taken where the image has it).
void adjacent_distances(const Image& im, const Roi& rows, std::vector<float>& d) {
  const int w = im.width(), h = im.height();
  auto dist = [&](int x0, int y0, int x1, int y1) {
    float a[3], b[3];
    if (!feature_at(im, x0, y0, a) || !feature_at(im, x1, y1, b)) return;
    double s = 0;
    for (int c = 0; c < 3; ++c) {
      const double t = double(a[c]) - double(b[c]);
      s += t * t;
    }
    if (s > 0) d.push_back(float(std::sqrt(s)));
  };
  for (int y = rows.y0; y < rows.y1; ++y)
    for (int x = 0; x < w; ++x) {
      if (x + 1 < w) dist(x, y, x + 1, y);
      if (y + 1 < h) dist(x, y, x, y + 1);
    }
}

// spacing: the frame's median adjacent distance when measured beforehand (a tiled run), else
// negative: measured here over the whole image.
Feature make_feature(const Pass* pass, double sigma, bool scale_by_spacing, double spacing) {
  Feature f;
  if (!pass) return f;
  f.image = &pass->image;
  const Image& im = pass->image;
  double scale = 1.0;
  if (scale_by_spacing) {
    // Positions are in scene units: sigma is given in units of the frame's median distance
    // between horizontally or vertically adjacent pixels (non-zero distances of finite pairs),
    // so one default fits any scene scale. Computed over the whole frame, whatever the roi.
    if (spacing >= 0) {
      if (spacing > 0) scale = spacing;
    } else {
      std::vector<float> d;
      d.reserve(std::size_t(im.width()) * std::size_t(im.height()) * 2);
      adjacent_distances(im, Roi::all(im.width(), im.height()), d);
      if (!d.empty()) scale = upper_median(d);
    }
  }
  const double s = sigma * scale;
  f.inv2s2 = 1.0 / (2.0 * s * s);
  if (!std::isfinite(f.inv2s2)) f.inv2s2 = kMaxExponent;  // sigma*scale underflowed: any difference stops
  return f;
}



}  // namespace

// ---------------------------------------------------------------------------------------------
// Building blocks

namespace pwaf {

double relative_variance(double variance, double lum) { return variance / (lum * lum + 0.01); }

int window_radius(double rel_variance, double rho_max, int min_r, int max_r) {
  if (!(rel_variance >= 0) || !std::isfinite(rel_variance)) return max_r;
  if (!(rho_max > 0)) return rel_variance > 0 ? max_r : min_r;
  const double t = std::clamp(rel_variance / rho_max, 0.0, 1.0);
  return min_r + int(std::lround(t * double(max_r - min_r)));
}


}  // namespace pwaf

// ---------------------------------------------------------------------------------------------
// The filter

const FilterInfo& PwafFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "pwaf";
    i.summary = "Point-wise adaptive cross-bilateral filter: window radius per pixel from its colour variance";
    i.reference = "Guo & Pan 2012, Point-wise Adaptive Filtering for Fast Monte Carlo Noise Reduction (eq. 8, 3.2, 3.3)";
    i.params = with_common_params({
        ParamSpec::Int("min_radius", 3, 0, 32, "window half width for the least noisy pixels"),
        ParamSpec::Int("max_radius", 8, 0, 32, "window half width for pixels at or above variance_max (and everywhere when adaptive=false)"),
        ParamSpec::Bool("adaptive", true, "per-pixel window radius from the colour variance; false = max_radius everywhere (Table 1's fixed windows)"),
        ParamSpec::Float("variance_max", 6.0, 1e-6, 1e6,
                         "the radius reaches max_radius at this multiple of the frame's median relative variance v/(Y^2+0.01); linear below"),
        ParamSpec::Float("sigma_p", 3.0, 0.1, 1e6, "Gp: spatial standard deviation in pixels"),
        ParamSpec::Float("sigma_c", 1.0, 1e-3, 1e6, "Gc: colour standard deviation in units of the pixel's noise standard deviation sqrt(v)"),
        ParamSpec::Float("sigma_n", 0.1, 1e-4, 1e6, "Gn: first-hit normal standard deviation (normal units)"),
        ParamSpec::Float("sigma_sp", 8.0, 1e-4, 1e6, "Gsp: second-hit (fallback: first-hit) position standard deviation, in median adjacent-pixel distances of that pass"),
        ParamSpec::Float("sigma_sn", 0.5, 1e-4, 1e6, "Gsn: second-hit normal standard deviation (normal units)"),
        ParamSpec::Float("prefilter_sigma", 1.0, 0.0, 8.0, "estimated range value: fixed Gaussian (pixels) over the outlier-suppressed colour; 0 = the pixel's own value"),
        ParamSpec::Float("outlier_k", 5.0, 0.0, 1e3, "a pixel is an outlier when its luminance exceeds its neighbours' mean by k standard deviations (and by 1%); 0 = off"),
        ParamSpec::Int("outlier_radius", 3, 1, 8, "outlier statistics window half width"),
        ParamSpec::Int("variance_radius", 3, 1, 16, "half width of the window that clusters the variance (estimate or pass)"),
    });
    edge_keeping_step_back(i.params);
    // Demodulated by default (chosen on room+glossy): pwaf has no albedo weight, and its
    // variance estimate counts texture edges as noise (high-pass residuals), so on a clean
    // render Gc let textures blur (glossy 64 spp: 0.0103 against the input's 0.0066; 0.0056
    // demodulated). Without an albedo pass the step is skipped with a note unless
    // demodulate=true was given (prepare/preparation.h).
    for (ParamSpec& s : i.params)
      if (s.name == "demodulate") {
        s.default_value = true;
        s.help += " (pwaf: default true; skipped with a note when the render has no albedo pass and demodulate was "
                  "not given)";
      }
    i.required = {Role::Colour};
    i.optional = {Role::Normal, Role::Position, Role::SecondPosition, Role::SecondNormal, Role::Variance, Role::SampleCount};
    i.nonfinite_policy =
        "colour pixels with a NaN/Inf channel are replaced by the mean of the finite pixels of their outlier window "
        "(left out of every window and output 0 only when that window has none); a non-finite feature value switches "
        "that feature's Gaussian off (factor 1) for every pair that involves the pixel; a non-finite or negative "
        "variance-pass value is ignored (the estimate is used where none is left); the colour is scaled by a power "
        "of two into a range where no float sum overflows, weights are relative to each window's largest (a window "
        "never sums to 0 by underflow) and outputs are clamped to the float range, so no NaN/Inf is ever produced";
    return i;
  }();
  return info;
}

void PwafFilter::check_params() {
  if (params_.get_int("min_radius") > params_.get_int("max_radius"))
    throw Error(Errc::InvalidArgument, "filter 'pwaf': min_radius (" + std::to_string(params_.get_int("min_radius")) +
                                           ") must not exceed max_radius (" + std::to_string(params_.get_int("max_radius")) + ")");
}

void PwafFilter::measure_band(const Frame& band, const Image& colour, const Roi& rows, int nthreads) {
  const Pass* pos = band.find(Role::SecondPosition);
  if (!pos) pos = band.find(Role::Position, Prefer::Geometry);
  if (pos) adjacent_distances(pos->image, rows, measured_spacing_);
  if (!params_.get_bool("adaptive")) return;
  run_to_measure(band, colour, rows, nthreads);
}

void PwafFilter::fix_statistics() {
  fixed_spacing_ = upper_median(measured_spacing_);
  fixed_rho_median_ = upper_median(measured_rho_);
  drop_measured();
}

void PwafFilter::drop_measured() {
  std::vector<float>().swap(measured_spacing_);
  std::vector<float>().swap(measured_rho_);
}

void PwafFilter::drop_own_statistics() {
  drop_measured();
  fixed_spacing_ = fixed_rho_median_ = 0;
}

int PwafFilter::own_reach() const {
  // The window over the range value (the prefilter) and the variance (its window of 8-neighbour
  // residuals), both over the outlier-replaced colour.
  const double pf_sigma = params_.get_float("prefilter_sigma");
  const int pf_r = pf_sigma > 0 ? int(std::ceil(3.0 * pf_sigma)) : 0;
  return int(params_.get_int("max_radius")) + std::max(pf_r, int(params_.get_int("variance_radius")) + 1) +
         int(params_.get_int("outlier_radius")) + 2;
}

std::vector<std::string> PwafFilter::own_unused() const {
  std::vector<std::string> u = Filter::own_unused();
  const bool adaptive = params_.get_bool("adaptive");
  for (const char* name : {"min_radius", "variance_max"}) unused_when(!adaptive, name, "with adaptive=false", u);
  return u;
}

void PwafFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  stats_ = PwafStats{};
  const int w = frame.width, h = frame.height;
  const int min_r = int(params_.get_int("min_radius")), max_r = int(params_.get_int("max_radius"));
  const bool adaptive = params_.get_bool("adaptive");
  const double variance_max = params_.get_float("variance_max");
  const double sigma_p = params_.get_float("sigma_p"), sigma_c = params_.get_float("sigma_c");
  const double pf_sigma = params_.get_float("prefilter_sigma");
  const double outlier_k = params_.get_float("outlier_k");
  const int os_r = int(params_.get_int("outlier_radius")), var_r = int(params_.get_int("variance_radius"));
  const int pf_r = pf_sigma > 0 ? int(std::ceil(3.0 * pf_sigma)) : 0;

  // ---- SS: outlier replacement, variance, radius per pixel ----
  const auto t_ss = Clock::now();
  // `stat`: where the variance, the range value and the radius are needed -- the roi, or the
  // whole frame when adaptive (the radius mapping is normalised by the frame's median). Every
  // stage runs on what the next one reads and each value depends only on the input, so a roi
  // gives the same pixels as the whole frame, and tiles agree at their seams.
  const Roi stat = adaptive ? Roi::all(w, h) : roi;
  const Roi support = stat.grown(std::max({max_r, pf_r, var_r + 1}), w, h);
  OutlierResult os = replace_outliers(colour, os_r, outlier_k, support, nthreads);
  for (int y = support.y0; y < support.y1; ++y)
    for (int x = support.x0; x < support.x1; ++x) {
      const std::uint8_t r = os.replaced[std::size_t(y) * w + x];
      stats_.outliers_replaced += r == 1;
      stats_.nonfinite_replaced += r == 2;
    }
  const Image& in = os.colour;
  const std::vector<std::uint8_t>& valid = os.valid;

  // Variance: the pass (mean of its channels, averaged over the variance window, invalid values
  // skipped) when present; the estimate where the pass is absent or has nothing valid near.
  std::vector<double> variance(std::size_t(w) * h, 0.0);
  const Pass* vpass = frame.find(Role::Variance);
  const Pass* spp = frame.find(Role::SampleCount);
  if (vpass) {
    stats_.variance_from_pass = true;
    const Image& vi = vpass->image;
    const int vc = std::min(3, vi.channels());
    // When the colour was demodulated (divided by a_c), the variance of I_c / a_c is
    // Var(I_c) / a_c^2, so the pass is divided likewise (a 1-channel pass by the mean of
    // 1 / a_c^2).
    const Image* divisor = demodulation_divisor();
    auto inv_a2 = [&](int x, int y, int c) {
      if (!divisor) return 1.0;
      const double a = double(divisor->pixel(x, y)[c]);
      return 1.0 / (a * a);
    };
    const Roi vreg = stat.grown(var_r, w, h);
    const int vw = vreg.width();
    std::vector<double> pv(std::size_t(vw) * vreg.height(), -1.0);  // -1: invalid
    parallel_rows(vreg.y0, vreg.y1, nthreads, [&](int y) {
      for (int x = vreg.x0; x < vreg.x1; ++x) {
        const float* p = vi.pixel(x, y);
        double s = 0;
        bool ok = true;
        for (int c = 0; c < vc; ++c) {
          ok = ok && std::isfinite(p[c]) && p[c] >= 0.0f;
          if (vc == 3) s += double(p[c]) * inv_a2(x, y, c);
          else s += double(p[c]) * (inv_a2(x, y, 0) + inv_a2(x, y, 1) + inv_a2(x, y, 2)) / 3.0;
        }
        if (ok && std::isfinite(s)) pv[std::size_t(y - vreg.y0) * vw + (x - vreg.x0)] = s / vc;
      }
    });
    std::vector<std::uint8_t> need_estimate(std::size_t(w) * h, 0);
    parallel_rows(stat.y0, stat.y1, nthreads, [&](int y) {
      for (int x = stat.x0; x < stat.x1; ++x) {
        double s = 0;
        int n = 0;
        for (int yy = std::max(vreg.y0, y - var_r); yy <= std::min(vreg.y1 - 1, y + var_r); ++yy)
          for (int xx = std::max(vreg.x0, x - var_r); xx <= std::min(vreg.x1 - 1, x + var_r); ++xx) {
            const double q = pv[std::size_t(yy - vreg.y0) * vw + (xx - vreg.x0)];
            if (q >= 0) { s += q; ++n; }
          }
        const std::size_t i = std::size_t(y) * w + x;
        if (n > 0 && std::isfinite(s)) variance[i] = s / n;
        else need_estimate[i] = 1;
      }
    });
    if (std::find(need_estimate.begin(), need_estimate.end(), 1) != need_estimate.end()) {
      const std::vector<double> est = estimate_variance(in, valid, spp ? &spp->image : nullptr, var_r, stat, nthreads);
      for (std::size_t i = 0; i < variance.size(); ++i)
        if (need_estimate[i]) variance[i] = est[i];
      note("pwaf: variance pass has no valid value around some pixels; variance estimated there from the image");
    }
  } else {
    variance = estimate_variance(in, valid, spp ? &spp->image : nullptr, var_r, stat, nthreads);
    note(std::string("pwaf: no variance pass; variance estimated from high-pass residuals over ") +
         std::to_string(2 * var_r + 1) + "x" + std::to_string(2 * var_r + 1) + " windows" +
         (spp ? ", per sample, divided by the sample count" : ""));
  }
  stats_.ss_ms = ms_since(t_ss);

  // ---- OS: estimated range value (fixed Gaussian of the outlier-suppressed colour) ----
  const auto t_os = Clock::now();
  Image est(w, h, 3, 0.0f);
  {
    std::vector<double> g(std::size_t(pf_r) + 1);
    for (int d = 0; d <= pf_r; ++d) g[std::size_t(d)] = pf_sigma > 0 ? std::exp(-0.5 * d * d / (pf_sigma * pf_sigma)) : 1.0;
    // Separable: g(dx) g(dy) factorises and validity is per pixel, so rows then columns give
    // the 2-D valid-weighted sum.
    const int hy0 = std::max(0, stat.y0 - pf_r), hy1 = std::min(h, stat.y1 + pf_r), sw = stat.width();
    std::vector<double> hs(std::size_t(hy1 - hy0) * sw * 4);
    parallel_rows(hy0, hy1, nthreads, [&](int y) {
      for (int x = stat.x0; x < stat.x1; ++x) {
        double s[4] = {0, 0, 0, 0};
        for (int xx = std::max(0, x - pf_r); xx <= std::min(w - 1, x + pf_r); ++xx) {
          if (!valid[std::size_t(y) * w + xx]) continue;
          const double gw = g[std::size_t(std::abs(xx - x))];
          const float* q = in.pixel(xx, y);
          for (int c = 0; c < 3; ++c) s[c] += gw * double(q[c]);
          s[3] += gw;
        }
        std::copy(s, s + 4, &hs[(std::size_t(y - hy0) * sw + (x - stat.x0)) * 4]);
      }
    });
    parallel_rows(stat.y0, stat.y1, nthreads, [&](int y) {
      for (int x = stat.x0; x < stat.x1; ++x) {
        double s[4] = {0, 0, 0, 0};
        for (int yy = std::max(0, y - pf_r); yy <= std::min(h - 1, y + pf_r); ++yy) {
          const double gw = g[std::size_t(std::abs(yy - y))];
          const double* q = &hs[(std::size_t(yy - hy0) * sw + (x - stat.x0)) * 4];
          for (int c = 0; c < 4; ++c) s[c] += gw * q[c];
        }
        float* e = est.pixel(x, y);
        for (int c = 0; c < 3; ++c) e[c] = s[3] > 0 ? float(std::clamp(s[c] / s[3], -kFloatMax, kFloatMax)) : 0.0f;
      }
    });
  }
  stats_.os_ms = ms_since(t_os);

  // Radius per pixel (SS in the paper's breakdown; it needs the range value). 3.2: linear in the
  // relative variance rho = v / (Y^2 + 0.01), reaching max_radius at variance_max times the
  // frame's median rho, so that one default serves quiet and very noisy renders alike.
  const auto t_ss2 = Clock::now();
  std::vector<int> radius(std::size_t(w) * h, max_r);
  if (adaptive) {
    std::vector<double> rho(std::size_t(w) * h, 0.0);
    parallel_rows(0, h, nthreads, [&](int y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t i = std::size_t(y) * w + x;
        rho[i] = pwaf::relative_variance(variance[i], luminance(est.pixel(x, y)));
      }
    });
    if (measuring_run()) {  // a tiled run's statistics pass: this band's rows, nothing filtered
      for (int y = roi.y0; y < roi.y1; ++y)
        for (int x = roi.x0; x < roi.x1; ++x) {
          const std::size_t i = std::size_t(y) * w + x;
          if (valid[i] && std::isfinite(rho[i])) measured_rho_.push_back(float(rho[i]));
        }
      return;
    }
    double median = fixed_rho_median_;
    if (!statistics_fixed()) {
      std::vector<float> sorted;
      sorted.reserve(rho.size());
      for (std::size_t i = 0; i < rho.size(); ++i)
        if (valid[i] && std::isfinite(rho[i])) sorted.push_back(float(rho[i]));
      median = upper_median(sorted);
    }
    stats_.median_rel_variance = median;
    const double rho_max = variance_max * median;
    for (int y = roi.y0; y < roi.y1; ++y)
      for (int x = roi.x0; x < roi.x1; ++x) {
        const std::size_t i = std::size_t(y) * w + x;
        radius[i] = pwaf::window_radius(rho[i], rho_max, min_r, max_r);
      }
  }
  double radius_sum = 0;
  for (int y = roi.y0; y < roi.y1; ++y)
    for (int x = roi.x0; x < roi.x1; ++x) radius_sum += radius[std::size_t(y) * w + x];
  stats_.mean_radius = radius_sum / double(std::size_t(roi.width()) * roi.height());
  stats_.ss_ms += ms_since(t_ss2);

  // ---- FF: the feature-preserving filter, eq. 1 with the weight of eq. 8 ----
  const auto t_ff = Clock::now();
  const Pass* normal = frame.find(Role::Normal);
  const Pass* pos2 = frame.find(Role::SecondPosition);
  const Pass* nrm2 = frame.find(Role::SecondNormal);
  const Pass* pos1 = frame.find(Role::Position, Prefer::Geometry);
  if (!normal) note("pwaf: no normal pass; Gn dropped");
  if (!pos2 && pos1) note("pwaf: no second_position pass; Gsp uses the first-hit position pass instead");
  if (!pos2 && !pos1) note("pwaf: no second_position or position pass; Gsp dropped");
  if (!nrm2) note("pwaf: no second_normal pass; Gsn dropped (the first-hit normal is already in Gn)");
  const Roi fr = roi.grown(max_r, w, h);  // what the feature weights read
  // A pass constant over fr within constant_tolerance(its sigma) gives every pair a
  // factor within 1e-4 of 1 (kernels/feature_activity.h); one with no finite value
  // gives every pair factor 1: either is dropped. An exactly constant position is
  // dropped before its spacing scale is measured (a frame-wide sort).
  auto active = [&](const Pass* pass, double sigma, bool scale_by_spacing, const char* what, const char* weight) {
    if (!pass) return Feature{};
    FeatureActivity a = feature_activity(pass->image, 3, fr, 0.0, nthreads);
    Feature f;
    if (a.kind == Activity::Varies) {
      f = make_feature(pass, sigma, scale_by_spacing, statistics_fixed() ? fixed_spacing_ : -1.0);
      a = feature_activity(pass->image, 3, fr, constant_tolerance(std::sqrt(0.5 / f.inv2s2)), nthreads);
      if (a.kind == Activity::Varies) return f;
    }
    note("pwaf: " + activity_note(what, a, fr, w, h, std::string(weight) + " not used"));
    return Feature{};
  };
  const Feature fn = active(normal, params_.get_float("sigma_n"), false, "normal", "Gn");
  const Feature fsp =
      active(pos2 ? pos2 : pos1, params_.get_float("sigma_sp"), true, pos2 ? "second_position" : "position", "Gsp");
  const Feature fsn = active(nrm2, params_.get_float("sigma_sn"), false, "second_normal", "Gsn");
  const Feature* used[3];
  double inv[3] = {0, 0, 0};
  int nf = 0;
  for (const Feature* f : {&fn, &fsp, &fsn})
    if (f->image) {
      inv[nf] = f->inv2s2;
      used[nf++] = f;
    }
  // Everything the kernel reads, as planes over the roi grown by max_radius
  // (kernels/pwaf_window.h): the colour, scaled by a power of two into a range where no
  // float sum overflows or turns denormal (exact, undone on output); the range value,
  // the colour coefficient and the radius of every centre; each used feature (NaN where it is
  // not finite). The result is written over the range value's planes.
  ColourPlanes cp;
  planar_colour(in, fr, 0.0, nthreads, cp);
  const PlaneBox& pb = cp.pb;
  const float scale = cp.scale;
  PwafWindowPass wp;
  wp.pb = pb;
  std::vector<float> valid_plane = pb.plane(), ref[3] = {pb.plane(), pb.plane(), pb.plane()}, a_plane = pb.plane(),
                     r_plane = pb.plane();
  std::vector<float> feat[3][3];
  for (int k = 0; k < nf; ++k)
    for (auto& f : feat[k]) f = pb.plane(std::numeric_limits<float>::quiet_NaN());
  parallel_rows(fr.y0, fr.y1, nthreads, [&](int y) {
    for (int x = fr.x0; x < fr.x1; ++x) {
      const std::size_t j = pb.index(x, y);
      const bool ok = valid[std::size_t(y) * w + x];
      valid_plane[j] = ok ? 1.0f : 0.0f;
      if (!ok)
        for (auto& c : cp.c) c[j] = 0.0f;
      for (int k = 0; k < nf; ++k) {
        float v[3];
        if (feature_at(*used[k]->image, x, y, v))
          for (int c = 0; c < 3; ++c) feat[k][c][j] = v[c];
      }
    }
  });
  // Gc against the estimated range value, sigma_c(p)^2 = sigma_c^2 v(p) + (1e-3 Y(p))^2 +
  // 1e-300: the pixel's noise level sets the colour scale (3.3); the floors keep a
  // noise-free pixel from dividing by zero. Mean over the 3 channels, then 1/(2 sigma^2):
  // a = sqrt(1 / (6 sigma_c(p)^2)), in the scaled colour's units.
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t i = std::size_t(y) * w + x, j = pb.index(x, y);
      const float* ip = est.pixel(x, y);
      for (int c = 0; c < 3; ++c) ref[c][j] = ip[c] * scale;
      const double yl = luminance(ip);
      const double sc2 = sigma_c * sigma_c * std::min(variance[i], 1e300) + 1e-6 * yl * yl + 1e-300;
      a_plane[j] = float(std::min(std::sqrt(1.0 / (6.0 * sc2)) / double(scale), double(FLT_MAX)));
      r_plane[j] = float(radius[i]);
    }
  });
  for (int c = 0; c < 3; ++c) {
    wp.colour[c] = cp.c[c].data();
    wp.ref[c] = ref[c].data();
    wp.out[c] = ref[c].data();
  }
  wp.valid = valid_plane.data();
  wp.a = a_plane.data();
  wp.radius = r_plane.data();
  wp.features = nf;
  for (int k = 0; k < nf; ++k) {
    for (int c = 0; c < 3; ++c) wp.feature[k][c] = feat[k][c].data();
    wp.k[k] = float(std::min(inv[k], double(FLT_MAX)));
  }
  wp.max_radius = max_r;
  wp.spatial.resize(std::size_t(max_r + 1) * (max_r + 1));
  for (int dy = 0; dy <= max_r; ++dy)
    for (int dx = 0; dx <= max_r; ++dx)
      wp.spatial[std::size_t(dy) * (max_r + 1) + dx] = float(0.5 * (dx * dx + dy * dy) / (sigma_p * sigma_p));
  pwaf_window_filter(wp, roi, nthreads);
  const float* res[3] = {ref[0].data(), ref[1].data(), ref[2].data()};
  store_colour(res, pb, scale, roi, out, nthreads);
  stats_.ff_ms = ms_since(t_ff);
}

}  // namespace mcr
