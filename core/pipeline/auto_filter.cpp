#include "pipeline/auto_filter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>

#include "filters/registry.h"
#include "kernels/noise_scale.h"
#include "prepare/outliers.h"

namespace mcr {

namespace {

constexpr int kTile = 64;          // scored tile side
constexpr int kMargin = 16;        // what a candidate sees around a tile (its result there is not scored)
constexpr int kMinTiles = 4;
// A pixel beyond its neighbours' range by this many robust deviations is scored by its
// distance to the local median: SURE's expectation cannot see that this sample is far out.
constexpr double kScoreSigmas = 2.0;
constexpr double kDivergenceSlack = 1.0;  // per-pixel divergence kept in [-slack, 1 + slack]
constexpr double kProbe = 0.01;    // Monte Carlo probe: eps = kProbe x the robust noise deviation
// Without a variance pass, pixel (x, y) is held out where (x + 2y + phase) % kMaskPeriod == 0,
// one in five, none of whose four axis neighbours is held out (two patterns ranked no better).
constexpr int kMaskPeriod = 5;
// Held out, an ordinary pixel's noise variance is at most this many times its 3x3 neighbourhood's
// squared range (hold_out()): a deviation 4x the range of nine samples is not noise.
constexpr double kRangeCap = 16.0;
// Far-out pixels rarer than this share of the held-out ones leave "converged" to the rest.
constexpr double kRareFarOut = 0.001;

// The frame's passes inside r (a new, smaller frame).
Frame crop(const Frame& f, const Roi& r) {
  Frame c = f.header(r.width(), r.height());
  for (const Pass& p : f.passes) {
    const int ch = p.image.channels();
    Image img(c.width, c.height, ch);
    for (int y = 0; y < c.height; ++y) {
      const float* s = p.image.pixel(r.x0, r.y0 + y);
      std::copy(s, s + std::size_t(c.width) * std::size_t(ch), img.pixel(0, y));
    }
    // with_pixels: copying the pass whole first cost a frame of every pass per tile (42 tiles
    // of a 4 MP frame moved 20 GB, 3x the filter's own time).
    c.passes.push_back(with_pixels(p, std::move(img)));
  }
  return c;
}

// Tiles of about kTile px covering about `fraction` of roi, on a regular grid; the whole
// roi as one tile when it is small.
std::vector<Roi> sample_tiles(const Roi& roi, double fraction) {
  const double area = double(roi.width()) * roi.height();
  const double want = std::max(double(kMinTiles), std::round(fraction * area / (kTile * kTile)));
  if (roi.width() < 2 * kTile || roi.height() < 2 * kTile || want * kTile * kTile >= 0.5 * area) return {roi};
  const int nx = std::max(1, int(std::round(std::sqrt(want * roi.width() / roi.height()))));
  const int ny = std::max(1, int(std::round(want / nx)));
  std::vector<Roi> tiles;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int cx = roi.x0 + int((i + 0.5) * roi.width() / nx), cy = roi.y0 + int((j + 0.5) * roi.height() / ny);
      const int x0 = std::min(std::max(cx - kTile / 2, roi.x0), roi.x1 - kTile);
      const int y0 = std::min(std::max(cy - kTile / 2, roi.y0), roi.y1 - kTile);
      tiles.push_back({x0, y0, x0 + kTile, y0 + kTile});
    }
  return tiles;
}

// A held-out pixel (crop coordinates) with its relMSE weights and the input's estimated error.
struct HeldPixel {
  int x, y;
  double w[3], e[3];
  bool far;  // far_out(): its e is its distance to the local median
};

// One tile: the cropped frame, the noise, and the copy the candidates also run on: with a
// variance pass the probed frame (SURE), else the frame with the held-out pixels replaced.
struct Sample {
  Frame frame;
  Frame probed;                      // SURE
  Frame masked;                      // held out (no passes when SURE)
  Roi inner;  // the tile, in the crop's coordinates
  NoiseScales noise;
  std::vector<float> sign_over_eps;  // SURE: b_c / eps_c per pixel of the tile and channel
  std::vector<float> weight;         // relMSE weight 1 / (local mean_c^2 + 0.01) per pixel and channel
  std::vector<HeldPixel> held;       // held out: the pixels replaced in `masked`
  bool held_out() const { return !masked.passes.empty(); }
};

// relMSE weighs by the reference; the 7x7 mean of the input (fireflies read as their
// median) stands in for it, smooth enough that noise spread by the variance estimate
// and the error a filter spreads are weighed alike.
std::vector<float> local_weights(const Image& y, const NoiseScales& ns, const Roi& inner) {
  std::vector<float> w(std::size_t(inner.width()) * inner.height() * 3, 0.0f);
  std::size_t k = 0;
  for (int yy = inner.y0; yy < inner.y1; ++yy)
    for (int x = inner.x0; x < inner.x1; ++x) {
      double sum[3] = {0, 0, 0};
      int n = 0;
      for (int qy = std::max(inner.y0, yy - 3); qy <= std::min(inner.y1 - 1, yy + 3); ++qy)
        for (int qx = std::max(inner.x0, x - 3); qx <= std::min(inner.x1 - 1, x + 3); ++qx) {
          const std::size_t j = ns.at(qx, qy);
          if (!ns.finite[j]) continue;
          const float* q = ns.outlier[j] ? &ns.median[j * 3] : y.pixel(qx, qy);
          for (int c = 0; c < 3; ++c) sum[c] += q[c];
          ++n;
        }
      for (int c = 0; c < 3; ++c, ++k) {
        const double m = n ? sum[c] / n : 0.0;
        w[k] = float(1.0 / (m * m + kRelMseEps));
      }
    }
  return w;
}

// The mean of the four axis neighbours of (x, y), each read as its 3x3 median where it is an
// outlier (a firefly beside a held-out pixel would otherwise make it a second one, and the
// pair would pass every filter's outlier rule), into m (RGB); false when one is not finite.
// The neighbours lie inside the noise's box.
bool neighbour_mean(const Image& y, const NoiseScales& ns, int x, int yy, float* m) {
  double sum[3] = {0, 0, 0};
  for (const auto& [dx, dy] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}}) {
    const std::size_t j = ns.at(x + dx, yy + dy);
    if (!ns.finite[j]) return false;
    const float* q = ns.outlier[j] ? &ns.median[j * 3] : y.pixel(x + dx, yy + dy);
    for (int c = 0; c < 3; ++c) sum[c] += q[c];
  }
  for (int c = 0; c < 3; ++c) m[c] = float(sum[c] / 4.0);
  return true;
}

// Whether pixel i is scored by its distance to the local median: beyond its neighbours'
// range by kScoreSigmas robust deviations, unless a variance pass says its samples agree
// (NoiseScales::detail: aliased detail of a clean render, not a firefly).
bool far_out(const Sample& s, std::size_t i) {
  return s.noise.excess[i] > kScoreSigmas * kScoreSigmas && !s.noise.detail[i];
}

// The input's estimated squared error at pixel i, channel c (y: the pixel): its noise
// variance, or for a far-out pixel its distance to the local median.
double input_error(const Sample& s, std::size_t i, int c, const float* y) {
  if (!far_out(s, i)) return s.noise.variance_of(i, c);
  const double e = double(y[c]) - double(s.noise.median[i * 3 + std::size_t(c)]);
  return e * e;
}

// The range (max - min) of channel c over the finite pixels of the 3x3 neighbourhood of (x, y),
// the pixel included (inside the noise's box).
double neighbourhood_range(const Image& y, const NoiseScales& ns, int x, int yy, int c) {
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (int qy = std::max(ns.box.y0, yy - 1); qy <= std::min(ns.box.y1 - 1, yy + 1); ++qy)
    for (int qx = std::max(ns.box.x0, x - 1); qx <= std::min(ns.box.x1 - 1, x + 1); ++qx) {
      if (!ns.finite[ns.at(qx, qy)]) continue;
      lo = std::min(lo, double(y.at(qx, qy, c)));
      hi = std::max(hi, double(y.at(qx, qy, c)));
    }
  return hi >= lo ? hi - lo : 0.0;
}

// Whether (x, y) and its four axis neighbours may be held out on a render with an alpha pass
// (NaN read as opaque). On a transparent render (Film > Transparent, a shadow catcher) the world
// is an exact 0 with alpha 0, not a sample of anything, and an object's edge against it, or the
// world seen through glass, is coverage: held out there, the neighbours' mean reads the step as
// the input's noise (the product still's 2048-spp reference scored 0.0147 and was filtered:
// bilateral, 0.00078 from itself). Opaque: all five at alpha 1. Where a tile has no such pixel
// (a veil of smoke over the world, alpha below 1 everywhere) it holds out the pixels covered
// alike instead: alpha above 0, all five within kCoverageStep.
constexpr float kCoverageStep = 1.0f / 64.0f;

enum class Coverage { Opaque, Even };

bool covered(const Image& alpha, int x, int y, Coverage rule) {
  float lo = HUGE_VALF, hi = -HUGE_VALF;
  for (const auto& [dx, dy] : {std::pair{0, 0}, std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}}) {
    float a = alpha.at(x + dx, y + dy, 0);
    if (std::isnan(a)) a = 1.0f;
    if (rule == Coverage::Opaque ? !(a >= 1.0f) : !(a > 0.0f)) return false;
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  return hi - lo <= kCoverageStep;
}

// s.masked: s.frame with the pixels of the blind-spot pattern inside the tile (its outer ring
// left out: their neighbours must be scored pixels) replaced in the colour by their neighbours'
// mean: a filter's result there then does not depend on the pixel's own noise. The feature
// passes stay (they carry the edges the filters follow, and little of the noise). s.held: those
// pixels, each with its weights and the input's estimated error: held out, an ordinary pixel's
// noise variance is taken at most as kRangeCap times its 3x3 neighbourhood's squared range. The
// window estimate (noise_scale.h) spreads a bright highlight's edges over 9x9 pixels: on the
// glossy reference ten pixels beside a sun's reflection (93 against 0.06 around them) made 96%
// of the input's estimate, relMSE 0.35 for a 2048-spp render, and gaussian was run on it. Noise
// of deviation s spreads nine pixels over about 3 s, so the cap leaves noise its variance; a
// tight one (1x) cut it where the noise is heavy-tailed too (the flattened dof scene: 0.82x its
// true error against 0.89x at 16x), which sides with the input twice over (its own estimate,
// and the check's (f_J - y)^2 - e).
void hold_out(Sample& s, int phase) {
  s.masked = s.frame;
  Pass& colour = const_cast<Pass&>(s.masked.get(Role::Colour));  // the pass the filters read as colour
  const Image& y = s.frame.image(Role::Colour);
  const Pass* alpha = s.frame.find(Role::Alpha);
  float mean[3];
  auto hold = [&](Coverage rule) {
    for (int yy = s.inner.y0 + 1; yy + 1 < s.inner.y1; ++yy)
      for (int x = s.inner.x0 + 1; x + 1 < s.inner.x1; ++x) {
        const std::size_t i = s.noise.at(x, yy);
        if ((x + 2 * yy + phase) % kMaskPeriod != 0 || !s.noise.finite[i] || !neighbour_mean(y, s.noise, x, yy, mean)) continue;
        if (alpha && !covered(alpha->image, x, yy, rule)) continue;
        std::copy(mean, mean + 3, colour.image.pixel(x, yy));
        const std::size_t k = std::size_t(yy - s.inner.y0) * std::size_t(s.inner.width()) + std::size_t(x - s.inner.x0);
        HeldPixel h{x, yy, {}, {}, far_out(s, i)};
        for (int c = 0; c < 3; ++c) {
          h.w[c] = s.weight[k * 3 + std::size_t(c)];
          h.e[c] = input_error(s, i, c, y.pixel(x, yy));
          if (!h.far) {
            const double r = neighbourhood_range(y, s.noise, x, yy, c);
            h.e[c] = std::min(h.e[c], kRangeCap * r * r);
          }
        }
        s.held.push_back(h);
      }
  };
  hold(Coverage::Opaque);
  if (alpha && s.held.empty()) hold(Coverage::Even);  // nothing held out, nothing replaced yet
}

Sample make_sample(const Frame& frame, const Roi& tile, unsigned seed, int nthreads) {
  Sample s;
  const Roi outer = tile.grown(kMargin, frame.width, frame.height);
  s.frame = crop(frame, outer);
  s.inner = {tile.x0 - outer.x0, tile.y0 - outer.y0, tile.x1 - outer.x0, tile.y1 - outer.y0};
  const Image& y = s.frame.image(Role::Colour);
  const Pass* variance = s.frame.find(Role::Variance);
  s.noise = estimate_noise_scales(y, s.inner, nthreads, variance ? &variance->image : nullptr);
  s.weight = local_weights(y, s.noise, s.inner);
  // Held out without a variance pass, unless the tile is too small to hold out a pixel with
  // its four neighbours inside (a region under 8x8: then SURE on the image's noise).
  if (!variance && s.inner.width() >= 8 && s.inner.height() >= 8) {
    hold_out(s, int(seed % unsigned(kMaskPeriod)));
    return s;
  }
  s.probed = s.frame;
  // The pass the filters read as colour (find() picks among several by priority).
  Pass* colour = const_cast<Pass*>(&s.probed.get(Role::Colour));
  std::uint64_t st = 0x9E3779B97F4A7C15ull ^ (std::uint64_t(seed) * 0xBF58476D1CE4E5B9ull);
  s.sign_over_eps.assign(std::size_t(s.inner.width()) * s.inner.height() * 3, 0.0f);
  std::size_t k = 0;
  for (int yy = s.inner.y0; yy < s.inner.y1; ++yy)
    for (int x = s.inner.x0; x < s.inner.x1; ++x) {
      const std::size_t i = s.noise.at(x, yy);
      for (int c = 0; c < 3; ++c, ++k) {
        st ^= st << 13;
        st ^= st >> 7;
        st ^= st << 17;
        if (!s.noise.finite[i]) continue;
        const double eps = std::max(kProbe * std::sqrt(s.noise.robust(i, c)), 1e-6);
        const double b = (st >> 63) ? 1.0 : -1.0;
        const double probed = double(colour->image.at(x, yy, c)) + b * eps;
        colour->image.at(x, yy, c) = float(std::min(std::max(probed, -3.4e38), 3.4e38));
        s.sign_over_eps[k] = float(b / eps);
      }
    }
  return s;
}


// Sums of the risk estimate of one candidate on one sample, relMSE-weighted.
double risk(const Sample& s, const Image& f, const Image& fp) {
  const Image& y = s.frame.image(Role::Colour);
  double sum = 0;
  std::size_t k = 0;
  for (int yy = s.inner.y0; yy < s.inner.y1; ++yy)
    for (int x = s.inner.x0; x < s.inner.x1; ++x) {
      const std::size_t i = s.noise.at(x, yy);
      for (int c = 0; c < 3; ++c, ++k) {
        if (!s.noise.finite[i]) continue;
        const double w = s.weight[k];
        if (far_out(s, i)) {
          // A firefly: SURE's expectation (the local variance) would not see that this one
          // is far out; score how far the result stays from the local median instead.
          const double e = double(f.at(x, yy, c)) - double(s.noise.median[i * 3 + std::size_t(c)]);
          sum += w * e * e;
          continue;
        }
        const double v = s.noise.variance_of(i, c);
        const double d = double(f.at(x, yy, c)) - double(y.at(x, yy, c));
        // The divergence of a filter that averages is its centre weight, in [0, 1]; the probe's
        // estimate adds the zero-mean cross terms of the neighbours' weights. Far outside that, the
        // response was not a derivative but a jump (pwaf's radius follows its variance estimate,
        // which the probe moves): such a pixel says nothing of the slope, so it is cut to the range.
        const double div = std::clamp(
            double(s.sign_over_eps[k]) * (double(fp.at(x, yy, c)) - double(f.at(x, yy, c))), -kDivergenceSlack,
            1.0 + kDivergenceSlack);
        sum += w * (d * d - v + 2.0 * v * div);
      }
    }
  return sum;
}


double input_risk(const Sample& s, std::size_t& count) {
  double sum = 0;
  std::size_t k = 0;
  for (int yy = s.inner.y0; yy < s.inner.y1; ++yy)
    for (int x = s.inner.x0; x < s.inner.x1; ++x, k += 3) {
      const std::size_t i = s.noise.at(x, yy);
      if (!s.noise.finite[i]) continue;
      const float* y = s.frame.image(Role::Colour).pixel(x, yy);
      for (int c = 0; c < 3; ++c) sum += input_error(s, i, c, y) * s.weight[k + std::size_t(c)];
      count += 3;
    }
  return sum;
}

// Held out (no variance pass), one candidate's relMSE-weighted sums over a sample's held-out
// pixels and channels (f: its result on the frame, f_J: on the masked frame, which does not
// depend on the pixel's own noise n; y_J the held-out value, e the input's estimated error):
//   score  (f - y)^2 - e + 2 (f - f_J)(y - y_J): E (f - x)^2 = E (f - y)^2 - E n^2 + 2 E n f, and
//          E n f = E n (f - f_J), read from the pixel's own excursion y - y_J (= n, plus y_J's
//          error, small beside it) instead of SURE's derivative: no Gaussian law, so a filter
//          that follows Monte Carlo's bright excursions pays for it. Detail in y - y_J counts
//          as noise: it errs against a filter that keeps a pixel's detail. Ranks the candidates.
//   check  (f_J - y)^2 - e: E (f_J - y)^2 = E (f_J - x)^2 + E n^2 (Batson & Royer 2019), the
//          filter's error as made from a pixel's neighbours alone: errs toward keeping detail.
//          The best must beat the input by min_gain by it too.
struct HeldOut {
  double score = 0, check = 0;
};

// The input's score held out: its estimated error over the held-out pixels, and over the
// ordinary ones alone (ordinary, ordinary_count: the far-out pixels left out).
double held_input(const Sample& s, std::size_t& count, double& ordinary, std::size_t& ordinary_count) {
  double sum = 0;
  for (const HeldPixel& h : s.held)
    for (int c = 0; c < 3; ++c) {
      sum += h.w[c] * h.e[c];
      if (h.far) continue;
      ordinary += h.w[c] * h.e[c];
      ++ordinary_count;
    }
  count += 3 * s.held.size();
  return sum;
}

void held_out_sums(const Sample& s, const Image& f, const Image& fj, HeldOut& sums) {
  const Image& y = s.frame.image(Role::Colour);
  const Image& yj = s.masked.image(Role::Colour);
  for (const HeldPixel& h : s.held)
    for (int c = 0; c < 3; ++c) {
      const double p = y.at(h.x, h.y, c), d = double(f.at(h.x, h.y, c)) - p, dj = double(fj.at(h.x, h.y, c)) - p;
      const double response = double(f.at(h.x, h.y, c)) - double(fj.at(h.x, h.y, c));
      sums.score += h.w[c] * (d * d - h.e[c] + 2.0 * response * (p - double(yj.at(h.x, h.y, c))));
      sums.check += h.w[c] * (dj * dj - h.e[c]);
    }
}

// a := (a + b) / 2 inside r (a and b the same size): the mean of two candidates' results, scored
// (on a tile) and run (inside the region; outside it both hold the input) as a candidate of its
// own. Two filters err differently (a regression keeps edges a bilateral blurs, and the other way
// at a highlight), so their mean's error is often below either's: over the 13 stills at 4, 16
// and 64 spp the best mean of two had 0.61-1.15x the best single filter's relMSE (median 0.91).
// Every score is linear in the result (SURE's probe, the held-out response and check alike), so
// the mean is scored from the two runs already made, with no run of its own.
void average_into(Image& a, const Image& b, const Roi& r) {
  const std::size_t row = std::size_t(r.width()) * std::size_t(a.channels());
  for (int y = r.y0; y < r.y1; ++y) {
    float* o = a.pixel(r.x0, y);
    const float* q = b.pixel(r.x0, y);
    for (std::size_t i = 0; i < row; ++i) o[i] = 0.5f * o[i] + 0.5f * q[i];
  }
}

}  // namespace

const FilterInfo& AutoFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "auto";
    i.summary = "Chooses the filter for this render: every image filter the passes allow and the mean of every two, "
                "scored on a sample (SURE with "
                "a variance pass, else held-out pixels), the best run, or the input kept when none is estimated to help";
    i.reference = "Stein's unbiased risk estimate (Stein 1981) with a Monte Carlo divergence (Ramani et al. 2008), "
                  "held-out pixels after Batson & Royer 2019, over the project's filters with their defaults";
    i.params = {
        ParamSpec::Float("sample_fraction", 0.04, 0.001, 1.0,
                         "share of the region's pixels the candidates are scored on (64x64 tiles on a grid, at least 4; "
                         "a region too small for that is scored whole)"),
        ParamSpec::Float("converged", 1e-4, 0.0, 1.0,
                         "an input whose estimated relMSE is below this is kept as it is (1e-4: a relative noise of 1%, "
                         "below what anyone sees); 0 = always filter"),
        ParamSpec::Float("min_gain", 0.05, 0.0, 1.0,
                         "a candidate must be estimated to cut the input's relMSE by this share, else the input is "
                         "kept as it is"),
        ParamSpec::Float("kept_firefly_k", kKeptFireflyK, 0.0, 1000.0,
                         "where no filter is estimated to help (but the input is not converged), the input is kept "
                         "with its fireflies clamped: a pixel whose luminance exceeds mu + k sd of its 7x7 window's "
                         "other pixels is scaled down to that limit (the firefly step's rule, at a k far above its 8: "
                         "only a lone sample thousands of times its neighbours, which the scored tiles may not hold); "
                         "0 = kept as it is"),
        ParamSpec::Bool("pairs", true,
                        "also score the mean of every two candidates' results (from the runs already made) and run "
                        "the two when their mean scores best"),
        exposure_param(),
        components_param(),
        alpha_param(),
    };
    i.required = {Role::Colour};
    i.optional = {Role::Normal,   Role::Position,       Role::Albedo,       Role::Depth,       Role::Variance,
                  Role::SampleCount, Role::SecondPosition, Role::SecondNormal};
    i.steps = PrepSteps::none();
    i.steps.exposure = true;  // the candidates run at 1 on the frame it scaled
    i.nonfinite_policy = "as the filter it runs; a copied input has its non-finite values replaced by 0; non-finite "
                         "pixels take no part in the scores";
    return i;
  }();
  return info;
}

// A kept input still loses its lone fireflies: the scored tiles cover a few % of the frame, and
// a sample thousands of times its neighbours outside them is the whole render's error (a second
// draw of the jewel still at 64 spp: one pixel of 993 among 0.3, relMSE 12.1 kept, every filter
// 0.0025). Not on the converged path: a converged render's rare glints are kept.
void AutoFilter::clamp_kept_fireflies(const Frame& frame, const Roi& roi, int nthreads, Image& out) {
  const double k = params_.get_float("kept_firefly_k");
  if (k <= 0) return;
  // A pixel its own samples agree on is detail, not a firefly (noise_scale.h).
  const Pass* v = frame.find(Role::Variance);
  const std::vector<std::uint8_t> detail = detail_mask(out, v ? &v->image : nullptr, roi, nthreads);
  const Image before = out;
  clamp_fireflies(out, kKeptFireflyRadius, k, roi, nthreads, detail.empty() ? nullptr : &detail);
  // A clamp by less than relMSE's own floor, sqrt(0.01) in the render's units, is undone: a 2048-spp
  // reference's near-black speckle (the night street's, 0.002 among 0) is no one's error.
  const double floor = kKeptFireflyFloor * metric_scale();
  std::size_t n = 0;
  const Roi r = roi.clipped(out.width(), out.height());
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) {
      const float* b = before.pixel(x, y);
      float* o = out.pixel(x, y);
      double cut = 0;
      for (int c = 0; c < 3; ++c) cut = std::max(cut, double(b[c]) - double(o[c]));
      if (cut > floor) ++n;
      else if (cut > 0) std::copy(b, b + 3, o);
    }
  if (n) note("auto: the kept input's fireflies clamped: " + std::to_string(n) + " pixels (kept_firefly_k " + rounded_text(k, 3) + ")");
}

void AutoFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  (void)colour;
  scores_.clear();
  chosen_.clear();
  check_ = {};
  // Scores, converged and min_gain on the frame as the exposure step scaled it: `converged` is a
  // relative noise (1%), which a dim render's own relMSE would meet at any noise (at 1/100 of the
  // stills' exposure auto kept every 4- and 16-spp input so: showroom 4 spp 0.113 against the
  // filtered 0.0104). The candidates' step backs still weigh as relMSE on the render itself.
  // 1. Candidates: every image filter whose passes this frame has.
  std::vector<std::unique_ptr<Filter>> cands;
  std::string skipped;
  for (const std::string& name : filter_names()) {
    std::unique_ptr<Filter> f = make_filter(name);
    if (f->info().temporal) continue;  // a still has no history; temporal filters run by name
    if (f->info().deep_input) continue;  // per-sample filters run by name, on deep input
    const std::vector<Role> missing = f->missing_passes(frame);
    if (!missing.empty()) {
      skipped += (skipped.empty() ? "" : ", ") + name + " (no " + role_name(missing[0]) + " pass)";
      continue;
    }
    f->commit();
    // The frame is at the scale auto's exposure step chose (a tile's level is not the frame's);
    // its step back still weighs errors as on the render itself.
    f->pin_exposure(1.0, metric_scale());
    cands.push_back(std::move(f));
  }
  if (!skipped.empty()) note("auto: candidates skipped: " + skipped);

  // 2. Scores on the sample.
  const std::vector<Roi> tiles = sample_tiles(roi, params_.get_float("sample_fraction"));
  std::vector<Sample> samples;
  double in_sum = 0, in_ordinary = 0;
  std::size_t count = 0, ordinary_count = 0;
  for (std::size_t t = 0; t < tiles.size(); ++t) {
    samples.push_back(make_sample(frame, tiles[t], unsigned(t + 1), nthreads));
    const Sample& s = samples.back();
    in_sum += s.held_out() ? held_input(s, count, in_ordinary, ordinary_count) : input_risk(s, count);
  }
  const double n = std::max<double>(double(count), 1.0);
  const bool sure = !samples.front().held_out();  // a variance pass, or a region under 8x8 (every tile alike)
  // A candidate: one filter (second < 0) or the mean of two (first < second), named as scored.
  struct Choice {
    int first, second;
    std::string name;
  };
  std::vector<Choice> choices;
  std::vector<double> estimate, check;  // per choice, relMSE per channel
  std::vector<double> seconds(cands.size());
  // Each candidate's two results on each sample (the frame's, then the probed or masked one's).
  std::vector<std::vector<std::pair<Image, Image>>> results(cands.size());
  auto score = [&](const std::vector<std::pair<Image, Image>>& res, Choice choice, double secs) {
    double r = 0;
    HeldOut h;
    for (std::size_t k = 0; k < samples.size(); ++k) {
      if (sure)
        r += risk(samples[k], res[k].first, res[k].second);
      else
        held_out_sums(samples[k], res[k].first, res[k].second, h);
    }
    estimate.push_back((sure ? r : h.score) / n);
    check.push_back(h.check / n);
    scores_.push_back({choice.name, estimate.back(), secs});
    choices.push_back(std::move(choice));
  };
  for (std::size_t c = 0; c < cands.size(); ++c) {
    Filter& f = *cands[c];
    const auto t0 = std::chrono::steady_clock::now();
    for (const Sample& s : samples) {
      ExecOptions eo;
      eo.roi = s.inner;
      eo.nthreads = nthreads;
      Image a = f.execute(s.frame, eo);
      results[c].emplace_back(std::move(a), f.execute(sure ? s.probed : s.masked, eo));
    }
    seconds[c] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    score(results[c], {int(c), -1, f.info().name}, seconds[c]);
  }
  if (params_.get_bool("pairs"))
    for (std::size_t a = 0; a < cands.size(); ++a)
      for (std::size_t b = a + 1; b < cands.size(); ++b) {
        std::vector<std::pair<Image, Image>> mean = results[a];
        for (std::size_t k = 0; k < samples.size(); ++k) {
          average_into(mean[k].first, results[b][k].first, samples[k].inner);
          average_into(mean[k].second, results[b][k].second, samples[k].inner);
        }
        score(mean, {int(a), int(b), cands[a]->info().name + "+" + cands[b]->info().name}, seconds[a] + seconds[b]);
      }
  results.clear();
  scores_.push_back({"input", in_sum / n, 0.0});
  std::stable_sort(scores_.begin(), scores_.end(), [](const AutoScore& a, const AutoScore& b) { return a.relmse < b.relmse; });
  std::string table;
  for (const AutoScore& s : scores_) table += (table.empty() ? "" : ", ") + s.filter + " " + rounded_text(s.relmse, 3);
  note("auto: estimated relMSE on " + std::to_string(tiles.size()) + (tiles.size() == 1 ? " sample (the whole region)" : " tiles") +
       (sure ? " (SURE; only the order counts, below 0 where the noise estimate runs high): "
             : " (held-out pixels, each scored by its own excursion; only the order counts): ") +
       table);

  // 3. The best, unless it is not estimated to beat the input by min_gain (held out, by the
  // check: the ranking score errs against filters that keep detail, so a clean render would be
  // kept for the wrong reason; the check errs the same way, but less).
  const double input_score = in_sum / n;
  // Held out, converged is judged on the ordinary pixels where far-out ones are rare (under
  // kRareFarOut of the held-out pixels): one far-out pixel of a 2048-spp render (the showroom
  // reference's 16.8 among 0.56, a caustic's glint or a firefly the reference keeps) made 99.99%
  // of its estimate, and pwaf was run over the whole render for it. Such pixels are kept with
  // the rest (a filter run by name still cuts them); one in a hundred is the render's error.
  const bool ordinary =
      !sure && ordinary_count > 0 && double(count - ordinary_count) < kRareFarOut * double(count);
  const double converged_score = ordinary ? in_ordinary / double(ordinary_count) : input_score;
  if (converged_score < params_.get_float("converged")) {
    chosen_ = "input";
    note("auto: chose the input as it is: converged (estimated relMSE " + rounded_text(converged_score, 3) +
         (ordinary ? " at the held-out pixels that are not far out" : "") + " < converged=" +
         rounded_text(params_.get_float("converged"), 3) + ")");
    return;
  }
  // The first of the lowest, as the stable sort above lists them.
  const std::size_t best = std::size_t(std::min_element(estimate.begin(), estimate.end()) - estimate.begin());
  const std::size_t nchoices = choices.size();
  double best_estimate = best < nchoices ? estimate[best] : 0.0;
  if (best < nchoices && !sure) {
    const std::string& name = choices[best].name;
    best_estimate = check[best];
    check_ = {name, check[best], input_score};
    note("auto: check of " + name + " (its result at the held-out pixels made from their neighbours alone): estimated relMSE " +
         rounded_text(check[best], 3) + " against the input's " + rounded_text(input_score, 3));
  }
  // Held out, the best must also not rank above the input by its own score by more than min_gain:
  // on the held-out night street's 2048-spp reference every candidate scored above the input (pwaf
  // 0.00185 against 0.0016, 16% above), yet the check, which reads the reference's fine detail as
  // noise too, passed pwaf (0.00087), and auto filtered the reference. Within min_gain the two scores
  // are a tie (a second render of the dof still at 64 spp: pwaf 0.0137 against the input's 0.0137,
  // the check 0.0077; its input kept was 4x pwaf's error), and the check decides.
  const double min_gain = params_.get_float("min_gain");
  if (best < nchoices && !sure && !(estimate[best] <= (1.0 + min_gain) * input_score)) {
    chosen_ = "input";
    note("auto: chose the input as it is: no filter ranks within min_gain of it (" + choices[best].name + " " +
         rounded_text(estimate[best], 3) + " against " + rounded_text(input_score, 3) + ")");
    clamp_kept_fireflies(frame, roi, nthreads, out);
    return;
  }
  if (best == nchoices || !(best_estimate < (1.0 - min_gain) * input_score)) {
    chosen_ = "input";
    note("auto: chose the input as it is: no filter is estimated to cut its relMSE (" + rounded_text(input_score, 3) + ") by " +
         rounded_text(100.0 * min_gain, 3) + "%");
    clamp_kept_fireflies(frame, roi, nthreads, out);  // out holds the input colour
    return;
  }
  const Choice& ch = choices[best];
  chosen_ = ch.name;
  ExecOptions eo;
  eo.roi = roi;
  eo.nthreads = nthreads;
  out = cands[std::size_t(ch.first)]->execute(frame, eo);
  if (ch.second >= 0) average_into(out, cands[std::size_t(ch.second)]->execute(frame, eo), roi.clipped(out.width(), out.height()));
  note("auto: chose " + chosen_ + (ch.second < 0 ? " with its defaults" : " (the mean of the two results) with their defaults"));
  for (const int i : {ch.first, ch.second}) {
    if (i < 0) continue;
    const std::string& name = cands[std::size_t(i)]->info().name;
    for (const std::string& m : cands[std::size_t(i)]->notes()) note(m.rfind(name + ":", 0) == 0 ? m : name + ": " + m);
  }
}

}  // namespace mcr
