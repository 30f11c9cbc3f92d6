#include "filters/bmfr.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <ctime>

#include "linalg/householder_qr.h"
#include "util/error.h"
#include "util/parallel.h"

#include <tbb/enumerable_thread_specific.h>

namespace mcr {

namespace {

constexpr double kFloatMax = std::numeric_limits<float>::max();

double cpu_now_ms() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

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
  const float fx0 = float(floor_int(x)), fy0 = float(floor_int(y));
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
  float acc[3] = {0, 0, 0};
  const int bx = int(fx0) - 1, by = int(fy0) - 1;
  if (bx >= 0 && by >= 0 && bx + 3 < w && by + 3 < h) {  // interior: no clamping
    const float* base = im.data() + (std::size_t(by) * std::size_t(w) + std::size_t(bx)) * 3;
    for (int j = 0; j < 4; ++j) {
      const float* p = base + std::size_t(j) * std::size_t(w) * 3;
      float row[3] = {0, 0, 0};
      for (int i = 0; i < 4; ++i)
        for (int c = 0; c < 3; ++c) row[c] += wx[i] * p[i * 3 + c];
      for (int c = 0; c < 3; ++c) acc[c] += wy[j] * row[c];
    }
  } else {
    for (int j = 0; j < 4; ++j) {
      const int yy = std::clamp(by + j, 0, h - 1);
      float row[3] = {0, 0, 0};
      for (int i = 0; i < 4; ++i) {
        const float* p = im.pixel(std::clamp(bx + i, 0, w - 1), yy);
        for (int c = 0; c < 3; ++c) row[c] += wx[i] * p[c];
      }
      for (int c = 0; c < 3; ++c) acc[c] += wy[j] * row[c];
    }
  }
  for (int c = 0; c < 3; ++c) out[c] = acc[c];
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
        ParamSpec::Int("block_size", 0, 0, 128,
                       "side of the square regression blocks in pixels (8..128); 0 = auto: 32 (the paper's) when the "
                       "shorter image side is >= 360 pixels, 16 below"),
        ParamSpec::Float("epsilon", 0.01, 0.0, 10.0,
                         "stochastic regularisation: uniform noise in [-epsilon, epsilon] added to the fitted features"),
        ParamSpec::Float("alpha1", 0.2, 0.01, 1.0, "phase I: weight floor of the new noisy sample (cumulative average until then)"),
        ParamSpec::Float("alpha2", 0.1, 0.01, 1.0, "phase III: weight floor of the new fitted frame"),
        ParamSpec::Enum("features", "default", {"default", "first_order", "with_albedo", "with_depth"},
                        "feature set: default [1,n,w,w^2] (10), first_order [1,n,w] (7), with_albedo (+albedo, 13), "
                        "with_depth (+depth, 11)"),
        ParamSpec::Bool("offsets", true, "displace the block grid every frame by a fixed 16-entry random sequence"),
        ParamSpec::Bool("taa", true, "temporal anti-aliasing (reprojected history clipped to the 3x3 neighbourhood, see taa_clip) at the end"),
        ParamSpec::Float("taa_alpha", 0.2, 0.01, 1.0, "TAA: weight of the current frame"),
        ParamSpec::Enum("taa_clip", "ycocg_variance", {"ycocg_variance", "rgb_minmax"},
                        "TAA history clipping box: ycocg_variance = 3x3 min/max intersected with mean +- taa_gamma "
                        "standard deviations in YCoCg (Karis 2014, Salvi 2016); rgb_minmax = 3x3 min/max in RGB"),
        ParamSpec::Float("taa_gamma", 1.0, 0.1, 10.0, "TAA: half-width of the variance box in standard deviations"),
        ParamSpec::Enum("taa_history", "catmull_rom", {"bilinear", "catmull_rom"},
                        "TAA: history lookup (catmull_rom: sharper, Karis 2014; bilinear blurs a moving image a little "
                        "more every frame)"),
        ParamSpec::Bool("fit_clamp", true,
                        "clamp the fitted illumination to [min(0, block min), max(0, block max)] of the block's "
                        "accumulated input (the paper clamps only at 0 implicitly; guards ill-conditioned blocks)"),
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
  const std::int64_t b = params_.get_int("block_size");
  if (b != 0 && b < 8) throw Error(Errc::InvalidArgument, "filter 'bmfr': block_size must be 0 (auto) or 8..128, got " + std::to_string(b));
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

int BmfrFilter::block_side(std::int64_t param, int w, int h) {
  if (param > 0) return int(param);
  return std::min(w, h) >= 360 ? 32 : 16;
}

namespace {
void ensure_image(Image& im, int w, int h, int ch) {
  if (im.width() != w || im.height() != h || im.channels() != ch) im = Image(w, h, ch);
}

// Per-thread scratch of the fit, sized once for the largest block.
struct FitScratch {
  std::vector<float> raw;    // R columns x np, planar
  std::vector<float> feat;   // M columns x np, planar, scaled, noise-free
  std::vector<unsigned char> fin;
  std::vector<std::size_t> pix;
  std::vector<int> rows;
  std::vector<double> mat;   // W x (M + 3), column-major
  std::vector<double> acc;   // 3 x np synthesis
  AugmentedQr qr;
};
}  // namespace

void BmfrFilter::fit_blocks(const Frame& frame, const Image& illum, const std::vector<float>& valid, Image& fitted,
                            int nthreads) {
  const int w = frame.width, h = frame.height;
  const int B = block_side(params_.get_int("block_size"), w, h);
  const FeatureLayout lay = layout_of(params_.get_enum("features"));
  const double eps = params_.get_float("epsilon");
  const std::uint64_t seed = std::uint64_t(params_.get_int("seed"));
  const bool clamp_max = params_.get_bool("fit_clamp");
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
  const std::size_t cap = std::size_t(B) * std::size_t(B);
  const int pch = pos.channels(), nch = nrm.channels();

  // One task per block (rows of blocks would leave a thread idle on the last ones); the
  // result of a block depends on (seed, frame, block) only.
  const int nblocks = nbx * nby;
  tbb::task_arena arena(arena_threads(nthreads));
  tbb::enumerable_thread_specific<FitScratch> scratch;
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, nblocks, 1), [&](const tbb::blocked_range<int>& range) {
      FitScratch& S = scratch.local();
      if (S.fin.size() < cap) {
        S.raw.resize(cap * std::size_t(R));
        S.feat.resize(cap * std::size_t(M));
        S.fin.resize(cap);
        S.pix.resize(cap);
        S.rows.resize(cap);
        S.mat.resize(cap * std::size_t(M + 3));
        S.acc.resize(cap * 3);
      }
      for (int b = range.begin(); b != range.end(); ++b) {
        const int by = b / nbx, bx = b % nbx;
        const int x0 = std::max(0, bx * B - ox), x1 = std::min(w, (bx + 1) * B - ox);
        const int y0 = std::max(0, by * B - oy), y1 = std::min(h, (by + 1) * B - oy);
        if (x1 <= x0 || y1 <= y0) continue;
        const int bw = x1 - x0, np = bw * (y1 - y0);
        const std::size_t snp = std::size_t(np);
        float* raw = S.raw.data();
        float* feat = S.feat.data();
        unsigned char* fin = S.fin.data();
        std::size_t* pix = S.pix.data();
        // Raw features, planar; a pixel with any non-finite feature is left out of the fit
        // and its features read as mid-range (0 after scaling).
        int p = 0;
        for (int y = y0; y < y1; ++y) {
          const float* nrow = nrm.data() + (std::size_t(y) * w + x0) * nch;
          const float* prow = pos.data() + (std::size_t(y) * w + x0) * pch;
          for (int x = 0; x < bw; ++x, ++p) {
            pix[p] = std::size_t(y) * w + std::size_t(x0 + x);
            const float* n = nrow + std::size_t(x) * nch;
            const float* q = prow + std::size_t(x) * pch;
            raw[0 * snp + p] = n[0];
            raw[1 * snp + p] = n[1];
            raw[2 * snp + p] = n[2];
            raw[3 * snp + p] = q[0];
            raw[4 * snp + p] = q[1];
            raw[5 * snp + p] = q[2];
            int k = 6;
            if (alb) {
              const float* a = alb->pixel(x0 + x, y);
              for (int c = 0; c < 3; ++c) raw[std::size_t(k++) * snp + p] = a[std::min(c, alb->channels() - 1)];
            }
            if (dep) raw[std::size_t(k++) * snp + p] = dep->pixel(x0 + x, y)[0];
            bool f = true;
            for (int c = 0; c < R; ++c) f = f && std::isfinite(raw[std::size_t(c) * snp + p]);
            fin[p] = f ? 1 : 0;
          }
        }
        // Scaled to [-1, 1] over the block's finite pixels; a column constant within float
        // rounding is 0 (the constant column carries it).
        auto scale_column = [&](const float* src, float* dst) {
          float lo = INFINITY, hi = -INFINITY;
          for (int i = 0; i < np; ++i)
            if (fin[i]) {
              lo = std::min(lo, src[i]);
              hi = std::max(hi, src[i]);
            }
          const double range = double(hi) - double(lo);
          if (!(range > 1e-5 * std::max(std::fabs(double(lo)), std::fabs(double(hi)))) || !(range > 1e-30) ||
              !std::isfinite(range)) {
            std::fill(dst, dst + np, 0.0f);
            return;
          }
          const float sc = float(2.0 / range);
          for (int i = 0; i < np; ++i) {
            const float v = std::clamp((src[i] - lo) * sc - 1.0f, -1.0f, 1.0f);
            dst[i] = fin[i] ? v : 0.0f;
          }
        };
        std::fill(feat, feat + np, 1.0f);
        // Columns: 0 constant; 1..3 normal; 4..6 position; [7..9 position^2]; extras.
        for (int c = 0; c < R; ++c) {
          const int col = c < 6 ? 1 + c : 1 + c + (lay.squares ? 3 : 0);
          scale_column(raw + std::size_t(c) * snp, feat + std::size_t(col) * snp);
        }
        if (lay.squares)
          for (int c = 0; c < 3; ++c) {
            // Square of the scaled position: the same span as w^2 with w, better conditioned.
            float* sq = raw;  // raw column 0 is no longer needed: reuse as scratch
            const float* s0 = feat + std::size_t(4 + c) * snp;
            for (int i = 0; i < np; ++i) sq[i] = s0[i] * s0[i];
            scale_column(sq, feat + std::size_t(7 + c) * snp);
          }
        // Fitted rows: valid colour and finite features.
        int W = 0;
        for (int i = 0; i < np; ++i)
          if (fin[i] && valid[pix[i]] > 0.0f) S.rows[std::size_t(W++)] = i;
        if (W == 0) {
          for (int i = 0; i < np; ++i)
            for (int c = 0; c < 3; ++c) fitted.data()[pix[i] * 3 + c] = std::numeric_limits<float>::quiet_NaN();
          continue;
        }
        double* mat = S.mat.data();
        const std::size_t sW = std::size_t(W);
        std::uint64_t rng = seed * 0x2545F4914F6CDD1Dull ^ (std::uint64_t(frame_index_) << 32) ^
                            (std::uint64_t(by) * 65537u + std::uint64_t(bx) + 1);
        // Per-block noise stream: xorshift64 seeded by splitmix of (seed, frame, block),
        // two 32-bit uniforms in [-1, 1) per step (plenty for a regulariser).
        std::uint64_t xs = splitmix(rng) | 1u;
        const int* rows = S.rows.data();
        const bool dense = W == np;  // every pixel fitted: rows[r] == r
        for (int r = 0; r < W; ++r) mat[r] = 1.0;  // no noise on the constant: a constant block stays exact
        // The noise goes on the fitted features only, never on the synthesis ones.
        const double e31 = eps * (1.0 / 2147483648.0);
        for (int m = 1; m < M; ++m) {
          double* col = mat + std::size_t(m) * sW;
          const float* fm = feat + std::size_t(m) * snp;
          if (dense)
            for (int r = 0; r < W; ++r) col[r] = double(fm[r]);
          else
            for (int r = 0; r < W; ++r) col[r] = double(fm[rows[r]]);
          if (eps > 0) {
            int r = 0;
            for (; r + 2 <= W; r += 2) {
              xs ^= xs << 13;
              xs ^= xs >> 7;
              xs ^= xs << 17;
              col[r] += e31 * double(std::int32_t(std::uint32_t(xs)));
              col[r + 1] += e31 * double(std::int32_t(std::uint32_t(xs >> 32)));
            }
            if (r < W) {
              xs ^= xs << 13;
              xs ^= xs >> 7;
              xs ^= xs << 17;
              col[r] += e31 * double(std::int32_t(std::uint32_t(xs >> 32)));
            }
          }
        }
        double zmin[3] = {INFINITY, INFINITY, INFINITY}, zmax[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int c = 0; c < 3; ++c) {
          double* col = mat + std::size_t(M + c) * sW;
          double zm = INFINITY, zx = -INFINITY;
          for (int r = 0; r < W; ++r) {
            const double z = illum.data()[pix[rows[r]] * 3 + std::size_t(c)];
            col[r] = z;
            zm = std::min(zm, z);
            zx = std::max(zx, z);
          }
          zmin[c] = zm;
          zmax[c] = zx;
        }
        S.qr.factorize(mat, W, M, 3);
        double alpha[3][32];
        for (int c = 0; c < 3; ++c) S.qr.solve(c, alpha[c]);
        // Synthesis with the noise-free features (planar, vectorised over the pixels).
        double* acc = S.acc.data();
        for (int c = 0; c < 3; ++c) {
          double* ac = acc + std::size_t(c) * snp;
          const double a0 = alpha[c][0];
          for (int i = 0; i < np; ++i) ac[i] = a0;
          for (int m = 1; m < M; ++m) {
            const double am = alpha[c][m];
            if (am == 0.0) continue;
            const float* fm = feat + std::size_t(m) * snp;
            for (int i = 0; i < np; ++i) ac[i] += am * double(fm[i]);
          }
        }
        for (int i = 0; i < np; ++i) {
          float* o = fitted.data() + pix[i] * 3;
          for (int c = 0; c < 3; ++c) {
            // Radiance is not negative: no fit below min(0, the block's smallest input).
            // Nor above the block's largest input: an ill-conditioned fit extrapolating at
            // the pixels it was not fitted on (invalid ones, partial edge blocks) cannot
            // make a highlight brighter than anything it was given.
            double v = std::max(acc[std::size_t(c) * snp + i], std::min(0.0, zmin[c]));
            if (clamp_max) v = std::min(v, std::max(0.0, zmax[c]));
            o[c] = std::isfinite(v) ? float(std::clamp(v, -kFloatMax, kFloatMax)) : std::numeric_limits<float>::quiet_NaN();
          }
        }
      }
    });
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
  stage_cpu_ms_.fill(0.0);
  auto t0 = std::chrono::steady_clock::now();
  double c0 = cpu_now_ms();

  // Albedo guard: [albedo_floor, inf) per channel, non-finite reads as 1.
  const std::size_t n = std::size_t(w) * h;
  const Pass* ap = frame.find(Role::Albedo);
  // The common `demodulate` parameter, when set, has the base class divide before run()
  // and multiply after (TAA then sees the illumination): our own step is skipped so the
  // albedo is divided out exactly once.
  const bool base_demod = params_.get_bool("demodulate");
  const bool demod = params_.get_bool("albedo_demodulation") && ap && !base_demod;
  if (params_.get_bool("albedo_demodulation") && !ap) note("no albedo pass: the colour is fitted without demodulation");
  if (params_.get_bool("albedo_demodulation") && base_demod) note("demodulate=true: the base class demodulates; albedo_demodulation skipped");
  // Demodulation fused into phase I: row y of the illumination is made right before
  // phase I reads it.
  std::function<void(int)> demod_row;
  if (demod) {
    ensure_image(illum_, w, h, 3);
    ensure_image(albedo_, w, h, 3);
    const float lo = float(params_.get_float("albedo_floor"));
    const Image& ai = ap->image;
    const int ach = ai.channels();
    demod_row = [&, lo, ach](int y) {
      const std::size_t b = std::size_t(y) * w, e = b + std::size_t(w);
      float* il = illum_.data();
      float* al = albedo_.data();
      const float* co = colour.data();
      const float* ad = ai.data();
      for (std::size_t i = b; i < e; ++i)
        for (int c = 0; c < 3; ++c) {
          const float v = ad[i * std::size_t(ach) + std::size_t(std::min(c, ach - 1))];
          const float a = std::isfinite(v) ? std::max(v, lo) : 1.0f;
          al[i * 3 + c] = a;
          il[i * 3 + c] = co[i * 3 + c] / a;
        }
    };
  }

  // Phase I (reprojection fused with the accumulation).
  const Image& acc1 = demod ? phase1_.accumulate(frame, illum_, demod_row, nthreads) : phase1_.accumulate(frame, colour, nthreads);
  const Reprojection& rep = phase1_.last_reprojection();
  last_cut_ = rep.cut;
  if (rep.cut) note("camera cut: " + std::to_string(rep.discarded) + " of " + std::to_string(n) + " pixels lost their history; restarted");
  if (!rep.has_history || rep.cut) {
    phase3_.reset();
    taa_history_ = Image();
  }
  stage_ms_[kAccumulate] = ms_since(t0);
  stage_cpu_ms_[kAccumulate] = cpu_now_ms() - c0;

  // Phase II.
  t0 = std::chrono::steady_clock::now();
  c0 = cpu_now_ms();
  ensure_image(fitted_, w, h, 3);
  fit_blocks(frame, acc1, phase1_.sample_count(), fitted_, nthreads);
  stage_ms_[kFit] = ms_since(t0);
  stage_cpu_ms_[kFit] = cpu_now_ms() - c0;

  // Phase III: second accumulation on phase I's reprojection (its discard decisions),
  // remodulation and (for TAA) the conversion to its clipping space, in one pass.
  t0 = std::chrono::steady_clock::now();
  c0 = cpu_now_ms();
  const bool use_taa = params_.get_bool("taa");
  const bool hist = use_taa && !taa_history_.empty() && taa_history_.width() == w && taa_history_.height() == h &&
                    rep.has_history && !rep.cut;
  const bool ycocg = params_.get_enum("taa_clip") == "ycocg_variance";
  const double alpha2 = params_.get_float("alpha2");
  ensure_image(result_, w, h, 3);
  if (hist) space_.resize(n * 3);
  phase3_.begin(rep, fitted_);
  parallel_rows(0, h, nthreads, [&](int y) {
    phase3_.row(y, rep, fitted_, alpha2);
    const float* s = phase3_.pending().data() + std::size_t(y) * w * 3;
    float* r = result_.data() + std::size_t(y) * w * 3;
    const float* a = demod ? albedo_.data() + std::size_t(y) * w * 3 : nullptr;
    for (std::size_t i = 0; i < std::size_t(w) * 3; ++i) {
      const float v = a ? s[i] * a[i] : s[i];
      r[i] = std::isfinite(v) ? v : (std::isnan(v) ? v : std::copysign(std::numeric_limits<float>::max(), v));
    }
    if (!hist) return;
    float* s0 = space_.data() + std::size_t(y) * w;
    float* s1 = s0 + n;
    float* s2 = s1 + n;
    for (int x = 0; x < w; ++x) {
      const float R = r[x * 3], G = r[x * 3 + 1], B = r[x * 3 + 2];
      if (ycocg) {
        s0[x] = 0.25f * R + 0.5f * G + 0.25f * B;
        s1[x] = 0.5f * R - 0.5f * B;
        s2[x] = -0.25f * R + 0.5f * G - 0.25f * B;
      } else {
        s0[x] = R;
        s1[x] = G;
        s2[x] = B;
      }
    }
  });
  phase3_.finish();
  stage_ms_[kPost] = ms_since(t0);
  stage_cpu_ms_[kPost] = cpu_now_ms() - c0;

  t0 = std::chrono::steady_clock::now();
  c0 = cpu_now_ms();
  if (use_taa) {
    taa(rep, hist, nthreads);
  } else {
    taa_history_ = Image();
  }
  stage_ms_[kTaa] = ms_since(t0);
  stage_cpu_ms_[kTaa] = cpu_now_ms() - c0;

  const Image& final_image = use_taa ? taa_history_ : result_;
  for (int y = roi.y0; y < roi.y1; ++y)
    std::copy(final_image.pixel(roi.x0, y), final_image.pixel(roi.x0, y) + std::size_t(roi.width()) * 3, out.pixel(roi.x0, y));
  ++frame_index_;
}

// TAA (Karis 2014): the previous output reprojected by the motion pass (bilinear or
// Catmull-Rom), clipped to the current result's 3x3 neighbourhood, blended with weight
// taa_alpha for the current frame. taa_clip=ycocg_variance: the box is the intersection
// of the 3x3 min/max and mean +- taa_gamma standard deviations (Salvi 2016), in YCoCg
// (Karis 2014): tighter than the plain min/max, which lets outliers of the fit through.
// taa_clip=rgb_minmax: the 3x3 min/max in RGB.
void BmfrFilter::taa(const Reprojection& rep, bool hist, int nthreads) {
  const int w = result_.width(), h = result_.height();
  const std::size_t n = std::size_t(w) * h;
  const float a = float(params_.get_float("taa_alpha"));
  const bool cubic = params_.get_enum("taa_history") == "catmull_rom";
  const bool ycocg = params_.get_enum("taa_clip") == "ycocg_variance";
  const float gamma = float(params_.get_float("taa_gamma"));
  ensure_image(taa_next_, w, h, 3);
  if (!hist) {
    std::copy(result_.storage().begin(), result_.storage().end(), taa_next_.storage().begin());
    std::swap(taa_history_, taa_next_);
    return;
  }
  // space_ holds the result in the clipping space, planar (made in phase III).
  parallel_rows(0, h, nthreads, [&](int y) {
    // Column statistics over rows y-1..y+1 (clamped: the border pixel counts twice),
    // with one pixel of padding on each side, then the 3-wide sums along the row.
    thread_local std::vector<float> col;
    col.resize(std::size_t(w + 2) * 12);
    const int ya = std::max(0, y - 1), yb = std::min(h - 1, y + 1);
    for (int c = 0; c < 3; ++c) {
      const float* p0 = space_.data() + std::size_t(c) * n + std::size_t(ya) * w;
      const float* p1 = space_.data() + std::size_t(c) * n + std::size_t(y) * w;
      const float* p2 = space_.data() + std::size_t(c) * n + std::size_t(yb) * w;
      float* cs = col.data() + std::size_t(c) * 4 * (w + 2);
      float* cq = cs + (w + 2);
      float* cmn = cq + (w + 2);
      float* cmx = cmn + (w + 2);
      for (int x = 0; x < w; ++x) {
        const float v0 = p0[x], v1 = p1[x], v2 = p2[x];
        cs[x + 1] = v0 + v1 + v2;
        cq[x + 1] = v0 * v0 + v1 * v1 + v2 * v2;
        cmn[x + 1] = std::min(v0, std::min(v1, v2));
        cmx[x + 1] = std::max(v0, std::max(v1, v2));
      }
      cs[0] = cs[1]; cq[0] = cq[1]; cmn[0] = cmn[1]; cmx[0] = cmx[1];
      cs[w + 1] = cs[w]; cq[w + 1] = cq[w]; cmn[w + 1] = cmn[w]; cmx[w + 1] = cmx[w];
    }
    const float* hist_data = taa_history_.data();
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      const float* c = result_.data() + i * 3;
      float* o = taa_next_.data() + i * 3;
      float hv[3];
      bool ok;
      if (cubic) {
        ok = rep.inside[i] && catmull_rom(taa_history_, rep.prev_x[i], rep.prev_y[i], hv);
      } else {
        ok = rep.sample(i, hist_data, 3, rep.inside[i], hv, [](std::size_t) { return true; }) > 0.0f;
      }
      if (!ok) {
        o[0] = c[0]; o[1] = c[1]; o[2] = c[2];
        continue;
      }
      float hs[3];
      if (ycocg) {
        hs[0] = 0.25f * hv[0] + 0.5f * hv[1] + 0.25f * hv[2];
        hs[1] = 0.5f * hv[0] - 0.5f * hv[2];
        hs[2] = -0.25f * hv[0] + 0.5f * hv[1] - 0.25f * hv[2];
      } else {
        hs[0] = hv[0]; hs[1] = hv[1]; hs[2] = hv[2];
      }
      float blo[3], bhi[3];
      for (int k = 0; k < 3; ++k) {
        const float* cs = col.data() + std::size_t(k) * 4 * (w + 2);
        const float* cq = cs + (w + 2);
        const float* cmn = cq + (w + 2);
        const float* cmx = cmn + (w + 2);
        float lo = std::min(cmn[x], std::min(cmn[x + 1], cmn[x + 2]));
        float hi = std::max(cmx[x], std::max(cmx[x + 1], cmx[x + 2]));
        if (ycocg) {
          const float mean = (cs[x] + cs[x + 1] + cs[x + 2]) * (1.0f / 9.0f);
          const float var = std::max(0.0f, (cq[x] + cq[x + 1] + cq[x + 2]) * (1.0f / 9.0f) - mean * mean);
          const float sd = gamma * std::sqrt(var);
          // The box always holds the current pixel: a history equal to it passes.
          const float cur = space_[std::size_t(k) * n + i];
          lo = std::max(lo, std::min(mean - sd, cur));
          hi = std::min(hi, std::max(mean + sd, cur));
        }
        blo[k] = lo;
        bhi[k] = hi;
      }
      if (ycocg) {
        // Clip towards the box centre along the line to the history (Karis 2014): keeps
        // the history's hue instead of moving each channel on its own.
        // A channel whose box is flat (within float rounding of the luma) does not steer
        // the clip: the final clamp handles it.
        float ratio = 1.0f;
        float ctr[3], d[3];
        for (int k = 0; k < 3; ++k) {
          ctr[k] = 0.5f * (blo[k] + bhi[k]);
          d[k] = hs[k] - ctr[k];
        }
        const float tol = 1e-5f * (std::fabs(ctr[0]) + 0.5f * (bhi[0] - blo[0])) + 1e-30f;
        for (int k = 0; k < 3; ++k) {
          const float ext = 0.5f * (bhi[k] - blo[k]);
          const float ad = std::fabs(d[k]);
          if (ext > tol && ad > ext) ratio = std::max(ratio, ad / ext);
        }
        if (ratio > 1.0f && std::isfinite(ratio))
          for (int k = 0; k < 3; ++k) hs[k] = ctr[k] + d[k] / ratio;
        for (int k = 0; k < 3; ++k) hs[k] = std::clamp(hs[k], blo[k], bhi[k]);
      } else {
        for (int k = 0; k < 3; ++k) hs[k] = std::clamp(hs[k], blo[k], bhi[k]);
      }
      float hc[3];
      if (ycocg) {
        const float t = hs[0] - hs[2];
        hc[0] = t + hs[1];
        hc[1] = hs[0] + hs[2];
        hc[2] = t - hs[1];
      } else {
        hc[0] = hs[0]; hc[1] = hs[1]; hc[2] = hs[2];
      }
      for (int k = 0; k < 3; ++k) {
        const float v = hc[k] + a * (c[k] - hc[k]);
        o[k] = std::isfinite(v) ? v : c[k];
      }
    }
  });
  std::swap(taa_history_, taa_next_);
}

}  // namespace mcr
