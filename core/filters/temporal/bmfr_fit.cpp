// BMFR phase II: per-block least-squares fit of the accumulated illumination to the
// multi-order features (Koskela et al. 2019, 4.2), one task per block; the feature
// columns (layout, gather, scaling) are in bmfr_fit_features.*.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <limits>

#include "filters/temporal/bmfr.h"
#include "filters/temporal/bmfr_fit_features.h"
#include "linalg/householder_qr.h"
#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

namespace {

using namespace bmfr;  // FeatureLayout, layout_of, masked_min_max, scale_masked, gather_row_avx2

constexpr double kFloatMax = std::numeric_limits<float>::max();


// Counter-based random numbers (splitmix64): the noise of a block depends on
// (seed, frame, block) only, never on the thread that fits it.
std::uint64_t splitmix(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// xorshift64 (13, 7, 17) is linear over GF(2): the state k steps ahead is a 64 x 64 bit
// matrix times the state. kNoiseLane steps ahead, as the images of the 64 unit vectors.
constexpr std::size_t kNoiseLane = 256, kNoiseLanes = 4, kNoiseGroup = kNoiseLane * kNoiseLanes;

inline std::uint64_t xorshift_step(std::uint64_t x) {
  x ^= x << 13;
  x ^= x >> 7;
  x ^= x << 17;
  return x;
}

const std::array<std::uint64_t, 64>& noise_jump() {
  static const std::array<std::uint64_t, 64> jump = [] {
    std::array<std::uint64_t, 64> j{};
    for (int b = 0; b < 64; ++b) {
      std::uint64_t x = std::uint64_t(1) << b;
      for (std::size_t k = 0; k < kNoiseLane; ++k) x = xorshift_step(x);
      j[std::size_t(b)] = x;
    }
    return j;
  }();
  return jump;
}

inline std::uint64_t jump_ahead(const std::array<std::uint64_t, 64>& j, std::uint64_t x) {
  std::uint64_t r0 = 0, r1 = 0;
  for (int b = 0; b < 64; b += 2) {
    r0 ^= j[std::size_t(b)] & (std::uint64_t(0) - ((x >> b) & 1u));
    r1 ^= j[std::size_t(b + 1)] & (std::uint64_t(0) - ((x >> (b + 1)) & 1u));
  }
  return r0 ^ r1;
}

// out[k] = the state after k + 1 steps from xs, k < n (n a multiple of kNoiseGroup): the
// serial sequence, made kNoiseLanes chains at a time (lane l starts l * kNoiseLane
// steps ahead).
void xorshift_stream(std::uint64_t xs, std::uint64_t* out, std::size_t n) {
  const auto& j = noise_jump();
  for (std::size_t g = 0; g < n; g += kNoiseGroup) {
    std::uint64_t s[kNoiseLanes];
    s[0] = xs;
    for (std::size_t l = 1; l < kNoiseLanes; ++l) s[l] = jump_ahead(j, s[l - 1]);
    std::uint64_t* o = out + g;
    for (std::size_t k = 0; k < kNoiseLane; ++k)
      for (std::size_t l = 0; l < kNoiseLanes; ++l) {
        s[l] = xorshift_step(s[l]);
        o[l * kNoiseLane + k] = s[l];
      }
    xs = s[kNoiseLanes - 1];
  }
}

// 4 doubles / floats / int32 (GCC vector extensions: AVX in the AVX2 clone, SSE2 pairs
// in the default one); loaded and stored unaligned.
typedef double v4d __attribute__((vector_size(32), aligned(8)));
typedef float v4f __attribute__((vector_size(16), aligned(4)));
typedef std::int32_t v4i __attribute__((vector_size(16)));

// Per-thread scratch of the fit, sized once for the largest block.
struct FitScratch {
  std::vector<float> raw;    // R columns x np, planar
  std::vector<float> feat;   // M columns x np, planar, scaled, noise-free
  std::vector<float> fin;    // 1: finite features
  std::vector<float> z;      // 3 x np, planar illumination
  std::vector<int> rows;
  std::vector<double> mat;   // W x (M + 3), column-major
  std::vector<double> acc;   // 3 x np synthesis
  std::vector<std::uint64_t> noise;  // regularisation noise stream
  AugmentedQr qr;
};

// Everything one block needs (read-only), for fit_block().
struct FitJob {
  int w, h, B, ox, oy, nbx, R, M, pch, nch;
  FeatureLayout lay;
  double eps;
  std::uint64_t seed;
  std::int64_t frame_index;
  bool clamp_max;
  const Image *pos, *nrm, *alb, *dep;
  const Image* illum;
  const float* valid;
  Image* fitted;
};

// Fits block b. Built for AVX2 as well (util/isa.h): no FMA, so the same operations and
// the same results as the generic build.
MCR_ALWAYS_INLINE void fit_block_body(const FitJob& J, FitScratch& S, int b) {
  const int w = J.w, h = J.h, B = J.B, ox = J.ox, oy = J.oy, nbx = J.nbx, R = J.R, M = J.M, pch = J.pch, nch = J.nch;
  const FeatureLayout& lay = J.lay;
  const double eps = J.eps;
  const std::uint64_t seed = J.seed;
  const std::int64_t frame_index_ = J.frame_index;
  const bool clamp_max = J.clamp_max;
  const Image &pos = *J.pos, &nrm = *J.nrm, &illum = *J.illum;
  const Image *alb = J.alb, *dep = J.dep;
  const float* valid = J.valid;
  Image& fitted = *J.fitted;
  (void)h;
  const int by = b / nbx, bx = b % nbx;
  const int x0 = std::max(0, bx * B - ox), x1 = std::min(w, (bx + 1) * B - ox);
  const int y0 = std::max(0, by * B - oy), y1 = std::min(h, (by + 1) * B - oy);
  if (x1 <= x0 || y1 <= y0) return;
  const int bw = x1 - x0, np = bw * (y1 - y0);
  const std::size_t snp = std::size_t(np);
  float* raw = S.raw.data();
  float* feat = S.feat.data();
  float* fin = S.fin.data();  // 1: every feature finite, 0: not
  float* zp = S.z.data();     // accumulated illumination, 3 planar columns
  int* rows = S.rows.data();
  // Raw features and the illumination, planar, in one sweep over the block's rows; a
  // pixel with any non-finite feature is left out of the fit and its features read as
  // mid-range (0 after scaling). Fitted rows: finite features and a valid colour.
  int p = 0, W = 0;
  for (int y = y0; y < y1; ++y) {
    const std::size_t rb = std::size_t(y) * std::size_t(w) + std::size_t(x0);
    const float* nrow = nrm.data() + rb * std::size_t(nch);
    const float* prow = pos.data() + rb * std::size_t(pch);
    const float* irow = illum.data() + rb * 3;
    const float* vrow = valid + rb;
    int x = 0;
#ifdef MCR_FIT_GATHER_AVX2
    if ((!alb || (lay.albedo_luminance && alb->channels() == 3)) && !dep && pch == 3 && nch == 3 &&
        isa_at_least(Isa::Avx2)) {
      x = bw / 8 * 8;
      W = gather_row_avx2(nrow, prow, alb ? alb->data() + rb * 3 : nullptr, irow, vrow, x, p, snp, raw, fin, zp, rows,
                          W);
      p += x;
    }
#endif
    for (; x < bw; ++x, ++p) {
      const float* n = nrow + std::size_t(x) * std::size_t(nch);
      const float* q = prow + std::size_t(x) * std::size_t(pch);
      const float v[6] = {n[0], n[1], n[2], q[0], q[1], q[2]};
      float f = 0.0f;  // x - x: 0 for finite x, NaN otherwise
      for (int c = 0; c < 6; ++c) {
        raw[std::size_t(c) * snp + std::size_t(p)] = v[c];
        f += v[c] - v[c];
      }
      int k = 6;
      if (alb) {
        const float* a = alb->pixel(x0 + x, y);
        const int ac = alb->channels() - 1;
        if (lay.albedo_luminance) {
          const float t = albedo_luminance(a[0], a[std::min(1, ac)], a[std::min(2, ac)]);
          raw[std::size_t(k++) * snp + std::size_t(p)] = t;
          f += t - t;
        } else {
          for (int c = 0; c < 3; ++c, ++k) {
            const float t = a[std::min(c, ac)];
            raw[std::size_t(k) * snp + std::size_t(p)] = t;
            f += t - t;
          }
        }
      }
      if (dep) {
        const float t = dep->pixel(x0 + x, y)[0];
        raw[std::size_t(k) * snp + std::size_t(p)] = t;
        f += t - t;
      }
      const bool ok = f == 0.0f;
      fin[p] = ok ? 1.0f : 0.0f;
      for (int c = 0; c < 3; ++c) zp[std::size_t(c) * snp + std::size_t(p)] = irow[std::size_t(x) * 3 + std::size_t(c)];
      rows[W] = p;
      W += (ok && vrow[x] > 0.0f) ? 1 : 0;
    }
  }
  // Scaled to [-1, 1] over the block's finite pixels; a column constant within float
  // rounding is 0 (the constant column carries it).
  auto scale_column = [&](const float* src, float* dst) {
    float lo, hi;
    masked_min_max(src, fin, np, lo, hi);
    const double range = double(hi) - double(lo);
    if (!(range > 1e-5 * std::max(std::fabs(double(lo)), std::fabs(double(hi)))) || !(range > 1e-30) ||
        !std::isfinite(range)) {
      std::fill(dst, dst + np, 0.0f);
      return;
    }
    scale_masked(src, fin, np, lo, float(2.0 / range), dst);
  };
  std::fill(feat, feat + np, 1.0f);
  // Columns: 0 constant; 1..3 normal; 4..6 position; [7..9 position^2]; extras.
  // Columns of frame-wide constant passes (lay.dropped) are 0 here and left out of the QR.
  auto dropped = [&](int col) { return (lay.dropped >> col) & 1u; };
  for (int c = 0; c < R; ++c) {
    const int col = lay.column_of_raw(c);
    if (dropped(col)) std::fill(feat + std::size_t(col) * snp, feat + std::size_t(col + 1) * snp, 0.0f);
    else scale_column(raw + std::size_t(c) * snp, feat + std::size_t(col) * snp);
  }
  if (lay.squares)
    for (int c = 0; c < 3; ++c) {
      if (dropped(7 + c)) {
        std::fill(feat + std::size_t(7 + c) * snp, feat + std::size_t(8 + c) * snp, 0.0f);
        continue;
      }
      // Square of the scaled position: the same span as w^2 with w, better conditioned.
      float* sq = raw;  // raw column 0 is no longer needed: reuse as scratch
      const float* s0 = feat + std::size_t(4 + c) * snp;
      for (int i = 0; i < np; ++i) sq[i] = s0[i] * s0[i];
      scale_column(sq, feat + std::size_t(7 + c) * snp);
    }
  if (W == 0) {
    for (int y = y0; y < y1; ++y) {
      float* o = fitted.data() + (std::size_t(y) * std::size_t(w) + std::size_t(x0)) * 3;
      std::fill(o, o + std::size_t(bw) * 3, std::numeric_limits<float>::quiet_NaN());
    }
    return;
  }
  double* mat = S.mat.data();
  const std::size_t sW = std::size_t(W);
  std::uint64_t rng = seed * 0x2545F4914F6CDD1Dull ^ (std::uint64_t(frame_index_) << 32) ^
                      (std::uint64_t(by) * 65537u + std::uint64_t(bx) + 1);
  // Per-block noise stream: xorshift64 seeded by splitmix of (seed, frame, block),
  // two 32-bit uniforms in [-1, 1) per step (plenty for a regulariser).
  std::uint64_t xs = splitmix(rng) | 1u;
  const bool dense = W == np;  // every pixel fitted: rows[r] == r
  for (int r = 0; r < W; ++r) mat[r] = 1.0;  // no noise on the constant: a constant block stays exact
  // The noise goes on the fitted features only, never on the synthesis ones. The
  // stream is one xorshift64 sequence over the columns, ceil(W/2) steps per column
  // (low half to row r, high half to row r + 1; an odd last row takes the high half),
  // generated ahead in 4 interleaved lanes by jump-ahead (the same values).
  const double e31 = eps * (1.0 / 2147483648.0);
  const std::size_t hs = (sW + 1) / 2;
  const std::uint64_t* nz = nullptr;
  if (eps > 0) {
    const std::size_t steps = hs * std::size_t(M - 1);
    const std::size_t need = (steps + kNoiseGroup - 1) / kNoiseGroup * kNoiseGroup;
    if (S.noise.size() < need) S.noise.resize(need);
    xorshift_stream(xs, S.noise.data(), need);
    nz = S.noise.data();
  }
  // Step r >> 1 gives row r its low half (r even) or high half (r odd): on a
  // little-endian machine that is 32-bit word r of the stream, a loop the compiler
  // vectorises (int32 -> double conversions).
  typedef std::int32_t noise_word __attribute__((__may_alias__));
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "noise words assume little endian");
  const int even = W & ~1;
  // The fitted columns: all but the dropped ones, each with the noise of its own index.
  int fcol[32];
  int MK = 1;
  fcol[0] = 0;
  for (int m = 1; m < M; ++m)
    if (!dropped(m)) fcol[MK++] = m;
  for (int k = 1; k < MK; ++k) {
    const int m = fcol[k];
    double* col = mat + std::size_t(k) * sW;
    const float* fm = feat + std::size_t(m) * snp;
    const noise_word* q = nz ? reinterpret_cast<const noise_word*>(nz + std::size_t(m - 1) * hs) : nullptr;
    if (dense && q)
      for (int r = 0; r < even; ++r) col[r] = double(fm[r]) + e31 * double(q[r]);
    else if (dense)
      for (int r = 0; r < W; ++r) col[r] = double(fm[r]);
    else
      for (int r = 0; r < W; ++r) col[r] = double(fm[rows[r]]);
    if (q) {
      if (!dense)
        for (int r = 0; r < even; ++r) col[r] += e31 * double(q[r]);
      if (even < W) {  // odd last row: the high half of its step
        if (dense) col[even] = double(fm[even]);
        col[even] += e31 * double(q[even + 1]);
      }
    }
  }
  double zmin[3], zmax[3];
  for (int c = 0; c < 3; ++c) {
    double* col = mat + std::size_t(MK + c) * sW;
    const float* zc = zp + std::size_t(c) * snp;
    float zm = INFINITY, zx = -INFINITY;
    if (dense) {
      // 8 running minima and maxima (min and max do not depend on the order; NaN is
      // skipped either way), so the loop vectorises.
      float m8[8], x8[8];
      std::fill(m8, m8 + 8, INFINITY);
      std::fill(x8, x8 + 8, -INFINITY);
      int r = 0;
      for (; r + 8 <= W; r += 8)
        for (int l = 0; l < 8; ++l) {
          const float z = zc[r + l];
          col[r + l] = double(z);
          m8[l] = z < m8[l] ? z : m8[l];
          x8[l] = x8[l] < z ? z : x8[l];
        }
      for (int l = 0; l < 8; ++l) {
        zm = std::min(zm, m8[l]);
        zx = std::max(zx, x8[l]);
      }
      for (; r < W; ++r) {
        const float z = zc[r];
        col[r] = double(z);
        zm = std::min(zm, z);
        zx = std::max(zx, z);
      }
    } else {
      for (int r = 0; r < W; ++r) {
        const float z = zc[rows[r]];
        col[r] = double(z);
        zm = std::min(zm, z);
        zx = std::max(zx, z);
      }
    }
    zmin[c] = double(zm);
    zmax[c] = double(zx);
  }
  S.qr.factorize(mat, W, MK, 3);
  double alpha[3][32], ak[32];
  for (int c = 0; c < 3; ++c) {
    S.qr.solve(c, ak);
    std::fill(alpha[c], alpha[c] + M, 0.0);
    for (int k = 0; k < MK; ++k) alpha[c][fcol[k]] = ak[k];
  }
  // Synthesis with the noise-free features, the three channels in one sweep over each
  // 4-pixel chunk (sums in registers; per channel the same terms in the same order as
  // a channel-by-channel loop, a zero coefficient skipped).
  double* acc = S.acc.data();
  bool use[3][32];
  for (int c = 0; c < 3; ++c)
    for (int m = 1; m < M; ++m) use[c][m] = alpha[c][m] != 0.0;
  int i4 = 0;
  for (; i4 + 4 <= np; i4 += 4) {
    v4d s0 = v4d{} + alpha[0][0], s1 = v4d{} + alpha[1][0], s2 = v4d{} + alpha[2][0];
    for (int m = 1; m < M; ++m) {
      const v4d f = __builtin_convertvector(*reinterpret_cast<const v4f*>(feat + std::size_t(m) * snp + std::size_t(i4)), v4d);
      if (use[0][m]) s0 += alpha[0][m] * f;
      if (use[1][m]) s1 += alpha[1][m] * f;
      if (use[2][m]) s2 += alpha[2][m] * f;
    }
    *reinterpret_cast<v4d*>(acc + std::size_t(i4)) = s0;
    *reinterpret_cast<v4d*>(acc + snp + std::size_t(i4)) = s1;
    *reinterpret_cast<v4d*>(acc + 2 * snp + std::size_t(i4)) = s2;
  }
  for (int c = 0; c < 3; ++c) {
    double* ac = acc + std::size_t(c) * snp;
    for (int i = i4; i < np; ++i) ac[i] = alpha[c][0];
    for (int m = 1; m < M; ++m) {
      if (!use[c][m]) continue;
      const float* fm = feat + std::size_t(m) * snp;
      for (int i = i4; i < np; ++i) ac[i] += alpha[c][m] * double(fm[i]);
    }
  }
  const double zlo[3] = {std::min(0.0, zmin[0]), std::min(0.0, zmin[1]), std::min(0.0, zmin[2])};
  const double zhi[3] = {std::max(0.0, zmax[0]), std::max(0.0, zmax[1]), std::max(0.0, zmax[2])};
  for (int y = y0, i = 0; y < y1; ++y) {
    float* o = fitted.data() + (std::size_t(y) * std::size_t(w) + std::size_t(x0)) * 3;
    int x = 0;
    // 4 pixels at a time: the scalar loop below as vector selects (the same values).
    for (; x + 4 <= bw; x += 4, i += 4) {
      v4f out[3];
      for (int c = 0; c < 3; ++c) {
        const v4d a = *reinterpret_cast<const v4d*>(acc + std::size_t(c) * snp + std::size_t(i));
        v4d v = a < zlo[c] ? v4d{} + zlo[c] : a;  // std::max(a, zlo)
        if (clamp_max) v = zhi[c] < v ? v4d{} + zhi[c] : v;  // std::min(v, zhi)
        v4d cl = v < -kFloatMax ? v4d{} - kFloatMax : v;  // std::clamp(v, -max, max)
        cl = kFloatMax < cl ? v4d{} + kFloatMax : cl;
        const v4f f = __builtin_convertvector(cl, v4f);
        const v4f nan = v4f{} + std::numeric_limits<float>::quiet_NaN();
        out[c] = __builtin_convertvector((v - v) == 0.0, v4i) ? f : nan;  // finite: v - v == 0
      }
      float* op = o + std::size_t(x) * 3;
      for (int l = 0; l < 4; ++l) {
        op[3 * l] = out[0][l];
        op[3 * l + 1] = out[1][l];
        op[3 * l + 2] = out[2][l];
      }
    }
    for (; x < bw; ++x, ++i)
      for (int c = 0; c < 3; ++c) {
        // Radiance is not negative: no fit below min(0, the block's smallest input).
        // Nor above the block's largest input: an ill-conditioned fit extrapolating at
        // the pixels it was not fitted on (invalid ones, partial edge blocks) cannot
        // make a highlight brighter than anything it was given.
        double v = std::max(acc[std::size_t(c) * snp + std::size_t(i)], zlo[c]);
        if (clamp_max) v = std::min(v, zhi[c]);
        o[std::size_t(x) * 3 + std::size_t(c)] =
            std::isfinite(v) ? float(std::clamp(v, -kFloatMax, kFloatMax)) : std::numeric_limits<float>::quiet_NaN();
      }
  }
}
MCR_ISA_VERSIONS_AVX2(void, fit_block, (const FitJob& J, FitScratch& S, int b), (J, S, b))

}  // namespace

void BmfrFilter::fit_blocks(const Frame& frame, const Image& illum, const std::vector<float>& valid, Image& fitted,
                            int nthreads) {
  const int w = frame.width, h = frame.height;
  const int B = block_side(params_.get_int("block_size"), w, h);
  FeatureLayout lay = layout_of(params_.get_enum("features"));
  lay.albedo_luminance = !lay.albedo && params_.get_bool("albedo_luminance") && frame.find(Role::Albedo);
  const double eps = params_.get_float("epsilon");
  const std::uint64_t seed = std::uint64_t(params_.get_int("seed"));
  const bool clamp_max = params_.get_bool("fit_clamp");
  const Image& pos = frame.image(Role::Position, Prefer::Geometry);
  const Image& nrm = frame.image(Role::Normal, Prefer::Geometry);
  const Image* alb = lay.albedo || lay.albedo_luminance ? &frame.image(Role::Albedo) : nullptr;
  const Image* dep = lay.depth ? &frame.image(Role::Depth) : nullptr;
  std::vector<std::string> skipped;
  lay.dropped = constant_columns(lay, nrm, pos, alb, dep, nthreads, skipped);
  for (std::string& s : skipped) note("bmfr: " + s);

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
  FitJob job{w, h, B, ox, oy, nbx, R, M, pch, nch, lay, eps, seed, frame_index_, clamp_max, &pos, &nrm, alb, dep, &illum,
             valid.data(), &fitted};
  tbb::task_arena& arena = shared_arena(nthreads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, nblocks, 1), [&](const tbb::blocked_range<int>& range) {
      // Per thread, kept from frame to frame (a fresh scratch per frame was ~200 KB of
      // new pages per thread and frame).
      thread_local FitScratch S;
      // Grown only (block size and feature set may change between calls).
      auto grow = [](auto& v, std::size_t k) {
        if (v.size() < k) v.resize(k);
      };
      grow(S.raw, cap * std::size_t(R));
      grow(S.feat, cap * std::size_t(M));
      grow(S.fin, cap);
      grow(S.z, cap * 3);
      grow(S.rows, cap);
      grow(S.mat, cap * std::size_t(M + 3));
      grow(S.acc, cap * 3);
      for (int b = range.begin(); b != range.end(); ++b) {
        fit_block(job, S, b);
      }
    });
  });
}

}  // namespace mcr
