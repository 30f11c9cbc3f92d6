// Shirley et al.'s per-pixel reconstructions against the paper's own code (Appendices A and B,
// transcribed below as written, apart from A's blend ramp: see sweep_kernel.h), closed forms,
// and the layered path against the sorted sweep.
#include "filters/samples/sweep_kernel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

namespace mcr::sweep {
namespace {

// Samples of the (2r+1)^2 pixels around a centre pixel, ns per pixel, uniform positions.
// depth_of(dx, dy, u) gives depth; diameter_of(z) the diameter.
template <class Depth, class Diameter>
std::vector<Sample> neighbourhood(int r, int ns, unsigned seed, Depth depth_of, Diameter diameter_of) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Sample> out;
  for (int py = -r; py <= r; ++py)
    for (int px = -r; px <= r; ++px)
      for (int k = 0; k < ns; ++k) {
        Sample s;
        s.dx = float(px) + u(rng) - 0.5f;
        s.dy = float(py) + u(rng) - 0.5f;
        s.z = depth_of(s.dx, s.dy, u(rng));
        s.d = diameter_of(s.z);
        s.q = 1.0f / float(ns);
        for (float& c : s.rgb) c = u(rng) * 2.0f;
        out.push_back(s);
      }
  return out;
}

// --- The paper's code, as printed (float, qsort by z) ---------------------------------------
struct PaperSample {
  float x, y, z, denoisingblur;
  float color[3];
};
int compare_sample_z(const void* a, const void* b) {
  const float za = static_cast<const PaperSample*>(a)->z, zb = static_cast<const PaperSample*>(b)->z;
  return za < zb ? -1 : (za > zb ? 1 : 0);
}
float paper_box(float x, float radius) { return std::fabs(x) < radius ? 0.5f / radius : 0; }

std::vector<PaperSample> to_paper(const std::vector<Sample>& v) {
  std::vector<PaperSample> s;
  for (const Sample& a : v) s.push_back({a.dx, a.dy, a.z, a.d, {a.rgb[0], a.rgb[1], a.rgb[2]}});
  return s;
}

// Appendix A; the only change: blend = clamp((D - 1) / 4) (this project's ramp) for (D - 1) / 5.
std::vector<float> appendix_a(std::vector<PaperSample> s, float ns) {
  const int N = int(s.size());
  qsort(s.data(), std::size_t(N), sizeof(s[0]), compare_sample_z);
  float cov_1 = 0.0f, cov_5 = 0.0f, cov = 0.0f;
  float sum[3] = {0, 0, 0};
  for (int i = 0; i < N; i++) {
    float D = s[i].denoisingblur;
    float w_1 = (1 / ns) * paper_box(s[i].x, 0.5f) * paper_box(s[i].y, 0.5f);
    float w_5 = (1 / ns) * paper_box(s[i].x, 2.5f) * paper_box(s[i].y, 2.5f);
    float w;
    float blend = std::clamp((D - 1) / 4, 0.0f, 1.0f);
    w = blend * (w_5 * (1 - cov_1) + w_1 * cov_1);
    cov_5 += blend * (w_5 * (1 - cov_1));
    w += (1 - blend) * (w_1 * (1 - cov_5) + w_5 * cov_5);
    cov_1 += (1 - blend) * (w_1 * (1 - cov_5));
    cov += w;
    for (int c = 0; c < 3; ++c) sum[c] += w * s[i].color[c];
  }
  return {sum[0] / cov, sum[1] / cov, sum[2] / cov};
}

// Appendix B, as printed.
std::vector<float> appendix_b(std::vector<PaperSample> s, float ns) {
  const int N = int(s.size());
  qsort(s.data(), std::size_t(N), sizeof(s[0]), compare_sample_z);
  float cov_1 = 0.0f, cov_3 = 0.0f, cov_5 = 0.0f, cov_7 = 0.0f, cov = 0.0f;
  float sum[3] = {0, 0, 0};
  for (int i = 0; i < N; i++) {
    float D = s[i].denoisingblur;
    float w_1 = (1 / ns) * paper_box(s[i].x, 0.5f) * paper_box(s[i].y, 0.5f);
    float w_3 = (1 / ns) * paper_box(s[i].x, 1.5f) * paper_box(s[i].y, 1.5f);
    float w_5 = (1 / ns) * paper_box(s[i].x, 2.5f) * paper_box(s[i].y, 2.5f);
    float w_7 = (1 / ns) * paper_box(s[i].x, 3.5f) * paper_box(s[i].y, 3.5f);
    float w;
    if (D > 7) {
      w = w_7 * (1 - cov_1 - cov_3 - cov_5) + w_1 * cov_1 + w_3 * cov_3 + w_5 * cov_5;
      cov_7 += w_7 * (1 - cov_1 - cov_3 - cov_5);
    } else if (D > 5) {
      w = w_5 * (1 - cov_1 - cov_3 - cov_7) + w_1 * cov_1 + w_3 * cov_3 + w_7 * cov_7;
      cov_5 += w_5 * (1 - cov_1 - cov_3 - cov_7);
    } else if (D > 3) {
      w = w_3 * (1 - cov_1 - cov_5 - cov_7) + w_1 * cov_1 + w_5 * cov_5 + w_7 * cov_7;
      cov_3 += w_3 * (1 - cov_1 - cov_5 - cov_7);
    } else {
      w = w_1 * (1 - cov_3 - cov_5 - cov_7) + w_3 * cov_3 + w_5 * cov_5 + w_7 * cov_7;
      cov_1 += w_1 * (1 - cov_3 - cov_5 - cov_7);
    }
    cov += w;
    for (int c = 0; c < 3; ++c) sum[c] += w * s[i].color[c];
  }
  return {sum[0] / cov, sum[1] / cov, sum[2] / cov};
}
// ---------------------------------------------------------------------------------------------

// A defocused scene around one pixel: a near occluder over half the neighbourhood, a surface
// near the focus, a far background; diameters grow away from the focus (a circle of confusion).
float coc(float z) { return 1.5f + 9.0f * std::fabs(z - 4.0f) / z; }
float scene_depth(float dx, float dy, float u) {
  if (dx + 0.3f * dy < -0.5f) return 1.5f + 0.5f * u;  // near, blurred
  if (dy > 1.2f) return 30.0f + u;                      // far, blurred
  return 3.8f + 0.4f * u;                               // in focus
}

TEST(SweepKernel, AppendixABlendMatchesThePapersCode) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    auto v = neighbourhood(2, 16, seed, scene_depth, coc);
    float got[3];
    Options o;  // two scales, 1 and 5, blended
    ASSERT_TRUE(sweep(v.data(), int(v.size()), o, got));
    const auto want = appendix_a(to_paper(v), 16.0f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 2e-5f * std::max(1.0f, std::fabs(want[c]))) << seed;
  }
}

TEST(SweepKernel, AppendixBFourScalesMatchThePapersCode) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    auto v = neighbourhood(3, 16, seed, scene_depth, coc);
    float got[3];
    Options o;
    o.scales = Scales::even(4, 7);
    o.blend = false;
    ASSERT_TRUE(sweep(v.data(), int(v.size()), o, got));
    const auto want = appendix_b(to_paper(v), 16.0f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 2e-5f * std::max(1.0f, std::fabs(want[c]))) << seed;
  }
}

TEST(SweepKernel, ScalesAndAssignment) {
  EXPECT_EQ(Scales::even(2, 5).widths, (std::vector<float>{1, 5}));
  EXPECT_EQ(Scales::even(4, 7).widths, (std::vector<float>{1, 3, 5, 7}));
  const Scales b = Scales::even(4, 7);
  // Appendix B: D > 7 -> 7, D > 5 -> 5, D > 3 -> 3, else 1.
  EXPECT_EQ(assign(8, b, false).k, 3);
  EXPECT_EQ(assign(7, b, false).k, 2);
  EXPECT_EQ(assign(5.5f, b, false).k, 2);
  EXPECT_EQ(assign(4, b, false).k, 1);
  EXPECT_EQ(assign(3, b, false).k, 0);
  EXPECT_EQ(assign(0.2f, b, false).k, 0);
  // Blending is continuous across every scale boundary.
  for (float d = 0.5f; d < 9.0f; d += 0.01f) {
    const Assign lo = assign(d, b, true), hi = assign(d + 0.01f, b, true);
    const float a = float(lo.k) + lo.t, c = float(hi.k) + hi.t;
    EXPECT_LE(std::fabs(c - a), 0.01f / 2.0f + 1e-4f) << d;
  }
  EXPECT_EQ(assign(3.0f, b, true), (Assign{1, 0.0f}));
  EXPECT_EQ(assign(4.0f, b, true), (Assign{1, 0.5f}));
  EXPECT_EQ(assign(20.0f, b, true), (Assign{3, 0.0f}));
}

TEST(SweepKernel, OneScaleIsItsBoxWithoutSorting) {
  // Every sample sharp: the 1-pixel box mean of the centre pixel, no sort.
  auto v = neighbourhood(2, 16, 3, [](float, float, float u) { return 4.0f + u; }, [](float) { return 1.0f; });
  float got[3];
  bool sorted = true;
  ASSERT_TRUE(sweep(v.data(), int(v.size()), Options{}, got, &sorted));
  EXPECT_FALSE(sorted);
  double want[3] = {0, 0, 0};
  int n = 0;
  for (const Sample& s : v)
    if (std::fabs(s.dx) < 0.5f && std::fabs(s.dy) < 0.5f) {
      ++n;
      for (int c = 0; c < 3; ++c) want[c] += s.rgb[c];
    }
  ASSERT_EQ(n, 16);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c] / n, 1e-5);
  // Every sample blurred by 9: the 5x5 box mean (the widest scale), still no sort.
  for (Sample& s : v) s.d = 9;
  ASSERT_TRUE(sweep(v.data(), int(v.size()), Options{}, got, &sorted));
  EXPECT_FALSE(sorted);
  for (int c = 0; c < 3; ++c) want[c] = 0;
  for (const Sample& s : v)
    for (int c = 0; c < 3; ++c) want[c] += s.rgb[c];
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c] / double(v.size()), 1e-5);
}

TEST(SweepKernel, SharpPixelInFrontHidesTheBlurredBackground) {
  // Artifact 2: the centre pixel fully covered by a sharp surface in front; blurred samples
  // behind it in the whole neighbourhood. Alg 2 gives the sharp surface alone.
  std::vector<Sample> v;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int py = -2; py <= 2; ++py)
    for (int px = -2; px <= 2; ++px)
      for (int k = 0; k < 16; ++k) {
        Sample s;
        s.dx = float(px) + u(rng) - 0.5f;
        s.dy = float(py) + u(rng) - 0.5f;
        s.q = 1.0f / 16;
        const bool centre = px == 0 && py == 0;
        s.z = centre ? 1.0f : 10.0f;
        s.d = centre ? 1.0f : 8.0f;
        s.rgb[0] = s.rgb[1] = s.rgb[2] = centre ? 0.25f : 4.0f;
        v.push_back(s);
      }
  Options o;
  o.blend = false;
  float got[3];
  ASSERT_TRUE(sweep(v.data(), int(v.size()), o, got));
  EXPECT_NEAR(got[0], 0.25f, 1e-6f);
  // Alg 1B lets the background leak in (the paper's artifact 2).
  ASSERT_TRUE(splat(v.data(), int(v.size()), true, 5, got));
  EXPECT_GT(got[0], 1.0f);
}

// Artifact 1's case: a blurred occluder (12 of 16 samples in every pixel, diameter 9) in front
// of a sharp surface (4 of 16, diameter 1) over a 5x5 neighbourhood, scales 1 and 5 unblended.
// Closed form of the sweep: the 300 occluder samples come first, each with weight 1/400
// (coverage 0.75 of the wide scale); then every surface sample gets w_1 * 0.25 + w_5 * 0.75:
// (0.75 / 400) outside the centre pixel and (0.25 / 16 + 0.75 / 400) inside it.
struct Occluded {
  std::vector<Sample> v;
  std::vector<double> front, back, centre;  // colours (channel 0)
};
Occluded occluded_scene() {
  Occluded o;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int py = -2; py <= 2; ++py)
    for (int px = -2; px <= 2; ++px)
      for (int k = 0; k < 16; ++k) {
        Sample s;
        s.dx = float(px) + u(rng) - 0.5f;
        s.dy = float(py) + u(rng) - 0.5f;
        s.q = 1.0f / 16;
        const bool occluder = k < 12;
        s.z = occluder ? 1.0f : 10.0f;
        s.d = occluder ? 9.0f : 1.0f;
        s.rgb[0] = s.rgb[1] = s.rgb[2] = occluder ? 1.0f + u(rng) : 3.0f + u(rng);
        (occluder ? o.front : (px == 0 && py == 0 ? o.centre : o.back)).push_back(s.rgb[0]);
        o.v.push_back(s);
      }
  return o;
}

double occluded_closed_form(const Occluded& o, double p) {
  const double wf = std::pow(1.0 / 400, p), wb = std::pow(0.75 / 400, p), wc = std::pow(0.25 / 16 + 0.75 / 400, p);
  double w = 0, c = 0;
  for (double x : o.front) w += wf, c += wf * x;
  for (double x : o.back) w += wb, c += wb * x;
  for (double x : o.centre) w += wc, c += wc * x;
  return c / w;
}

TEST(SweepKernel, BlurredOccluderWidensTheSharpSurfaceBehindIt) {
  Occluded o = occluded_scene();
  ASSERT_EQ(o.front.size(), 300u);
  ASSERT_EQ(o.centre.size(), 4u);
  Options opt;
  opt.blend = false;
  float got[3];
  ASSERT_TRUE(sweep(o.v.data(), int(o.v.size()), opt, got));
  EXPECT_NEAR(got[0], occluded_closed_form(o, 1.0), 1e-5);
}

TEST(SweepKernel, PowerBlursLess) {
  // fig. 5: each w_i^1.3: the centre pixel's surface samples (the largest weights) gain.
  Occluded o = occluded_scene();
  Options opt;
  opt.blend = false;
  opt.power = 1.3f;
  float got[3];
  ASSERT_TRUE(sweep(o.v.data(), int(o.v.size()), opt, got));
  EXPECT_NEAR(got[0], occluded_closed_form(o, 1.3), 1e-5);
  EXPECT_NE(occluded_closed_form(o, 1.3), occluded_closed_form(o, 1.0));
}

TEST(SweepKernel, LayeredEqualsSortedOnDefocus) {
  for (int K : {1, 2, 3, 4}) {
    for (float p : {1.0f, 1.3f}) {
      for (unsigned seed = 1; seed <= 10; ++seed) {
        auto v = neighbourhood(3, 16, seed * 7 + unsigned(K), scene_depth, coc);
        Options o;
        o.scales = Scales::even(K, 7);
        o.blend = false;
        o.power = p;
        float a[3], b[3];
        ASSERT_TRUE(layered(v.data(), int(v.size()), o, 4.0f, a));
        ASSERT_TRUE(sweep(v.data(), int(v.size()), o, b));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-5f * std::max(1.0f, std::fabs(b[c]))) << K << " " << p;
      }
    }
  }
}

TEST(SweepKernel, SplatAlgorithm1IsThePixelMean) {
  auto v = neighbourhood(2, 16, 13, scene_depth, coc);
  float got[3];
  ASSERT_TRUE(splat(v.data(), int(v.size()), false, 5, got));
  double want = 0;
  for (const Sample& s : v)
    if (std::fabs(s.dx) < 0.5f && std::fabs(s.dy) < 0.5f) want += s.rgb[1];
  EXPECT_NEAR(got[1], want / 16.0, 1e-5);
}

TEST(SweepKernel, NoWeightGivesZeroAndFalse) {
  std::vector<Sample> v(3);
  for (Sample& s : v) s.dx = 10;  // outside every box
  float got[3] = {1, 1, 1};
  EXPECT_FALSE(sweep(v.data(), 3, Options{}, got));
  EXPECT_EQ(got[0], 0.0f);
  EXPECT_FALSE(sweep(nullptr, 0, Options{}, got));
  EXPECT_FALSE(layered(v.data(), 3, Options{Scales::even(2, 5), false, 1}, 4.0f, got));
  EXPECT_FALSE(splat(v.data(), 3, true, 5, got));
}

}  // namespace
}  // namespace mcr::sweep
