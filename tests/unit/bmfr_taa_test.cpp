// BMFR's TAA stage on its own (temporal_antialias): against the scalar oracle of
// bmfr_taa_oracle.h, properties of the clip and the blend, the fallbacks to the current
// frame, pinned bits for non-finite inputs, and the generic and AVX2 builds bit for bit.
// Every check runs on each instruction-set build the CPU has.
#include "filters/temporal/bmfr_taa.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "bmfr_taa_oracle.h"
#include "util/isa.h"

namespace mcr {
namespace {

using namespace testutil;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

Planar random_frame(int w, int h, unsigned seed, float lo, float hi) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  Planar f(w, h);
  for (float& x : f.v) x = u(g);
  return f;
}

// Where the previous frame had pixel (x, y): prev(x, y, px, py). The inside bits are set
// the way the reprojection sets them (tap k of the bilinear footprint in the frame).
Reprojection reprojection(int w, int h, const std::function<void(int, int, float&, float&)>& prev) {
  Reprojection r;
  r.width = w;
  r.height = h;
  const std::size_t n = std::size_t(w) * std::size_t(h);
  r.prev_x.resize(n);
  r.prev_y.resize(n);
  r.taps.assign(n, 15);
  r.inside.resize(n);
  r.has_history = true;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
      float px = float(x), py = float(y);
      prev(x, y, px, py);
      const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
      std::uint8_t in = 0;
      for (int k = 0; k < 4; ++k) {
        const int tx = x0 + (k & 1), ty = y0 + (k >> 1);
        if (tx >= 0 && ty >= 0 && tx < w && ty < h) in |= std::uint8_t(1u << k);
      }
      r.prev_x[i] = px;
      r.prev_y[i] = py;
      r.inside[i] = in;
    }
  return r;
}

Reprojection static_camera(int w, int h) {
  return reprojection(w, h, [](int, int, float&, float&) {});
}

Planar run_taa(const TaaSettings& s, const Reprojection& rep, const Planar& cur, const Planar& hist, int nthreads = 1) {
  Planar next(cur.w, cur.h, -1.0f);
  temporal_antialias(s, rep, cur.v.data(), hist.v.data(), next.v.data(), nthreads);
  return next;
}

TaaSettings settings(bool ycocg, bool catmull_rom, float alpha = 0.2f, float gamma = 1.0f) {
  TaaSettings s;
  s.ycocg = ycocg;
  s.catmull_rom = catmull_rom;
  s.alpha = alpha;
  s.gamma = gamma;
  return s;
}

// The levels this CPU runs (the AVX-512 level runs the AVX2 build).
std::vector<Isa> levels() {
  std::vector<Isa> l;
  for (Isa level : {Isa::Generic, Isa::Avx2, Isa::Avx512})
    if (int(level) <= int(best_isa())) l.push_back(level);
  return l;
}

// fn(ycocg, catmull_rom) for every clip box and history lookup, on every build.
void for_each_build_and_setting(const std::function<void(bool, bool)>& fn) {
  for (Isa level : levels()) {
    const ScopedIsa use(level);
    for (bool ycocg : {true, false})
      for (bool cubic : {true, false}) {
        SCOPED_TRACE(std::string(isa_name(level)) + (ycocg ? " ycocg" : " rgb") +
                     (cubic ? " catmull_rom" : " bilinear"));
        fn(ycocg, cubic);
      }
  }
}

void expect_near_oracle(const Planar& got, const Planar& want, double tol) {
  int bad = 0;
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < got.h; ++y)
      for (int x = 0; x < got.w; ++x) {
        const double g = got.at(c, x, y), e = want.at(c, x, y);
        if (!(std::fabs(g - e) <= tol * std::max(1.0, std::fabs(e))) && bad++ < 5)
          ADD_FAILURE() << "channel " << c << " pixel " << x << "," << y << ": " << g << " vs oracle " << e;
      }
  EXPECT_EQ(bad, 0);
}

// The 3x3 mean of every pixel (border pixels repeated): inside every clipping box.
Planar neighbourhood_mean(const Planar& f) {
  Planar m(f.w, f.h);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < f.h; ++y)
      for (int x = 0; x < f.w; ++x) {
        double s = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) s += f.at(c, std::clamp(x + dx, 0, f.w - 1), std::clamp(y + dy, 0, f.h - 1));
        m.at(c, x, y) = float(s / 9);
      }
  return m;
}

// Current frame in [0, 1]; history: on a quarter of the pixels the current frame's 3x3
// mean, elsewhere anything in [-0.5, 2] (mostly outside the box).
struct Inputs {
  Planar cur, hist;
};
Inputs mixed_inputs(int w, int h, unsigned seed) {
  Inputs in{random_frame(w, h, seed, 0.0f, 1.0f), random_frame(w, h, seed + 1, -0.5f, 2.0f)};
  const Planar mean = neighbourhood_mean(in.cur);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if ((x + 3 * y) % 4 == 0)
        for (int c = 0; c < 3; ++c) in.hist.at(c, x, y) = mean.at(c, x, y);
  return in;
}

// 37 = 4 * 9 + 1 = 8 * 4 + 5 columns: every build has a partly filled last vector.
constexpr int kW = 37, kH = 13;

TEST(BmfrTaa, StaticCameraMatchesTheOracle) {
  const Inputs in = mixed_inputs(kW, kH, 11);
  const Reprojection rep = static_camera(kW, kH);
  for_each_build_and_setting([&](bool ycocg, bool cubic) {
    const TaaSettings s = settings(ycocg, cubic, 0.3f, 0.8f);
    OracleStats st;
    const Planar want = oracle(s, rep, in.cur, in.hist, &st);
    expect_near_oracle(run_taa(s, rep, in.cur, in.hist), want, 2e-6);
    // Both branches of the clip are taken often.
    EXPECT_GT(st.clipped, kW * kH / 3);
    EXPECT_GT(st.inside_box, kW * kH / 5);
    EXPECT_EQ(st.no_history, 0);
  });
}

TEST(BmfrTaa, MovingCameraMatchesTheOracle) {
  // Per-pixel motion up to 2.5 pixels: interior Catmull-Rom samples, samples whose taps
  // are clamped at the border, samples outside the frame, and some pixels whose taps the
  // reprojection found outside.
  const Inputs in = mixed_inputs(kW, kH, 21);
  std::mt19937 g(5);
  std::uniform_real_distribution<float> m(-2.5f, 2.5f);
  Reprojection rep = reprojection(kW, kH, [&](int, int, float& px, float& py) {
    px += m(g);
    py += m(g);
  });
  for (std::size_t i = 0; i < rep.inside.size(); i += 17) rep.inside[i] = 0;
  for_each_build_and_setting([&](bool ycocg, bool cubic) {
    const TaaSettings s = settings(ycocg, cubic, 0.2f, 1.3f);
    OracleStats st;
    const Planar want = oracle(s, rep, in.cur, in.hist, &st);
    expect_near_oracle(run_taa(s, rep, in.cur, in.hist, 2), want, 1e-5);
    EXPECT_GT(st.no_history, 20);
    EXPECT_GT(st.clipped, kW * kH / 3);
  });
}

TEST(BmfrTaa, HistoryInsideTheBoxIsBlendedWithTaaAlpha) {
  // The history is the 3x3 mean of the current frame, inside every box: nothing is
  // clipped and the output is history + alpha (current - history). With the RGB box the
  // static-camera lookup returns the history exactly and no conversion rounds: the same
  // float expression, bit for bit.
  const int w = 19, h = 7;
  const Planar cur = random_frame(w, h, 31, 0.0f, 1.0f), hist = neighbourhood_mean(cur);
  const Reprojection rep = static_camera(w, h);
  for_each_build_and_setting([&](bool ycocg, bool cubic) {
    for (float alpha : {0.2f, 0.5f, 1.0f}) {
      const Planar got = run_taa(settings(ycocg, cubic, alpha), rep, cur, hist);
      for (std::size_t i = 0; i < got.v.size(); ++i) {
        const float want = hist.v[i] + alpha * (cur.v[i] - hist.v[i]);
        if (ycocg)
          ASSERT_NEAR(got.v[i], want, 1e-6f) << i << " alpha " << alpha;
        else
          ASSERT_EQ(got.v[i], want) << i << " alpha " << alpha;
      }
    }
  });
}

TEST(BmfrTaa, HistoryOutsideTheBoxIsPulledOntoIt) {
  // A history far from the current frame. RGB box: each channel clamped to the 3x3
  // min/max. YCoCg box: moved towards the box centre along the line to it (its hue
  // kept) until it touches the box. The clipped history is read back from the blend.
  const int w = 21, h = 9;
  const Planar cur = random_frame(w, h, 41, 0.2f, 0.6f);
  Planar hist(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      hist.at(0, x, y) = 3.0f + 0.1f * float(x % 5);
      hist.at(1, x, y) = 1.8f;
      hist.at(2, x, y) = -0.4f - 0.2f * float(y % 3);
    }
  const Reprojection rep = static_camera(w, h);
  const float alpha = 0.5f;
  for_each_build_and_setting([&](bool ycocg, bool cubic) {
    const Planar got = run_taa(settings(ycocg, cubic, alpha, 1.0f), rep, cur, hist);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        Rgb k;  // the clipped history: out = k + alpha (cur - k)
        for (int c = 0; c < 3; ++c) k.c[c] = (got.at(c, x, y) - alpha * cur.at(c, x, y)) / (1 - alpha);
        const Box b = clip_box(cur, x, y, ycocg, 1.0);
        if (!ycocg) {
          for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(k.c[c], std::clamp(double(hist.at(c, x, y)), b.lo.c[c], b.hi.c[c]), 1e-6) << x << "," << y;
          continue;
        }
        const Rgb q = to_ycocg(k), hq = to_ycocg(pixel(hist, x, y));
        double on_surface = 0, t[3];
        for (int c = 0; c < 3; ++c) {
          const double centre = (b.hi.c[c] + b.lo.c[c]) / 2, extent = (b.hi.c[c] - b.lo.c[c]) / 2;
          on_surface = std::max(on_surface, std::fabs(q.c[c] - centre) / extent);
          t[c] = (q.c[c] - centre) / (hq.c[c] - centre);  // the same fraction of the way on every axis
        }
        ASSERT_NEAR(on_surface, 1.0, 1e-4) << x << "," << y;
        ASSERT_GT(t[0], 0.0);
        ASSERT_LT(t[0], 1.0);
        ASSERT_NEAR(t[1], t[0], 1e-4) << x << "," << y;
        ASSERT_NEAR(t[2], t[0], 1e-4) << x << "," << y;
      }
  });
}

TEST(BmfrTaa, PixelsWithoutAUsableHistoryKeepTheCurrentValue) {
  // The output is the current value, bit for bit, where the pixel has no tap inside the
  // frame, where its sample lies outside the frame, where the sample is NaN (in that
  // channel; in every channel with the YCoCg box, which mixes them), and where the blend
  // leaves the float range. Everywhere else it is finite; a NaN of the current frame
  // stays in its own pixel and channel.
  const int w = 23, h = 6;
  Planar cur = random_frame(w, h, 51, 0.0f, 1.0f);
  Planar hist = random_frame(w, h, 52, 0.0f, 1.0f);
  Reprojection rep = static_camera(w, h);
  auto idx = [&](int x, int y) { return std::size_t(y) * std::size_t(w) + std::size_t(x); };
  rep.inside[idx(3, 1)] = 0;
  rep.prev_x[idx(20, 2)] = -0.75f;  // left of the frame: bilinear has a tap, Catmull-Rom none
  rep.inside[idx(20, 2)] = 2;       // only tap (x0 + 1, y0) = (0, 2) inside
  hist.at(1, 9, 3) = kNaN;
  cur.at(0, 6, 4) = kNaN;
  // R of (17, 1): current 3e38, history -3e38, inside the RGB box (its neighbour has
  // -3e38): history + alpha (current - history) overflows.
  cur.at(0, 17, 1) = 3e38f;
  cur.at(0, 18, 1) = -3e38f;
  hist.at(0, 17, 1) = -3e38f;
  for_each_build_and_setting([&](bool ycocg, bool cubic) {
    const Planar got = run_taa(settings(ycocg, cubic, 0.25f), rep, cur, hist);
    auto same = [&](int c, int x, int y) {
      const float g = got.at(c, x, y), e = cur.at(c, x, y);
      return std::memcmp(&g, &e, sizeof g) == 0;
    };
    for (int c = 0; c < 3; ++c) {
      EXPECT_TRUE(same(c, 3, 1)) << c;
      if (cubic) EXPECT_TRUE(same(c, 20, 2)) << c;
      if (ycocg || c == 1) EXPECT_TRUE(same(c, 9, 3)) << c;
    }
    EXPECT_TRUE(same(0, 6, 4));
    if (!ycocg) EXPECT_TRUE(same(0, 17, 1));
    if (!cubic) EXPECT_FALSE(same(0, 20, 2));  // the bilinear sample: its one tap inside
    if (!ycocg) EXPECT_FALSE(same(0, 9, 3));   // the NaN was in G only
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c)
          if (std::isfinite(cur.at(c, x, y)))
            ASSERT_TRUE(std::isfinite(got.at(c, x, y))) << x << "," << y << " channel " << c;
  });
}

TEST(BmfrTaa, WritesTheRoiOfTheOutputFromTheNextHistory) {
  const Inputs in = mixed_inputs(kW, kH, 61);
  const Reprojection rep = static_camera(kW, kH);
  const TaaSettings s = settings(true, true);
  const Planar next = run_taa(s, rep, in.cur, in.hist);
  Planar next2(kW, kH);
  Image out(kW, kH, 3, -5.0f);
  const Roi roi{4, 3, 30, 11};
  temporal_antialias(s, rep, in.cur.v.data(), in.hist.v.data(), next2.v.data(), 2, &out, roi);
  EXPECT_EQ(next2.v, next.v);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) {
        const bool inside = x >= roi.x0 && x < roi.x1 && y >= roi.y0 && y < roi.y1;
        ASSERT_EQ(out.at(x, y, c), inside ? next.at(c, x, y) : -5.0f) << x << "," << y;
      }
}

// Stress values: NaN, +-inf, near the float range, signed zeros, tiny, among ordinary
// ones. A portable generator (xorshift32), so that the pinned hashes below hold with any
// standard library.
struct Stress {
  std::uint32_t s = 2463534242u;
  std::uint32_t next() {
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    return s;
  }
  float unit() { return float(next() >> 8) * (1.0f / 16777216.0f); }  // [0, 1)
  float value(float scale) {
    const float special[] = {kNaN, kInf, -kInf, 3e38f, -3e38f, 0.0f, -0.0f, 1e-30f};
    const std::uint32_t r = next();
    return r % 16 == 0 ? special[(r >> 4) % 8] : scale * (unit() - 0.2f);
  }
  // Current and history frames of stress values, motion up to 3 pixels.
  void fill(Planar& cur, Planar& hist, Reprojection& rep) {
    for (float& v : cur.v) v = value(1.5f);
    for (float& v : hist.v) v = value(3.0f);
    rep = reprojection(cur.w, cur.h, [&](int, int, float& px, float& py) {
      px += 6 * unit() - 3;
      py += 6 * unit() - 3;
    });
  }
};

std::uint64_t fnv1a(const std::vector<float>& v) {
  std::uint64_t h = 1469598103934665603ull;
  for (float f : v) {
    std::uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    for (int k = 0; k < 4; ++k) h = (h ^ ((b >> (8 * k)) & 0xffu)) * 1099511628211ull;
  }
  return h;
}

TEST(BmfrTaa, StressInputsKeepThePinnedBits) {
  // With NaN and infinities, which operand a min, max or clamp returns decides the bits
  // (the oracle above has finite inputs only). Pinned to what the separate SSE2 and AVX2
  // loops gave before the TAA became one source (0f526db), on both builds.
  const int w = 29, h = 9;
  Planar cur(w, h), hist(w, h);
  Reprojection rep;
  Stress().fill(cur, hist, rep);
  const std::uint64_t pinned[2][2] = {{0xa44bb35afdac42c2ull, 0x470da703f172b67bull},   // rgb: catmull_rom, bilinear
                                      {0x990b3eb44669c66aull, 0xe83931596e9794d7ull}};  // ycocg
  for_each_build_and_setting([&](bool ycocg, bool cubic) {
    EXPECT_EQ(fnv1a(run_taa(settings(ycocg, cubic, 0.2f, 0.7f), rep, cur, hist).v), pinned[ycocg][cubic ? 0 : 1]);
  });
}

TEST(BmfrTaa, GenericAndAvx2BuildsGiveTheSameBits) {
  if (best_isa() < Isa::Avx2) GTEST_SKIP() << "no AVX2 on this CPU";
  // Stress values, every setting, widths below, at and past both vector widths.
  Stress g;
  int compared = 0;
  for (int w : {1, 3, 4, 5, 7, 8, 9, 12, 16, 17, kW})
    for (int h : {1, 2, 5}) {
      Planar cur(w, h), hist(w, h);
      Reprojection rep;
      g.fill(cur, hist, rep);
      for (bool ycocg : {true, false})
        for (bool cubic : {true, false})
          for (float gamma : {0.3f, 1.0f}) {
            const TaaSettings s = settings(ycocg, cubic, gamma < 1 ? 0.2f : 1.0f, gamma);
            Planar a = [&] {
              const ScopedIsa use(Isa::Generic);
              return run_taa(s, rep, cur, hist);
            }();
            Planar b = [&] {
              const ScopedIsa use(Isa::Avx2);
              return run_taa(s, rep, cur, hist, 2);
            }();
            ASSERT_EQ(std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(float)), 0)
                << w << "x" << h << (ycocg ? " ycocg" : " rgb") << (cubic ? " catmull_rom" : " bilinear") << " gamma "
                << gamma;
            ++compared;
          }
    }
  EXPECT_EQ(compared, 11 * 3 * 8);
}

}  // namespace
}  // namespace mcr
