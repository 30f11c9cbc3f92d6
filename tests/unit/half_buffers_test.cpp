// io/half_buffers: the mean and the variance pass of two half buffers, against known noise
// and against the sample renders' halves, their 16-spp file and their reference.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <random>

#include "feature_filter_testutil.h"
#include "io/deep_writer.h"
#include "io/frame_reader.h"
#include "io/half_buffers.h"
#include "io/sample_manifest.h"
#include "kernels/noise_scale.h"
#include "util/error.h"

namespace mcr {
namespace {

TEST(HalfBuffers, MeanAndVarianceOfTheMeanOnKnownNoise) {
  const int w = 96, h = 64;
  const double s = 0.2;  // per half
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, float(s));
  Image a(w, h, 4, 1.0f), b(w, h, 4, 1.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = 0.5f + 0.01f * float(x);
        a.at(x, y, c) = v + noise(rng);
        b.at(x, y, c) = v + noise(rng);
      }
  Frame fa = testutil::colour_frame(a), fb = testutil::colour_frame(b);
  fa.path = "a.exr";
  fb.path = "b.exr";
  const Frame f = combine_halves(fa, fb);
  const Image& m = f.image(Role::Colour);
  const Image& v = f.image(Role::Variance);
  double mean_v = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(m.at(x, y, c), 0.5f * a.at(x, y, c) + 0.5f * b.at(x, y, c));
        mean_v += v.at(x, y, c);
      }
      EXPECT_EQ(m.at(x, y, 3), 1.0f);  // alpha from the first
    }
  mean_v /= 3.0 * w * h;
  EXPECT_NEAR(mean_v / (s * s / 2), 1.0, 0.05);  // the variance of the mean of two halves
  Frame small = testutil::colour_frame(Image(10, 10, 3));
  small.path = "small.exr";
  try {
    combine_halves(fa, small);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::SizeMismatch);
    EXPECT_NE(std::string(e.what()).find("small.exr"), std::string::npos);
  }
}

// The feature passes a renderer accumulates over the samples are the halves' mean; the ones
// Blender writes from the first sample only (depth, position, motion) stay the first's; a
// value one half lacks is the other's.
TEST(HalfBuffers, AccumulatedPassesAreAveragedFirstSamplePassesKept) {
  const int w = 8, h = 6;
  Frame fa = testutil::colour_frame(testutil::random_image(w, h, 3, 1));
  Frame fb = testutil::colour_frame(testutil::random_image(w, h, 3, 2));
  for (Role r : {Role::Albedo, Role::Normal, Role::Depth, Role::Position, Role::Motion, Role::DiffuseColour,
                 Role::SampleCount}) {
    const int ch = role_channels(r);
    testutil::add_pass(fa, r, testutil::random_image(w, h, ch, 10 + unsigned(r)));
    testutil::add_pass(fb, r, testutil::random_image(w, h, ch, 40 + unsigned(r)));
  }
  testutil::pass_image(fa, Role::Albedo).at(2, 3, 1) = testutil::kNaN;
  testutil::pass_image(fb, Role::Albedo).at(4, 1, 0) = testutil::kInf;
  // Blender's second half: depth 1e10, position 0.
  testutil::pass_image(fb, Role::Depth) = Image(w, h, 1, 1e10f);
  testutil::pass_image(fb, Role::Position) = Image(w, h, 3, 0.0f);
  const Frame f = combine_halves(fa, fb);
  for (Role r : {Role::Albedo, Role::Normal, Role::Depth, Role::Position, Role::Motion, Role::DiffuseColour,
                 Role::SampleCount}) {
    SCOPED_TRACE(role_name(r));
    const Image& m = f.image(r);
    const Image& a = fa.image(r);
    const Image& b = fb.image(r);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < m.channels(); ++c) {
          const float va = a.at(x, y, c), vb = b.at(x, y, c);
          if (r == Role::Depth || r == Role::Position || r == Role::Motion)
            EXPECT_EQ(m.at(x, y, c), va);
          else if (!std::isfinite(va))
            EXPECT_EQ(m.at(x, y, c), vb);
          else if (!std::isfinite(vb))
            EXPECT_EQ(m.at(x, y, c), va);
          else if (r == Role::SampleCount)
            EXPECT_FLOAT_EQ(m.at(x, y, c), va + vb);
          else
            EXPECT_FLOAT_EQ(m.at(x, y, c), 0.5f * va + 0.5f * vb);
        }
  }
}

// The sample scenes' halves: their mean is the 16-spp file, and the variance they give is
// within 1.5x of |16 spp - reference|^2 at the median 16x16 tile.
TEST(HalfBuffers, SampleHalvesGiveThe16SppRenderAndItsNoise) {
  int checked = 0;
  for (const SampleScene& sc : load_sample_manifest(std::string(MCRECON_SOURCE_DIR) + "/samples/data")) {
    for (const auto& [spp, pair] : sc.halves) {
      SCOPED_TRACE(pair.first);
      const Frame f = combine_halves(read_frame(pair.first), read_frame(pair.second));
      const Image full = read_frame(sc.noisy.at(spp)).image(Role::Colour);
      const Image ref = read_frame(sc.reference).image(Role::Colour);
      const Image& y = f.image(Role::Colour);
      double worst = 0;
      for (int yy = 0; yy < y.height(); ++yy)
        for (int x = 0; x < y.width(); ++x)
          for (int c = 0; c < 3; ++c)
            worst = std::max(worst, std::abs(double(y.at(x, yy, c)) - full.at(x, yy, c)) / (std::abs(full.at(x, yy, c)) + 1e-3));
      EXPECT_LT(worst, 2e-3);  // half-float rounding of three files
      // Its feature passes are the 16-spp file's too (Blender accumulates them); depth,
      // position and motion are the first half's.
      const Frame whole = read_frame(sc.noisy.at(spp)), first = read_frame(pair.first);
      int passes = 0;
      for (const Pass& p : f.passes) {
        if (p.role == Role::Colour || p.role == Role::Variance) continue;
        const bool kept = p.role == Role::Depth || p.role == Role::Position || p.role == Role::Motion;
        const Pass* q = nullptr;
        for (const Pass& c : (kept ? first : whole).passes)
          if (c.role == p.role && c.name == p.name) q = &c;
        ASSERT_NE(q, nullptr) << p.name;
        double d = 0, spread = 0;
        for (std::size_t i = 0; i < p.image.storage().size(); ++i) {
          d = std::max(d, std::abs(double(p.image.storage()[i]) - q->image.storage()[i]));
          spread = std::max(spread, std::abs(double(q->image.storage()[i])));
        }
        EXPECT_LT(d, 4e-3 * std::max(spread, 1.0)) << p.name;  // half-float rounding, not 8 samples against 16
        ++passes;
      }
      EXPECT_GE(passes, 4);
      const NoiseScales ns = estimate_noise_scales(y, Roi::all(y.width(), y.height()), 0, &f.image(Role::Variance));
      std::vector<double> ratio;
      for (int ty = 0; ty + 16 <= y.height(); ty += 16)
        for (int tx = 0; tx + 16 <= y.width(); tx += 16) {
          double e = 0, t = 0;
          for (int yy = ty; yy < ty + 16; ++yy)
            for (int x = tx; x < tx + 16; ++x) {
              e += ns.variance[ns.at(x, yy)];
              for (int c = 0; c < 3; ++c) t += std::pow(double(full.at(x, yy, c)) - ref.at(x, yy, c), 2) / 3;
            }
          if (t > 0 && e > 0) ratio.push_back(std::log2(e / t));
        }
      std::nth_element(ratio.begin(), ratio.begin() + long(ratio.size() / 2), ratio.end());
      EXPECT_LT(std::abs(ratio[ratio.size() / 2]), std::log2(1.5));
      // The reader does the same when given the second half.
      ReadOptions ro;
      ro.second_half = pair.second;
      EXPECT_EQ(read_frame(pair.first, ro).image(Role::Colour).storage(), y.storage());
      EXPECT_EQ(loose_pass_files(ro), std::vector<std::string>{pair.second});  // an input: never an output
      ++checked;
    }
  }
  EXPECT_GE(checked, 3);
}

// `d` written as a deep EXR and read back as a frame (the file removed).
Frame written_and_read(const DeepSamples& d) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("mcrecon_halves_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "samples.exr").string();
  write_deep_samples(d, path);
  Frame f = read_frame(path);
  std::filesystem::remove_all(dir);
  return f;
}

// A per-sample deep file (no alpha) read as a flat frame carries the variance of each
// pixel's mean from the halves of its samples in stored order: (A - B)^2 n1 n2 / n^2, with
// n1 = n / 2. Non-finite samples are left out; under two finite samples, NaN. A file with
// alpha (compositing layers, not independent samples) gets none.
TEST(HalfBuffers, APerSampleFileCarriesTheVarianceOfItsHalves) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // R of each pixel's samples; G = 2 R, B = R + 1 (the same variance as R, four times for G).
  const std::vector<std::vector<float>> r = {{1, 1, 3, 3}, {0, 2, 5}, {7}, {4, nan, 6}, {2, 2}, {1, 2, 3, 4, 5, 6}};
  const double want[] = {4.0 * 2 * 2 / 16, 3.5 * 3.5 * 1 * 2 / 9, -1, 4.0 * 1 * 1 / 4, 0.0, 9.0 * 3 * 3 / 36};
  DeepSamples d;
  d.width = 3;
  d.height = 2;
  d.channel_names = {"R", "G", "B", "Z"};
  d.offsets = {0};
  d.values.assign(4, {});
  for (const auto& px : r) {
    for (float v : px) {
      d.values[0].push_back(v);
      d.values[1].push_back(2 * v);
      d.values[2].push_back(v + 1);
      d.values[3].push_back(5.0f);
    }
    d.offsets.push_back(d.offsets.back() + px.size());
  }
  const Frame f = written_and_read(d);
  const Pass* var = f.find(Role::Variance);
  ASSERT_NE(var, nullptr);
  for (int i = 0; i < 6; ++i) {
    const int x = i % 3, y = i / 3;
    if (want[i] < 0) {
      for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isnan(var->image.at(x, y, c))) << i;
      continue;
    }
    EXPECT_NEAR(var->image.at(x, y, 0), want[i], 1e-5 * (1 + want[i])) << i;
    EXPECT_NEAR(var->image.at(x, y, 1), 4 * want[i], 1e-5 * (1 + want[i])) << i;
    EXPECT_NEAR(var->image.at(x, y, 2), want[i], 1e-5 * (1 + want[i])) << i;
  }
  // With alpha: compositing layers, no variance pass.
  d.channel_names = {"R", "G", "B", "A"};
  for (float& a : d.values[3]) a = 0.5f;
  EXPECT_EQ(written_and_read(d).find(Role::Variance), nullptr);
}

// Sixteen points of [0, 1) in render order as Cycles' progressive patterns lay them: every
// prefix of 2^k points one per 1/2^k stratum (the base-2 radical inverse of the index, each
// digit flipped by a random bit per prefix of digits: Owen's scrambling), jittered inside its
// 1/16 stratum. Each half is a stratified set of eight, the whole one of sixteen.
std::vector<double> progressive16(std::mt19937& rng) {
  std::uniform_int_distribution<int> bit(0, 1);
  std::uniform_real_distribution<double> jitter(0.0, 1.0 / 16);
  int flip[16];  // flip[node]: one per prefix of digits (a binary tree of 15 nodes)
  for (int& f : flip) f = bit(rng);
  std::vector<double> u(16);
  for (int i = 0; i < 16; ++i) {
    int node = 1;
    double x = 0, scale = 0.5;
    for (int j = 0; j < 4; ++j) {
      const int d = ((i >> j) & 1) ^ flip[node];
      x += d * scale;
      scale /= 2;
      node = 2 * node + d;
    }
    u[std::size_t(i)] = x + jitter(rng);
  }
  return u;
}

// The halves of stratified samples over-state the variance of their mean (each half is
// stratified only at its own count: for a pixel crossed by an edge, 3x at 16 samples). The pass
// reads how the halves' own estimates compare with the whole's (Var ~ n^-alpha) and corrects
// for it. Each kind of pixel in a frame of its own:
//   - an edge at a random place (jittered sampling's closed form p (1 - p) / 256, p its place
//     inside its 1/16 stratum): within 1.33x of the truth, where the plain halves read 2.5x+;
//   - independent samples: within 10% of the plain halves estimate (unbiased for them);
//   - one bright sample among flat ones (a rare path), among edges: the plain estimate, unchanged.
struct HalvesCase {
  std::vector<double> truth, plain, pass;
};
HalvesCase per_sample_variance(int kind, std::mt19937& rng) {
  std::uniform_real_distribution<double> edge(0.25, 0.75);
  std::normal_distribution<double> noise(0.5, 0.1);
  const int w = 48, h = 32;
  DeepSamples d;
  d.width = w;
  d.height = h;
  d.channel_names = {"R", "G", "B", "Z"};
  d.offsets = {0};
  d.values.assign(4, {});
  HalvesCase out;
  for (int i = 0; i < w * h; ++i) {
    std::vector<double> s(16, 0.5);
    double truth = 0;
    if (kind == 0 || (kind == 2 && i % 2 == 0)) {
      const double t = edge(rng), p = 16 * t - std::floor(16 * t);
      const std::vector<double> u = progressive16(rng);
      for (int k = 0; k < 16; ++k) s[std::size_t(k)] = u[std::size_t(k)] < t ? 1.0 : 0.0;
      truth = p * (1 - p) / 256;
    } else if (kind == 1) {
      for (double& v : s) v = noise(rng);
      truth = 0.01 / 16;
    } else {
      s[std::size_t(rng() % 16)] = 1.0;
      truth = -1;  // a rare path
    }
    double a = 0, b = 0;
    for (int k = 0; k < 8; ++k) a += s[std::size_t(k)] / 8;
    for (int k = 8; k < 16; ++k) b += s[std::size_t(k)] / 8;
    out.plain.push_back((a - b) * (a - b) / 4);
    out.truth.push_back(truth);
    for (double v : s)
      for (int c = 0; c < 3; ++c) d.values[std::size_t(c)].push_back(float(v));
    for (int k = 0; k < 16; ++k) d.values[3].push_back(1.0f);
    d.offsets.push_back(d.offsets.back() + 16);
  }
  const Frame f = written_and_read(d);
  const Pass* var = f.find(Role::Variance);
  if (var)
    for (int i = 0; i < w * h; ++i) out.pass.push_back(var->image.at(i % w, i / w, 0));
  return out;
}

double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

TEST(HalfBuffers, APerSampleFileCorrectsItsHalvesForStratification) {
  std::mt19937 rng(11);
  const HalvesCase edges = per_sample_variance(0, rng);
  ASSERT_EQ(edges.pass.size(), edges.truth.size());
  EXPECT_GT(sum(edges.plain) / sum(edges.truth), 2.5);  // the bias the correction is for
  EXPECT_LT(std::abs(std::log(sum(edges.pass) / sum(edges.truth))), std::log(1.33)) << sum(edges.pass) / sum(edges.truth);
  const HalvesCase independent = per_sample_variance(1, rng);
  ASSERT_EQ(independent.pass.size(), independent.plain.size());
  EXPECT_LT(std::abs(std::log(sum(independent.plain) / sum(independent.truth))), std::log(1.1));
  EXPECT_LT(std::abs(std::log(sum(independent.pass) / sum(independent.plain))), std::log(1.1))
      << sum(independent.pass) / sum(independent.plain);
  const HalvesCase rare = per_sample_variance(2, rng);
  ASSERT_EQ(rare.pass.size(), rare.plain.size());
  for (std::size_t i = 0; i < rare.pass.size(); ++i)
    if (rare.truth[i] < 0) EXPECT_NEAR(rare.pass[i], rare.plain[i], 1e-6 * rare.plain[i]) << i;
}

}  // namespace
}  // namespace mcr
