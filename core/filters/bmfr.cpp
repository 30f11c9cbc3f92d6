#include "filters/bmfr.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "linalg/householder_qr.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

namespace {

constexpr double kFloatMax = std::numeric_limits<float>::max();

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Counter-based random numbers (splitmix64): the noise of a block depends on
// (seed, frame, block) only, never on the thread that fits it.
std::uint64_t splitmix(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
double uniform_pm1(std::uint64_t& s) { return double(splitmix(s) >> 11) * (2.0 / 9007199254740992.0) - 1.0; }

// Raw (unscaled) feature channels per feature set. The fitted columns are then
// [1, raw scaled to [-1,1] ..., squares of the scaled positions rescaled to [-1,1]].
struct FeatureLayout {
  bool squares = true;        // w^2 columns
  bool albedo = false;        // + albedo RGB
  bool depth = false;         // + depth
  int raw() const { return 6 + (albedo ? 3 : 0) + (depth ? 1 : 0); }
  int columns() const { return 1 + raw() + (squares ? 3 : 0); }
};

FeatureLayout layout_of(const std::string& set) {
  FeatureLayout l;
  if (set == "first_order") l.squares = false;
  if (set == "with_albedo") l.albedo = true;
  if (set == "with_depth") l.depth = true;
  return l;
}

// Catmull-Rom (bicubic) sample of an RGB image at (x, y), pixel centres at integers,
// taps clamped to the border: the sharper history lookup Karis 2014 recommends for TAA
// (bilinear resampling every frame blurs a moving image). False when (x, y) is outside.
bool catmull_rom(const Image& im, float x, float y, float* out) {
  const int w = im.width(), h = im.height();
  if (!(x >= -0.5f && y >= -0.5f && x <= float(w) - 0.5f && y <= float(h) - 0.5f)) return false;
  const float fx0 = std::floor(x), fy0 = std::floor(y);
  const float tx = x - fx0, ty = y - fy0;
  auto weights = [](float t, float* wt) {
    const float t2 = t * t, t3 = t2 * t;
    wt[0] = 0.5f * (-t3 + 2 * t2 - t);
    wt[1] = 0.5f * (3 * t3 - 5 * t2 + 2);
    wt[2] = 0.5f * (-3 * t3 + 4 * t2 + t);
    wt[3] = 0.5f * (t3 - t2);
  };
  float wx[4], wy[4];
  weights(tx, wx);
  weights(ty, wy);
  double acc[3] = {0, 0, 0};
  for (int j = 0; j < 4; ++j) {
    const int yy = std::clamp(int(fy0) - 1 + j, 0, h - 1);
    for (int i = 0; i < 4; ++i) {
      const int xx = std::clamp(int(fx0) - 1 + i, 0, w - 1);
      const float* p = im.pixel(xx, yy);
      const double wgt = double(wx[i]) * wy[j];
      for (int c = 0; c < 3; ++c) acc[c] += wgt * p[c];
    }
  }
  for (int c = 0; c < 3; ++c) out[c] = float(acc[c]);
  return true;
}

}  // namespace

const std::array<std::array<float, 2>, 16>& BmfrFilter::grid_offsets() {
  // A fixed sequence of 16 random displacements, uniform over the block (drawn once).
  static const std::array<std::array<float, 2>, 16> offsets = {{{0.00f, 0.00f}, {0.53f, 0.27f}, {0.19f, 0.81f},
                                                                {0.72f, 0.62f}, {0.38f, 0.09f}, {0.91f, 0.44f},
                                                                {0.06f, 0.56f}, {0.64f, 0.94f}, {0.27f, 0.35f},
                                                                {0.83f, 0.13f}, {0.45f, 0.71f}, {0.13f, 0.19f},
                                                                {0.97f, 0.86f}, {0.58f, 0.50f}, {0.31f, 0.98f},
                                                                {0.77f, 0.31f}}};
  return offsets;
}

const FilterInfo& BmfrFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "bmfr";
    i.summary = "Blockwise multi-order feature regression: temporal accumulation, per-block QR fit, TAA";
    i.reference = "Koskela et al., Blockwise Multi-Order Feature Regression for real-time path tracing reconstruction, ACM TOG 2019";
    i.params = with_common_params({
        ParamSpec::Int("block_size", 32, 8, 128, "side of the square regression blocks in pixels"),
        ParamSpec::Float("epsilon", 0.01, 0.0, 10.0,
                         "stochastic regularisation: uniform noise in [-epsilon, epsilon] added to the fitted features"),
        ParamSpec::Float("alpha1", 0.2, 0.01, 1.0, "phase I: weight floor of the new noisy sample (cumulative average until then)"),
        ParamSpec::Float("alpha2", 0.1, 0.01, 1.0, "phase III: weight floor of the new fitted frame"),
        ParamSpec::Enum("features", "default", {"default", "first_order", "with_albedo", "with_depth"},
                        "feature set: default [1,n,w,w^2] (10), first_order [1,n,w] (7), with_albedo (+albedo, 13), "
                        "with_depth (+depth, 11)"),
        ParamSpec::Bool("offsets", true, "displace the block grid every frame by a fixed 16-entry random sequence"),
        ParamSpec::Bool("taa", true, "temporal anti-aliasing (reprojected history clamped to the 3x3 min/max) at the end"),
        ParamSpec::Float("taa_alpha", 0.2, 0.01, 1.0, "TAA: weight of the current frame"),
        ParamSpec::Enum("taa_history", "bilinear", {"bilinear", "catmull_rom"},
                        "TAA: history lookup (catmull_rom: sharper, Karis 2014; bilinear: lower relMSE on the samples)"),
        ParamSpec::Int("seed", 0, 0, 2147483647, "seed of the regularisation noise"),
        ParamSpec::Bool("albedo_demodulation", true,
                        "fit illumination = colour / max(albedo, albedo_floor) and multiply back before TAA (when an albedo pass "
                        "exists); skipped when the common demodulate=true does it instead (around the whole pipeline)"),
        ParamSpec::Enum("position_test", "relative", {"relative", "absolute"},
                        "history discard by world distance: relative = in pixel footprints, absolute = world units"),
        ParamSpec::Float("position_threshold", 3.0, 0.0, 1e9, "history tap kept when its world distance is at most this"),
        ParamSpec::Float("normal_threshold", 0.9, -1.0, 1.0, "history tap kept when the cosine between normals is at least this"),
        ParamSpec::Float("cut_fraction", 0.9, 0.0, 1.0,
                         "camera cut: history restarts when more than this fraction of pixels lose every tap"),
    });
    i.required = {Role::Colour, Role::Normal, Role::Position};
    i.optional = {Role::Albedo, Role::Motion, Role::Depth};
    i.temporal = true;
    i.nonfinite_policy =
        "NaN/Inf colour: the pixel keeps its reprojected history (or is invalid without one) and is left out of the fit; "
        "NaN/Inf position or normal: no history for that pixel, left out of the fit, its features read as mid-range; "
        "NaN/Inf albedo reads as 1; NaN/Inf motion means no history; a block with no valid pixel keeps the history "
        "(0 without one); outputs are clamped to the float range";
    i.sweep_param = "block_size";
    i.sweep_values = {16, 32, 64};
    return i;
  }();
  return info;
}

void BmfrFilter::check_params() {
  AccumulationParams p;
  p.alpha = params_.get_float("alpha1");
  p.reprojection.relative_position = params_.get_enum("position_test") == "relative";
  p.reprojection.position_threshold = params_.get_float("position_threshold");
  p.reprojection.normal_cos = params_.get_float("normal_threshold");
  p.reprojection.cut_fraction = params_.get_float("cut_fraction");
  phase1_.set_params(p);
}

void BmfrFilter::reset() {
  phase1_.reset();
  phase3_.reset();
  taa_history_ = Image();
  frame_index_ = 0;
  last_cut_ = false;
}

void BmfrFilter::fit_blocks(const Frame& frame, const Image& illum, const std::vector<float>& valid, Image& fitted,
                            int nthreads) {
  const int w = frame.width, h = frame.height;
  const int B = int(params_.get_int("block_size"));
  const FeatureLayout lay = layout_of(params_.get_enum("features"));
  const double eps = params_.get_float("epsilon");
  const std::uint64_t seed = std::uint64_t(params_.get_int("seed"));
  const Image& pos = frame.image(Role::Position, Prefer::Geometry);
  const Image& nrm = frame.image(Role::Normal, Prefer::Geometry);
  const Image* alb = lay.albedo ? &frame.image(Role::Albedo) : nullptr;
  const Image* dep = lay.depth ? &frame.image(Role::Depth) : nullptr;

  int ox = 0, oy = 0;
  if (params_.get_bool("offsets")) {
    const auto& o = grid_offsets()[std::size_t(frame_index_ % 16)];
    ox = std::min(B - 1, int(o[0] * float(B)));
    oy = std::min(B - 1, int(o[1] * float(B)));
  }
  // Blocks start at -ox + k B: the first and last ones are partial.
  const int nbx = (w + ox + B - 1) / B, nby = (h + oy + B - 1) / B;
  const int R = lay.raw(), M = lay.columns();

  parallel_rows(0, nby, nthreads, [&](int by) {
    std::vector<double> raw, feat, mat;
    std::vector<std::size_t> pix;
    std::vector<unsigned char> ffin;
    std::vector<int> rows;
    AugmentedQr qr;
    for (int bx = 0; bx < nbx; ++bx) {
      const int x0 = std::max(0, bx * B - ox), x1 = std::min(w, (bx + 1) * B - ox);
      const int y0 = std::max(0, by * B - oy), y1 = std::min(h, (by + 1) * B - oy);
      if (x1 <= x0 || y1 <= y0) continue;
      const int np = (x1 - x0) * (y1 - y0);
      pix.resize(std::size_t(np));
      raw.assign(std::size_t(np) * R, 0.0);
      ffin.assign(std::size_t(np), 1);
      // Raw features; a pixel with any non-finite feature is left out of the fit and
      // its features read as mid-range (0 after scaling).
      int p = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x, ++p) {
          pix[std::size_t(p)] = std::size_t(y) * w + x;
          double* f = raw.data() + std::size_t(p) * R;
          const float* n = nrm.pixel(x, y);
          const float* q = pos.pixel(x, y);
          f[0] = n[0]; f[1] = n[1]; f[2] = n[2];
          f[3] = q[0]; f[4] = q[1]; f[5] = q[2];
          int k = 6;
          if (alb) {
            const float* a = alb->pixel(x, y);
            for (int c = 0; c < 3; ++c) f[k++] = a[std::min(c, alb->channels() - 1)];
          }
          if (dep) f[k++] = dep->pixel(x, y)[0];
          for (int c = 0; c < R; ++c)
            if (!std::isfinite(f[c])) ffin[std::size_t(p)] = 0;
        }
      // Scaled, noise-free features for every pixel (row-major np x M).
      feat.assign(std::size_t(np) * M, 0.0);
      auto scale_column = [&](int col, auto&& value) {
        double lo = INFINITY, hi = -INFINITY;
        for (int i = 0; i < np; ++i)
          if (ffin[std::size_t(i)]) {
            const double v = value(i);
            lo = std::min(lo, v);
            hi = std::max(hi, v);
          }
        const double range = hi - lo;
        // Constant within float rounding: the column is 0 (the constant column carries it).
        if (!(range > 1e-5 * std::max(std::fabs(lo), std::fabs(hi))) || !(range > 1e-30) || !std::isfinite(range)) return;
        for (int i = 0; i < np; ++i)
          if (ffin[std::size_t(i)]) feat[std::size_t(i) * M + col] = std::clamp(2.0 * (value(i) - lo) / range - 1.0, -1.0, 1.0);
      };
      for (int i = 0; i < np; ++i) feat[std::size_t(i) * M] = 1.0;
      // Columns: 0 constant; 1..3 normal; 4..6 position; [7..9 position^2]; extras.
      for (int c = 0; c < R; ++c) {
        const int col = c < 6 ? 1 + c : 1 + c + (lay.squares ? 3 : 0);
        scale_column(col, [&](int i) { return raw[std::size_t(i) * R + c]; });
      }
      if (lay.squares)
        for (int c = 0; c < 3; ++c) {
          // Square of the scaled position: the same span as w^2 with w, better conditioned.
          scale_column(7 + c, [&](int i) {
            const double s = feat[std::size_t(i) * M + 4 + c];
            return s * s;
          });
        }
      // Fitted rows: valid colour and finite features.
      rows.clear();
      for (int i = 0; i < np; ++i)
        if (ffin[std::size_t(i)] && valid[pix[std::size_t(i)]] > 0.0f) rows.push_back(i);
      const int W = int(rows.size());
      if (W == 0) {
        for (int i = 0; i < np; ++i)
          for (int c = 0; c < 3; ++c) fitted.data()[pix[std::size_t(i)] * 3 + c] = std::numeric_limits<float>::quiet_NaN();
        continue;
      }
      mat.assign(std::size_t(W) * (M + 3), 0.0);
      std::uint64_t rng = seed * 0x2545F4914F6CDD1Dull ^ (std::uint64_t(frame_index_) << 32) ^
                          (std::uint64_t(by) * 65537u + std::uint64_t(bx) + 1);
      splitmix(rng);
      double zmin[3] = {INFINITY, INFINITY, INFINITY};
      for (int r = 0; r < W; ++r) {
        const int i = rows[std::size_t(r)];
        mat[std::size_t(r)] = 1.0;  // no noise on the constant: a constant block stays exact
        for (int m = 1; m < M; ++m)
          mat[std::size_t(m) * W + r] = feat[std::size_t(i) * M + m] + (eps > 0 ? eps * uniform_pm1(rng) : 0.0);
        const float* z = illum.data() + pix[std::size_t(i)] * 3;
        for (int c = 0; c < 3; ++c) {
          mat[std::size_t(M + c) * W + r] = z[c];
          zmin[c] = std::min(zmin[c], double(z[c]));
        }
      }
      qr.factorize(mat.data(), W, M, 3);
      double alpha[3][32];
      for (int c = 0; c < 3; ++c) qr.solve(c, alpha[c]);
      // Synthesis with the noise-free features.
      for (int i = 0; i < np; ++i) {
        const double* f = feat.data() + std::size_t(i) * M;
        float* o = fitted.data() + pix[std::size_t(i)] * 3;
        for (int c = 0; c < 3; ++c) {
          double s = 0;
          for (int m = 0; m < M; ++m) s += alpha[c][m] * f[m];
          // Radiance is not negative: no fit below min(0, the block's smallest input).
          s = std::max(s, std::min(0.0, zmin[c]));
          o[c] = std::isfinite(s) ? float(std::clamp(s, -kFloatMax, kFloatMax)) : std::numeric_limits<float>::quiet_NaN();
        }
      }
    }
  });
}

void BmfrFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  const int w = frame.width, h = frame.height;
  const FeatureLayout lay = layout_of(params_.get_enum("features"));
  if (lay.albedo && !frame.has(Role::Albedo))
    throw Error(Errc::MissingPass, "filter 'bmfr': features=with_albedo needs the albedo pass, absent in '" + frame.path + "'");
  if (lay.depth && !frame.has(Role::Depth))
    throw Error(Errc::MissingPass, "filter 'bmfr': features=with_depth needs the depth pass, absent in '" + frame.path + "'");
  stage_ms_.fill(0.0);
  auto t0 = std::chrono::steady_clock::now();

  // Albedo guard: [albedo_floor, inf) per channel, non-finite reads as 1.
  const std::size_t n = std::size_t(w) * h;
  std::vector<float> albedo;
  const Pass* ap = frame.find(Role::Albedo);
  // The common `demodulate` parameter, when set, has the base class divide before run()
  // and multiply after (TAA then sees the illumination): our own step is skipped so the
  // albedo is divided out exactly once.
  const bool base_demod = params_.get_bool("demodulate");
  const bool demod = params_.get_bool("albedo_demodulation") && ap && !base_demod;
  if (params_.get_bool("albedo_demodulation") && !ap) note("no albedo pass: the colour is fitted without demodulation");
  if (params_.get_bool("albedo_demodulation") && base_demod) note("demodulate=true: the base class demodulates; albedo_demodulation skipped");
  Image illum(w, h, 3);
  if (demod) albedo.resize(n * 3);
  {
    const float lo = float(params_.get_float("albedo_floor"));
    parallel_rows(0, h, nthreads, [&](int y) {
      for (std::size_t i = std::size_t(y) * w; i < std::size_t(y + 1) * w; ++i)
        for (int c = 0; c < 3; ++c) {
          float a = 1.0f;
          if (demod) {
            const Image& ai = ap->image;
            const float v = ai.data()[i * std::size_t(ai.channels()) + std::size_t(std::min(c, ai.channels() - 1))];
            a = std::isfinite(v) ? std::max(v, lo) : 1.0f;
            albedo[i * 3 + c] = a;
          }
          illum.data()[i * 3 + c] = colour.data()[i * 3 + c] / a;
        }
    });
  }

  // Phase I.
  const Image& acc1 = phase1_.accumulate(frame, illum, nthreads);
  const Reprojection& rep = phase1_.last_reprojection();
  last_cut_ = rep.cut;
  if (rep.cut) note("camera cut: " + std::to_string(rep.discarded) + " of " + std::to_string(n) + " pixels lost their history; restarted");
  if (!rep.has_history || rep.cut) {
    phase3_.reset();
    taa_history_ = Image();
  }
  stage_ms_[kAccumulate] = ms_since(t0);

  // Phase II.
  t0 = std::chrono::steady_clock::now();
  Image fitted(w, h, 3);
  fit_blocks(frame, acc1, phase1_.sample_count(), fitted, nthreads);
  stage_ms_[kFit] = ms_since(t0);

  // Phase III: second accumulation on the same reprojection, then remodulation.
  t0 = std::chrono::steady_clock::now();
  Image result = phase3_.accumulate(rep, fitted, params_.get_float("alpha2"), nthreads);
  parallel_rows(0, h, nthreads, [&](int y) {
    float* r = result.data() + std::size_t(y) * w * 3;
    const float* a = demod ? albedo.data() + std::size_t(y) * w * 3 : nullptr;
    for (std::size_t i = 0; i < std::size_t(w) * 3; ++i) {
      const double v = a ? double(r[i]) * a[i] : double(r[i]);
      r[i] = float(std::clamp(v, -kFloatMax, kFloatMax));
    }
  });
  stage_ms_[kPost] = ms_since(t0);

  // TAA (Karis 2014): previous output reprojected by the motion pass (bilinear or Catmull-Rom),
  // clamped to the 3x3 min/max of the current result, blended with weight taa_alpha for
  // the current frame.
  t0 = std::chrono::steady_clock::now();
  if (params_.get_bool("taa")) {
    const float a = float(params_.get_float("taa_alpha"));
    const bool cubic = params_.get_enum("taa_history") == "catmull_rom";
    Image taa(w, h, 3);
    const bool hist = !taa_history_.empty() && taa_history_.width() == w && taa_history_.height() == h && rep.has_history && !rep.cut;
    parallel_rows(0, h, nthreads, [&](int y) {
      for (int x = 0; x < w; ++x) {
        const float* c = result.pixel(x, y);
        float* o = taa.pixel(x, y);
        std::copy(c, c + 3, o);
        if (!hist) continue;
        const std::size_t i = std::size_t(y) * w + x;
        float hv[3];
        if (cubic) {
          if (!rep.inside[i] || !catmull_rom(taa_history_, rep.prev_x[i], rep.prev_y[i], hv)) continue;
        } else if (rep.sample(i, taa_history_.data(), 3, rep.inside[i], hv, [](std::size_t) { return true; }) <= 0.0f) {
          continue;
        }
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy)
          for (int xx = std::max(0, x - 1); xx <= std::min(w - 1, x + 1); ++xx) {
            const float* q = result.pixel(xx, yy);
            for (int k = 0; k < 3; ++k) {
              lo[k] = std::min(lo[k], q[k]);
              hi[k] = std::max(hi[k], q[k]);
            }
          }
        for (int k = 0; k < 3; ++k) {
          const float hc = std::clamp(hv[k], lo[k], hi[k]);
          o[k] = float(double(hc) + double(a) * (double(c[k]) - double(hc)));
        }
      }
    });
    taa_history_ = std::move(taa);
  } else {
    taa_history_ = Image();
  }
  stage_ms_[kTaa] = ms_since(t0);

  const Image& final_image = params_.get_bool("taa") ? taa_history_ : result;
  for (int y = roi.y0; y < roi.y1; ++y)
    std::copy(final_image.pixel(roi.x0, y), final_image.pixel(roi.x0, y) + std::size_t(roi.width()) * 3, out.pixel(roi.x0, y));
  ++frame_index_;
}

}  // namespace mcr
