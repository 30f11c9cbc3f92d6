// The guided filter (guided.h): its parameter table, run() and the frame-wide pass
// before the window work. The guide choices are in guided_guides.*, the running box sums
// and the per-window solve in guided_sums.*.
#include "filters/image/guided.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "filters/image/guided_guides.h"
#include "filters/image/guided_sums.h"
#include "image/luminance.h"
#include "kernels/noise_scale.h"
#include "util/error.h"
#include "util/median.h"
#include "util/parallel.h"

namespace mcr {

using namespace guided;

namespace {

// epsilon=0: epsilon = kEpsilonScale x the median relative noise variance (chosen with
// the radius and the guide on the tune scenes room and glossy, 1 to 64 spp).
constexpr double kEpsilonScale = 30.0;

// guided demodulates by default: its feature guide (normal, depth) carries no texture, so the
// texture must leave the colour before the regression. Without an albedo pass the step is
// skipped with a note (prepare/preparation.h), unless demodulate=true was given.
ParamTable with_demodulate_default(ParamTable t) {
  for (ParamSpec& s : t)
    if (s.name == "demodulate") {  // with_preparation_params() adds it with default false
      s.default_value = true;
      s.help += " (guided: default true; skipped with a note when the render has no albedo pass and demodulate was "
                "not given)";
    }
  return t;
}

}  // namespace

int guided::band_rows(int r) { return std::max(64, (16 * r + 63) / 64 * 64); }

double guided::auto_epsilon(double scale, double median_relative_noise) {
  const double e = scale * median_relative_noise;
  return std::isfinite(e) ? std::clamp(e, 1e-8, 1e6) : 1e6;
}

guided::FrameNoise guided::frame_noise(const Image& colour, int nthreads) {
  std::vector<float> rel, abs;
  gather_frame_noise(colour, Roi::all(colour.width(), colour.height()), nthreads, rel, abs);
  return frame_noise_of(rel, abs);
}

void guided::gather_frame_noise(const Image& colour, const Roi& rows, int nthreads, std::vector<float>& rel,
                                std::vector<float>& abs) {
  const NoiseScales ns = estimate_noise_scales(colour, rows, nthreads);
  rel.reserve(rel.size() + ns.relative.size());
  abs.reserve(abs.size() + ns.relative.size());
  // Over the pixels whose tile measured any noise: at 1 spp a render lit by rare paths is
  // mostly black, and a black tile's noise is not 0 but unmeasured (its median is 0).
  for (std::size_t i = 0; i < ns.relative.size(); ++i) {
    if (!ns.finite[i] || !(ns.relative[i] > 0)) continue;
    if (std::isfinite(ns.relative[i])) rel.push_back(ns.relative[i]);
    if (std::isfinite(ns.robust(i))) abs.push_back(float(std::min(ns.robust(i), double(FLT_MAX))));
  }
}

guided::FrameNoise guided::frame_noise_of(std::vector<float>& rel, std::vector<float>& abs) {
  FrameNoise fn;
  fn.relative = upper_median(rel);
  const double a = upper_median(abs);
  fn.level = fn.relative > 0.0 && std::isfinite(a / fn.relative) ? std::sqrt(a / fn.relative) : 0.0;
  return fn;
}

namespace {

// The frame-wide pass (validity flags, guide normalisation, outlier threshold),
// then the bands. Every reduction is per row, then combined in row order: the
// same numbers on any thread count.
template <int D>
void filter_d(Ctx& c, const std::vector<std::pair<int, int>>& groups, const std::vector<bool>& unit,
              const std::vector<double>& min_scale, const Roi& roi,
              Image& out, int nthreads, GuidedStats& st, std::vector<std::vector<double>>& work,
              std::vector<RowStats>* measure_rows, const std::vector<RowStats>* fixed_rows) {
  const int W = c.w, H = c.h;
  const std::size_t N = std::size_t(W) * std::size_t(H);
  std::vector<std::uint8_t> flags(N);
  static_assert(D <= kMaxGuideChannels, "guide channels");
  std::vector<RowStats> rows(static_cast<std::size_t>(H));
  parallel_rows(0, H, nthreads, [&](int y) {
    const GuideView<D> gv(c);
    const float* colour = c.colour;
    std::uint8_t* fl = flags.data();
    const std::size_t i0 = std::size_t(y) * std::size_t(W);
    std::uint32_t hist[4][256] = {};  // four, so that equal bins do not chain
    double sum[D] = {};
    std::uint64_t n = 0, bad = 0;
    for (int x = 0; x < W; ++x) {
      const std::size_t i = i0 + std::size_t(x);
      const float* p = colour + i * 3;
      std::uint8_t f = finite3(p) ? kColourOk : 0;
      bool ok = true;
      float v[D];
      for (int j = 0; j < D; ++j) {
        v[j] = gv.raw(i, j);
        ok = ok && std::isfinite(v[j]);
      }
      if (ok) {
        f |= kGuideOk;
        ++n;
        for (int j = 0; j < D; ++j) sum[j] += v[j];
      }
      if (f == kStat) {
        for (int k = 0; k < 3; ++k) {
          std::uint32_t bits;
          std::memcpy(&bits, p + k, sizeof bits);
          hist[(x + k) & 3][(bits >> 23) & 0xffu] += (bits & 0x7fffffffu) != 0;
        }
      } else {
        ++bad;
      }
      fl[i] = f;
    }
    RowStats& rs = rows[std::size_t(y)];
    rs.n = n;
    rs.invalid = bad;
    for (int b = 0; b < 256; ++b) rs.hist[b] = hist[0][b] + hist[1][b] + hist[2][b] + hist[3][b];
    if (!n) return;
    double mean[D], m2[D] = {};
    for (int j = 0; j < D; ++j) mean[j] = sum[j] / double(n);
    for (int x = 0; x < W; ++x) {
      const std::size_t i = i0 + std::size_t(x);
      if (!(fl[i] & kGuideOk)) continue;
      for (int j = 0; j < D; ++j) {
        const double dv = double(gv.raw(i, j)) - mean[j];
        m2[j] += dv * dv;
      }
    }
    std::copy(mean, mean + D, rs.mean);
    std::copy(m2, m2 + D, rs.m2);
  });
  // A tiled run's statistics pass: the band's own rows, in frame order; nothing filtered.
  if (measure_rows) {
    for (int y = roi.y0; y < roi.y1; ++y) measure_rows->push_back(rows[std::size_t(y)]);
    return;
  }
  // Rows combined in order (Chan, Golub & LeVeque): mean and sum of squared deviations.
  double n = 0, mean[D] = {}, m2[D] = {};
  std::array<std::uint64_t, 256> hist{};
  std::size_t invalid = 0;
  for (const RowStats& rs : fixed_rows ? *fixed_rows : rows) {
    invalid += rs.invalid;
    for (int b = 0; b < 256; ++b) hist[std::size_t(b)] += rs.hist[b];
    if (!rs.n) continue;
    const double nb = double(rs.n), nn = n + nb;
    for (int j = 0; j < D; ++j) {
      const double delta = rs.mean[j] - mean[j];
      mean[j] += delta * (nb / nn);
      m2[j] += rs.m2[j] + delta * delta * (n * nb / nn);
    }
    n = nn;
  }

  // Outlier threshold: 2^20 x the upper end of the exponent bin holding the 90th
  // percentile of the nonzero |colour| values; a power of two, so "|p| >= threshold"
  // is "exponent bin >= b90 + 21" and the histogram tells whether any exists.
  c.threshold = std::numeric_limits<double>::infinity();
  bool any_outlier = false;
  {
    std::uint64_t total = 0, acc = 0;
    for (std::uint64_t h : hist) total += h;
    const std::uint64_t want = total - total / 10;
    for (int b = 0; b < 256 && total; ++b) {
      acc += hist[std::size_t(b)];
      if (acc >= want) {
        c.threshold = std::ldexp(1.0, b - 126 + 20);
        for (int e = b + 21; e < 255; ++e) any_outlier = any_outlier || hist[std::size_t(e)] > 0;
        break;
      }
    }
  }
  std::size_t outliers = 0;
  if (any_outlier) {
    // Counted over the image given (a tiled run's band: its own; any_outlier, which is what
    // changes the filtering, is the frame's from the histogram).
    std::vector<std::uint32_t> row_out(std::size_t(H), 0);
    parallel_rows(0, H, nthreads, [&](int y) {
      for (int x = 0; x < W; ++x) {
        const std::size_t i = std::size_t(y) * std::size_t(W) + std::size_t(x);
        const float* p = c.colour + i * 3;
        row_out[std::size_t(y)] +=
            flags[i] == kStat && std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])}) >= c.threshold;
      }
    });
    for (std::uint32_t v : row_out) outliers += v;
  }

  // One scale per pass: s = rms std (s = 1 when that is 0), at least 1 for unit passes,
  // at least min_scale (a colour guide's level under epsilon=0).
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const auto [first, count] = groups[g];
    double v = 0;
    for (int j = first; j < first + count; ++j) v += n > 0 ? m2[j] / n : 0.0;
    const double rms = std::sqrt(v / count);
    double s = rms > 0.0 && std::isfinite(rms) ? rms : 1.0;
    if (unit[g]) s = std::max(1.0, s);
    if (min_scale[g] > 0.0 && std::isfinite(min_scale[g])) s = std::max(s, min_scale[g]);
    for (int j = first; j < first + count; ++j) {
      c.ch[std::size_t(j)].mean = mean[j];
      c.ch[std::size_t(j)].inv_scale = 1.0 / s;
    }
  }
  st.guide_channels = D;
  for (int j = 0; j < D; ++j) {
    st.guide_mean.push_back(c.ch[std::size_t(j)].mean);
    st.guide_scale.push_back(1.0 / c.ch[std::size_t(j)].inv_scale);
  }
  st.outlier_threshold = c.threshold;
  st.outlier_pixels = outliers;
  st.invalid_pixels = invalid;
  c.flags = flags.data();

  // Bands of a height set by the radius and the roi alone (never by the thread
  // count): the same sums in the same order on any number of threads. Each band
  // recomputes r coefficient rows past each of its ends, so bands are 16r rows (at
  // least 64) on the image's grid (guided::band_rows).
  const int band_h = guided::band_rows(c.r);
  st.bands = (roi.y1 - (roi.y0 - roi.y0 % band_h) + band_h - 1) / band_h;
  // The mean colour sums only when some output pixel has no finite guide.
  bool mp = false;
  for (int y = roi.y0; y < roi.y1 && !mp; ++y)
    for (int x = roi.x0; x < roi.x1; ++x) mp = mp || !(flags[std::size_t(y) * std::size_t(W) + std::size_t(x)] & kGuideOk);
  run_bands<D>(c, any_outlier, mp, roi, out, nthreads, band_h, work);
}

}  // namespace

const FilterInfo& GuidedFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "guided";
    i.summary = "Guided image filter: per-window ridge regression of the colour on a feature guide";
    i.reference =
        "He, Sun & Tang 2013 (Algorithm 1, multi-channel guide); Bauszat et al. 2011 (guide = normal + depth); "
        "Immonen 2017 thesis 3.5 and 4.2; Koskela et al. 2019 section 7 (radius 24/12, eps 0.01)";
    i.params = with_common_params({
        ParamSpec::Enum("guide", "normal_depth_colour", guide_names(),
                        "guide channels: normal_depth = 3 normal channels + depth (Bauszat et al.); luminance and "
                        "colour guide by the noisy colour itself (He et al.'s self-guided case); "
                        "normal_depth_colour (default) adds the colour to normal + depth, so shadows, glossy "
                        "reflections and lighting the features do not show are kept where they stand above the "
                        "noise (the default takes the passes the render has: a pass it lacks is left out with a note, the colour "
                        "guide when there is none; a guide set here needs all of its passes); each pass is "
                        "centred on its frame mean, depth/position/luminance/colour divided by their std (a colour "
                        "guide under epsilon=0 by max(std, its level)), normal/albedo by max(1, std)"),
        ParamSpec::Int("radius", 4, 1, 256, "half width of the box window in pixels (window = 2r+1); O(N): run time nearly independent of it"),
        ParamSpec::Float("epsilon", 0.0, 0.0, 1e6,
                         "ridge regulariser added to the guide covariance (guide channels normalised, see guide): "
                         "larger = smoother, towards a box-of-box mean; 0 = from the noise: epsilon_scale x the "
                         "frame's median relative noise variance (kernels/noise_scale.h), at least 1e-8"),
        ParamSpec::Float("epsilon_scale", kEpsilonScale, 1e-6, 1e6,
                         "epsilon=0: the multiple of the median relative noise variance taken as epsilon (a noisy "
                         "render is smoothed hard, a clean one barely)"),
    });
    i.params = with_demodulate_default(std::move(i.params));
    i.required = {Role::Colour};
    i.optional = {Role::Normal, Role::Depth, Role::Position, Role::Albedo};
    i.nonfinite_policy =
        "a pixel whose colour or whose guide has a non-finite channel is left out of every window's statistics "
        "(means over the valid pixels only; the guide normalisation uses the pixels with a finite guide); a window "
        "with no valid pixel is left out of the coefficient average; a pixel with a non-finite guide gets the "
        "average of its windows' mean colours; a pixel with no window holding a valid pixel (none within 2r) keeps "
        "its input colour where finite, else 0. Sums are in double and outputs clamped to +-FLT_MAX, so finite "
        "inputs up to FLT_MAX never overflow. Fireflies: the guided filter spreads a bright pixel over the windows "
        "holding it (up to 2r away, like a box filter); colour values >= 2^20 x the 90th percentile of |colour| "
        "have sums of their own, so pixels farther than 2r never see their rounding error; clamp limits them";
    return i;
  }();
  return info;
}

std::vector<Role> GuidedFilter::guide_passes(const std::string& guide) {
  std::vector<Role> roles;
  for (const GroupSpec& g : find_choice(guide).groups)
    if (reads_pass(g.source)) roles.push_back(source_role(g.source));
  return roles;
}

PassNeeds GuidedFilter::own_needs() const {
  PassNeeds n;
  n.require(Role::Colour);
  const std::string& guide = params_.get_enum("guide");
  // The default guide takes the passes the render has (the others are left out with a note, as a
  // constant pass is); a guide the user chose needs all of its passes.
  const bool chosen = params_.was_set("guide");
  for (Role r : guide_passes(guide)) {
    if (chosen) n.require(r, "guide=" + guide + "; guide=luminance needs no feature pass");
    else n.use(r);
  }
  return n;
}

std::vector<std::string> GuidedFilter::own_unused() const {
  std::vector<std::string> u = Filter::own_unused();
  unused_when(params_.get_float("epsilon") != 0.0, "epsilon_scale", "with epsilon set (only epsilon=0 reads it)", u);
  return u;
}

void GuidedFilter::run(const Frame& frame, const Image& colour_in, const Roi& roi, Image& out, int nthreads) {
  const std::string& guide = params_.get_enum("guide");
  const GuideChoice& choice = find_choice(guide);  // a chosen guide's passes: checked by needs() before any work
  const int W = frame.width, H = frame.height;
  const int r = int(params_.get_int("radius"));
  const Image* colour = &colour_in;
  Image lum;

  // Guide channels, grouped by pass (a group shares one scale).
  Ctx c;
  c.w = W;
  c.h = H;
  c.r = r;
  c.eps = params_.get_float("epsilon");
  double colour_scale = 0;  // epsilon=0: a colour guide is divided by at least its level
  if (c.eps == 0.0) {
    const FrameNoise fn = statistics_fixed() || measuring_run() ? fixed_noise_ : frame_noise(*colour, nthreads);
    c.eps = auto_epsilon(params_.get_float("epsilon_scale"), fn.relative);
    colour_scale = fn.level;
    note("epsilon " + number_text(c.eps) + " from the noise (median relative noise variance " + number_text(fn.relative) +
         ", colour level " + number_text(fn.level) + ")");
  }
  c.colour = colour->data();
  std::vector<std::pair<int, int>> groups;  // first channel, count
  std::vector<bool> unit;
  std::vector<double> min_scale;
  int d = 0;
  for (const GroupSpec& g : active_groups(choice, frame, c.eps, nthreads, [this](std::string s) { note(std::move(s)); })) {
    const Image* img = nullptr;
    if (g.source == Source::Colour) {
      img = colour;
    } else if (g.source == Source::Luminance) {
      lum = Image(W, H, 1);
      parallel_rows(0, H, nthreads, [&](int y) {
        for (int x = 0; x < W; ++x) {
          const float* p = colour->pixel(x, y);
          const double v = luminance(p);
          lum.at(x, y, 0) = finite3(p) ? float(std::clamp(v, -double(FLT_MAX), double(FLT_MAX)))
                                       : std::numeric_limits<float>::quiet_NaN();
        }
      });
      img = &lum;
    } else {
      img = &frame.image(source_role(g.source));
    }
    groups.emplace_back(d, g.channels);
    unit.push_back(g.unit);
    min_scale.push_back(g.source == Source::Colour || g.source == Source::Luminance ? colour_scale : 0.0);
    for (int j = 0; j < g.channels; ++j, ++d) {
      c.ch[std::size_t(d)].data = img->data();
      c.ch[std::size_t(d)].stride = img->channels();
      c.ch[std::size_t(d)].offset = std::min(j, img->channels() - 1);
    }
  }

  stats_ = GuidedStats{};
  std::vector<RowStats>* rows_in = measuring_run() ? &row_stats_ : nullptr;
  const std::vector<RowStats>* rows_fixed = statistics_fixed() ? &row_stats_ : nullptr;
  switch (d) {
    case 1: filter_d<1>(c, groups, unit, min_scale, roi, out, nthreads, stats_, work_, rows_in, rows_fixed); break;
    case 3: filter_d<3>(c, groups, unit, min_scale, roi, out, nthreads, stats_, work_, rows_in, rows_fixed); break;
    case 4: filter_d<4>(c, groups, unit, min_scale, roi, out, nthreads, stats_, work_, rows_in, rows_fixed); break;
    case 6: filter_d<6>(c, groups, unit, min_scale, roi, out, nthreads, stats_, work_, rows_in, rows_fixed); break;
    case 7: filter_d<7>(c, groups, unit, min_scale, roi, out, nthreads, stats_, work_, rows_in, rows_fixed); break;
    default: throw Error(Errc::Internal, "filter 'guided': no kernel for a " + std::to_string(d) + "-channel guide");
  }
}

void GuidedFilter::measure_band(const Frame& band, const Image& colour, const Roi& rows, int nthreads) {
  // First pass: the noise (epsilon=0) and, in the base class, every pass's spread; then the
  // guides that epsilon and those spreads leave active, and their statistics.
  if (statistics_pass() == 0) {
    if (noise_from_image()) gather_frame_noise(colour, rows, nthreads, measured_rel_, measured_abs_);
    return;
  }
  run_to_measure(band, colour, rows, nthreads);
}

bool GuidedFilter::statistics_pass_done() {
  if (statistics_pass() > 0) return false;
  if (noise_from_image()) fixed_noise_ = frame_noise_of(measured_rel_, measured_abs_);
  std::vector<float>().swap(measured_rel_);
  std::vector<float>().swap(measured_abs_);
  return true;
}

void GuidedFilter::drop_own_statistics() {
  std::vector<float>().swap(measured_rel_);
  std::vector<float>().swap(measured_abs_);
  std::vector<RowStats>().swap(row_stats_);
  fixed_noise_ = {};
}

}  // namespace mcr
