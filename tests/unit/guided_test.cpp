// Guided filter against a brute-force ridge-regression oracle (Eigen), closed forms
// (constant guide, tiny epsilon with the colour as its own guide, constant colour,
// guide offsets), and numerical stress (extreme values, NaN/Inf, tiny images,
// threads, roi, fireflies).
#include "filters/image/guided.h"

#include <gtest/gtest.h>

// Eigen is the oracle only; the core has its own small LDL^T solver.
#include <Eigen/Dense>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "feature_filter_testutil.h"
#include "filters/image/box.h"
#include "filters/registry.h"
#include "util/error.h"

namespace mcr {
namespace {

using testutil::kInf;
using testutil::kNaN;
using testutil::named_pass;
using testutil::Params;
using testutil::random_image;

// ---------------------------------------------------------------------------
// Frames

struct Passes {
  Image colour, normal, depth, albedo, position;
};

Frame frame_of(const Passes& ps) {
  Frame f;
  f.width = ps.colour.width();
  f.height = ps.colour.height();
  f.path = "test.exr";
  f.passes.push_back(named_pass(Role::Colour, "Combined", ps.colour));
  if (!ps.normal.empty()) f.passes.push_back(named_pass(Role::Normal, "Normal", ps.normal));
  if (!ps.depth.empty()) f.passes.push_back(named_pass(Role::Depth, "Depth", ps.depth));
  if (!ps.albedo.empty()) f.passes.push_back(named_pass(Role::Albedo, "Albedo", ps.albedo));
  if (!ps.position.empty()) f.passes.push_back(named_pass(Role::Position, "Position", ps.position));
  return f;
}

Image random_normals(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> dist(0.0f, 1.0f);
  Image im(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float n[3] = {dist(rng), dist(rng), std::fabs(dist(rng)) + 0.2f};
      const float l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = n[c] / l;
    }
  return im;
}

// A frame with every feature pass, random but with some structure (the colour
// partly follows the guide, so the fits are not trivial).
Passes random_passes(int w, int h, unsigned seed) {
  Passes ps;
  ps.normal = random_normals(w, h, seed);
  ps.depth = random_image(w, h, 1, seed + 1, 1.0f, 6.0f);
  ps.albedo = random_image(w, h, 3, seed + 2, 0.05f, 0.95f);
  ps.position = random_image(w, h, 3, seed + 3, -4.0f, 4.0f);
  ps.colour = random_image(w, h, 3, seed + 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        ps.colour.at(x, y, c) += 0.5f * ps.normal.at(x, y, c) + 0.1f * ps.depth.at(x, y, 0);
  return ps;
}

// The shared run, plus the guided filter's statistics of that run.
struct Result : testutil::Result {
  GuidedStats stats;
};

// The kernel tests fix what the defaults choose from the frame (guide, epsilon from the
// noise, demodulation), so the oracle below sees exactly what it models; the defaults
// have tests of their own (DefaultsFollowTheNoise and after). The common outlier step
// (firefly_k, on by default) is off: the oracle does not model it, and the firefly tests
// below check the kernel's own outlier sums.
const Params kKernelDefaults = {
    {"guide", std::string("normal_depth")}, {"epsilon", 0.01}, {"demodulate", false}, {"firefly_k", 0.0}};

Result run_guided(const Frame& frame, const Params& params, int nthreads = 1, Roi roi = {}) {
  GuidedFilter f;
  Result r;
  static_cast<testutil::Result&>(r) =
      testutil::run_filter(f, frame, testutil::with(kKernelDefaults, params), nthreads, roi);
  r.stats = f.stats();
  return r;
}

// ---------------------------------------------------------------------------
// The oracle: the documented definition, written out plainly in double.

struct GuideGroup {
  Role role;  // Role::Colour: from the colour (luminance or RGB)
  bool luminance;
  int channels;
  bool unit;
};

std::vector<GuideGroup> guide_groups(const std::string& guide) {
  const GuideGroup n{Role::Normal, false, 3, true}, d{Role::Depth, false, 1, false}, p{Role::Position, false, 3, false},
      a{Role::Albedo, false, 3, true};
  if (guide == "normal_depth") return {n, d};
  if (guide == "normal") return {n};
  if (guide == "depth") return {d};
  if (guide == "position") return {p};
  if (guide == "normal_position") return {n, p};
  if (guide == "albedo") return {a};
  if (guide == "normal_albedo") return {n, a};
  if (guide == "normal_depth_albedo") return {n, d, a};
  if (guide == "luminance") return {{Role::Colour, true, 1, false}};
  if (guide == "colour") return {{Role::Colour, false, 3, false}};
  if (guide == "normal_depth_colour") return {n, d, {Role::Colour, false, 3, false}};
  ADD_FAILURE() << "unknown guide " << guide;
  return {};
}

bool finite_rgb(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// Expected output of the guided filter on frame.colour (no demodulation, no holes).
Image oracle(const Frame& frame, const std::string& guide, int r, double eps) {
  const int w = frame.width, h = frame.height;
  const Image& colour = frame.image(Role::Colour);
  // Raw guide values per pixel.
  std::vector<std::vector<double>> raw(std::size_t(w) * h);
  std::vector<std::pair<int, int>> groups;
  std::vector<bool> unit;
  int d = 0;
  for (const GuideGroup& g : guide_groups(guide)) {
    groups.emplace_back(d, g.channels);
    unit.push_back(g.unit);
    d += g.channels;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        auto& v = raw[std::size_t(y) * w + x];
        if (g.role == Role::Colour) {
          const float* p = colour.pixel(x, y);
          if (g.luminance) {
            v.push_back(finite_rgb(p) ? double(float(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])) : double(kNaN));
          } else {
            for (int c = 0; c < 3; ++c) v.push_back(p[c]);
          }
        } else {
          const Image& img = frame.image(g.role);
          for (int c = 0; c < g.channels; ++c) v.push_back(img.at(x, y, std::min(c, img.channels() - 1)));
        }
      }
  }
  auto guide_ok = [&](std::size_t i) {
    for (double v : raw[i])
      if (!std::isfinite(v)) return false;
    return true;
  };
  // Normalisation over the finite guide pixels.
  std::vector<double> mean(d, 0.0), var(d, 0.0), scale(d, 1.0);
  int n = 0;
  for (std::size_t i = 0; i < raw.size(); ++i)
    if (guide_ok(i)) {
      ++n;
      for (int j = 0; j < d; ++j) mean[j] += raw[i][j];
    }
  for (double& m : mean) m = n ? m / n : 0.0;
  for (std::size_t i = 0; i < raw.size(); ++i)
    if (guide_ok(i))
      for (int j = 0; j < d; ++j) var[j] += (raw[i][j] - mean[j]) * (raw[i][j] - mean[j]);
  for (double& v : var) v = n ? v / n : 0.0;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    double v = 0;
    for (int j = groups[g].first; j < groups[g].first + groups[g].second; ++j) v += var[j];
    double s = std::sqrt(v / groups[g].second);
    if (!(s > 0.0)) s = 1.0;
    if (unit[g]) s = std::max(1.0, s);
    for (int j = groups[g].first; j < groups[g].first + groups[g].second; ++j) scale[j] = s;
  }
  auto z_of = [&](std::size_t i) {
    Eigen::VectorXd z(d);
    for (int j = 0; j < d; ++j) z[j] = (raw[i][j] - mean[j]) / scale[j];
    return z;
  };
  auto valid = [&](std::size_t i) { return guide_ok(i) && finite_rgb(colour.data() + i * 3); };

  // Per window: a (d x 3), b (3), mean colour (3), or nothing.
  struct Model {
    Eigen::MatrixXd a;
    Eigen::Vector3d b, mp;
  };
  std::vector<std::optional<Model>> models(std::size_t(w) * h);
  for (int ky = 0; ky < h; ++ky)
    for (int kx = 0; kx < w; ++kx) {
      std::vector<std::size_t> px;
      for (int y = std::max(0, ky - r); y <= std::min(h - 1, ky + r); ++y)
        for (int x = std::max(0, kx - r); x <= std::min(w - 1, kx + r); ++x)
          if (valid(std::size_t(y) * w + x)) px.push_back(std::size_t(y) * w + x);
      if (px.empty()) continue;
      const int m = int(px.size());
      // Augmented least squares: rows [z_i^T 1] -> p_i, plus sqrt(m eps) e_j -> 0,
      // i.e. min sum (a.z_i + b - p_i)^2 + m eps |a|^2 (He et al. 2013, eq. 3).
      Eigen::MatrixXd M = Eigen::MatrixXd::Zero(m + d, d + 1);
      Eigen::MatrixXd P = Eigen::MatrixXd::Zero(m + d, 3);
      Eigen::Vector3d mp = Eigen::Vector3d::Zero();
      for (int t = 0; t < m; ++t) {
        M.block(t, 0, 1, d) = z_of(px[t]).transpose();
        M(t, d) = 1.0;
        for (int c = 0; c < 3; ++c) {
          P(t, c) = colour.data()[px[t] * 3 + c];
          mp[c] += P(t, c) / m;
        }
      }
      for (int j = 0; j < d; ++j) M(m + j, j) = std::sqrt(m * eps);
      const Eigen::MatrixXd X = M.colPivHouseholderQr().solve(P);
      Model md;
      md.a = X.topRows(d);
      md.b = X.row(d).transpose();
      md.mp = mp;
      models[std::size_t(ky) * w + kx] = md;
    }
  Image out = colour;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      Eigen::Vector3d q = Eigen::Vector3d::Zero();
      int cnt = 0;
      for (int ky = std::max(0, y - r); ky <= std::min(h - 1, y + r); ++ky)
        for (int kx = std::max(0, x - r); kx <= std::min(w - 1, x + r); ++kx) {
          const auto& md = models[std::size_t(ky) * w + kx];
          if (!md) continue;
          ++cnt;
          if (guide_ok(i))
            q += md->a.transpose() * z_of(i) + md->b;
          else
            q += md->mp;
        }
      for (int c = 0; c < 3; ++c) {
        float& o = out.at(x, y, c);
        if (cnt)
          o = float(std::clamp(q[c] / cnt, -double(FLT_MAX), double(FLT_MAX)));
        else if (!std::isfinite(o))
          o = 0.0f;
      }
    }
  return out;
}

// |got - want| <= tol * max(1, |want|) at every value (and never non-finite).
void expect_close(const Image& got, const Image& want, double tol, const std::string& what) {
  ASSERT_EQ(got.width(), want.width());
  ASSERT_EQ(got.height(), want.height());
  ASSERT_EQ(got.channels(), 3);
  int bad = 0;
  for (int y = 0; y < got.height(); ++y)
    for (int x = 0; x < got.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const double g = got.at(x, y, c), e = want.at(x, y, c);
        const bool ok = std::isfinite(g) && std::fabs(g - e) <= tol * std::max(1.0, std::fabs(e));
        if (!ok && bad++ < 5)
          ADD_FAILURE() << what << ": pixel " << x << "," << y << " channel " << c << ": got " << g << ", want " << e;
      }
  EXPECT_EQ(bad, 0) << what;
}

void expect_all_finite(const Image& im, const std::string& what) {
  for (float v : im.storage()) ASSERT_TRUE(std::isfinite(v)) << what;
}

// ---------------------------------------------------------------------------
// Against the oracle

TEST(GuidedFilterTest, MatchesOracleNormalDepth) {
  const Frame f = frame_of(random_passes(12, 9, 1));
  for (int r : {1, 2, 3})
    for (double eps : {0.01, 0.5}) {
      const Result res = run_guided(f, {{"radius", std::int64_t(r)}, {"epsilon", eps}});
      EXPECT_EQ(res.repaired, 0u);
      EXPECT_EQ(res.stats.guide_channels, 4);
      expect_close(res.out, oracle(f, "normal_depth", r, eps), 1e-4,
                   "normal_depth r=" + std::to_string(r) + " eps=" + std::to_string(eps));
    }
}

TEST(GuidedFilterTest, MatchesOracleEveryGuide) {
  const Frame f = frame_of(random_passes(11, 8, 2));
  for (const char* g : {"normal", "depth", "position", "normal_position", "albedo", "normal_albedo",
                        "normal_depth_albedo", "luminance", "colour", "normal_depth_colour"})
    for (int r : {1, 3}) {
      const Result res = run_guided(f, {{"guide", std::string(g)}, {"radius", std::int64_t(r)}});
      expect_close(res.out, oracle(f, g, r, 0.01), 1e-4, std::string(g) + " r=" + std::to_string(r));
    }
}

// One guide channel: a = cov / (var + eps), b = mean p - a mean z, written out by hand.
TEST(GuidedFilterTest, OneChannelGuideIsTheClassicClosedForm) {
  const Frame f = frame_of(random_passes(10, 7, 3));
  const int r = 2;
  const double eps = 0.05;
  const Image& depth = f.image(Role::Depth);
  const Image& p = f.image(Role::Colour);
  const int w = f.width, h = f.height;
  double mean = 0, var = 0;
  for (float v : depth.storage()) mean += v;
  mean /= depth.storage().size();
  for (float v : depth.storage()) var += (v - mean) * (v - mean);
  const double s = std::sqrt(var / depth.storage().size());
  auto z = [&](int x, int y) { return (depth.at(x, y, 0) - mean) / s; };
  std::vector<double> a(std::size_t(w) * h * 3), b(a.size());
  for (int ky = 0; ky < h; ++ky)
    for (int kx = 0; kx < w; ++kx) {
      double n = 0, mz = 0, mzz = 0, mp[3] = {0, 0, 0}, mzp[3] = {0, 0, 0};
      for (int y = std::max(0, ky - r); y <= std::min(h - 1, ky + r); ++y)
        for (int x = std::max(0, kx - r); x <= std::min(w - 1, kx + r); ++x) {
          ++n;
          mz += z(x, y);
          mzz += z(x, y) * z(x, y);
          for (int c = 0; c < 3; ++c) {
            mp[c] += p.at(x, y, c);
            mzp[c] += z(x, y) * p.at(x, y, c);
          }
        }
      mz /= n;
      const double vz = mzz / n - mz * mz;
      for (int c = 0; c < 3; ++c) {
        const double cov = mzp[c] / n - mz * mp[c] / n;
        const std::size_t k = (std::size_t(ky) * w + kx) * 3 + c;
        a[k] = cov / (vz + eps);
        b[k] = mp[c] / n - a[k] * mz;
      }
    }
  Image want(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        double q = 0;
        int cnt = 0;
        for (int ky = std::max(0, y - r); ky <= std::min(h - 1, y + r); ++ky)
          for (int kx = std::max(0, x - r); kx <= std::min(w - 1, x + r); ++kx) {
            const std::size_t k = (std::size_t(ky) * w + kx) * 3 + c;
            q += a[k] * z(x, y) + b[k];
            ++cnt;
          }
        want.at(x, y, c) = float(q / cnt);
      }
  const Result res = run_guided(f, {{"guide", std::string("depth")}, {"radius", std::int64_t(r)}, {"epsilon", eps}});
  expect_close(res.out, want, 1e-4, "depth guide closed form");
  expect_close(res.out, oracle(f, "depth", r, eps), 1e-4, "depth guide oracle");
}

TEST(GuidedFilterTest, MatchesOracleAcrossRowBandsAndWideRoi) {
  // 300 rows: several row bands (each recomputes the rows past its ends).
  const Frame f = frame_of(random_passes(9, 300, 4));
  for (int r : {1, 3}) {
    const Result res = run_guided(f, {{"radius", std::int64_t(r)}}, 2);
    EXPECT_GE(res.stats.bands, 2);
    expect_close(res.out, oracle(f, "normal_depth", r, 0.01), 1e-4, "bands r=" + std::to_string(r));
  }
}

TEST(GuidedFilterTest, RadiusLargerThanTheImage) {
  const Frame f = frame_of(random_passes(7, 5, 5));
  for (int r : {6, 20, 256}) {
    const Result res = run_guided(f, {{"radius", std::int64_t(r)}});
    expect_close(res.out, oracle(f, "normal_depth", r, 0.01), 1e-4, "radius " + std::to_string(r));
  }
}

TEST(GuidedFilterTest, TinyImages) {
  for (auto [w, h] : {std::pair{1, 1}, {1, 9}, {9, 1}, {2, 1}, {1, 2}}) {
    const Frame f = frame_of(random_passes(w, h, 6));
    for (int r : {1, 4}) {
      const Result res = run_guided(f, {{"radius", std::int64_t(r)}});
      EXPECT_EQ(res.repaired, 0u);
      expect_close(res.out, oracle(f, "normal_depth", r, 0.01), 1e-4,
                   std::to_string(w) + "x" + std::to_string(h) + " r=" + std::to_string(r));
    }
  }
  // 1x1: the only window is the pixel itself, a = 0, so the output is the input.
  const Frame one = frame_of(random_passes(1, 1, 7));
  const Result res = run_guided(one, {{"radius", std::int64_t(3)}});
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(res.out.at(0, 0, c), one.image(Role::Colour).at(0, 0, c));
}

// ---------------------------------------------------------------------------
// Closed forms

// Box mean of box means (what the guided filter is with a = 0), brute force.
Image box_of_box(const Image& p, int r) {
  const int w = p.width(), h = p.height();
  auto box = [&](const Image& in) {
    Image out(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) {
          double s = 0;
          int n = 0;
          for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
            for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx, ++n) s += in.at(xx, yy, c);
          out.at(x, y, c) = float(s / n);
        }
    return out;
  };
  return box(box(p));
}

TEST(GuidedFilterTest, ConstantGuideGivesTheBoxMeanOfBoxMeans) {
  // Sigma = 0 and cov = 0 in every window: a = 0, b = window mean, and the output
  // is the mean of the window means over the windows holding the pixel.
  Passes ps = random_passes(13, 10, 8);
  for (float& v : ps.normal.storage()) v = 0.5f;
  for (float& v : ps.depth.storage()) v = 3.0f;
  const Frame f = frame_of(ps);
  for (int r : {1, 2, 4}) {
    const Result res = run_guided(f, {{"radius", std::int64_t(r)}});
    expect_close(res.out, box_of_box(ps.colour, r), 1e-5, "constant guide r=" + std::to_string(r));
    // The same through the box filter run twice.
    BoxFilter box;
    testutil::without_step_back(box);
    box.set("radius", std::int64_t(r));
    box.commit();
    Frame once = f;
    once.passes[0].image = box.execute(f);
    expect_close(res.out, box.execute(once), 1e-5, "constant guide = box(box) r=" + std::to_string(r));
  }
}

TEST(GuidedFilterTest, ColourAsItsOwnGuideWithTinyEpsilonIsTheIdentity) {
  // Grey colour (R = G = B), guide = luminance = the colour: every window fits the
  // colour exactly with a = 1 / scale, so eps -> 0 gives back the input.
  Image grey = random_image(15, 11, 1, 9, 0.1f, 2.0f);
  Passes ps;
  ps.colour = Image(15, 11, 3);
  for (int y = 0; y < 11; ++y)
    for (int x = 0; x < 15; ++x)
      for (int c = 0; c < 3; ++c) ps.colour.at(x, y, c) = grey.at(x, y, 0);
  const Frame f = frame_of(ps);
  for (int r : {1, 3, 8}) {
    const Result res = run_guided(f, {{"guide", std::string("luminance")}, {"radius", std::int64_t(r)}, {"epsilon", 1e-8}});
    expect_close(res.out, ps.colour, 1e-4, "self-guided eps=1e-8 r=" + std::to_string(r));
    // And with a large eps it is not (the test can fail).
    const Result smooth =
        run_guided(f, {{"guide", std::string("luminance")}, {"radius", std::int64_t(r)}, {"epsilon", 10.0}});
    double diff = 0;
    for (std::size_t i = 0; i < ps.colour.storage().size(); ++i)
      diff = std::max(diff, double(std::fabs(smooth.out.storage()[i] - ps.colour.storage()[i])));
    EXPECT_GT(diff, 0.05);
  }
}

TEST(GuidedFilterTest, ConstantColourStaysConstant) {
  const Passes base = random_passes(12, 9, 10);
  for (float v : {0.0f, 0.375f, -2.5f, 1e-30f, 1e30f, 3.0e38f}) {
    Passes ps = base;
    for (float& c : ps.colour.storage()) c = v;
    const Result res = run_guided(frame_of(ps), {{"radius", std::int64_t(2)}});
    EXPECT_EQ(res.repaired, 0u);
    for (float o : res.out.storage()) ASSERT_NEAR(o, v, 1e-5 * std::fabs(v)) << "constant " << v;
  }
}

TEST(GuidedFilterTest, InvariantUnderAConstantAddedToTheGuide) {
  // Guide values on a 1/256 grid so that the offsets are exact in float.
  Passes ps = random_passes(12, 9, 11);
  for (float& v : ps.normal.storage()) v = std::round(v * 256.0f) / 256.0f;
  for (float& v : ps.depth.storage()) v = std::round(v * 256.0f) / 256.0f;
  const Result base = run_guided(frame_of(ps), {{"radius", std::int64_t(2)}});
  Passes shifted = ps;
  for (float& v : shifted.normal.storage()) v += 3.0f;
  for (float& v : shifted.depth.storage()) v += 1000.0f;
  const Result res = run_guided(frame_of(shifted), {{"radius", std::int64_t(2)}});
  expect_close(res.out, base.out, 1e-5, "guide + constant");
  // A scaled depth is a different guide only through the normalisation, which
  // divides the scale out again.
  Passes scaled = ps;
  for (float& v : scaled.depth.storage()) v *= 64.0f;
  expect_close(run_guided(frame_of(scaled), {{"radius", std::int64_t(2)}}).out, base.out, 1e-5, "depth x 64");
}

TEST(GuidedFilterTest, LinearInTheColour) {
  // q(s p) = s q(p): the same result at 1e-30 and 1e30 as at 1 (the outlier
  // threshold is relative, so the same sums are used).
  const Passes ps = random_passes(14, 10, 12);
  const Result unit = run_guided(frame_of(ps), {{"radius", std::int64_t(3)}});
  for (float s : {1e-30f, 1e-20f, 1e20f, 1e30f}) {
    Passes scaled = ps;
    for (float& v : scaled.colour.storage()) v *= s;
    const Result res = run_guided(frame_of(scaled), {{"radius", std::int64_t(3)}});
    EXPECT_EQ(res.repaired, 0u);
    for (std::size_t i = 0; i < unit.out.storage().size(); ++i)
      ASSERT_NEAR(res.out.storage()[i] / s, unit.out.storage()[i], 1e-4 * std::max(1.0f, std::fabs(unit.out.storage()[i])))
          << "scale " << s << " value " << i;
  }
}

// ---------------------------------------------------------------------------
// Non-finite values, extremes

TEST(GuidedFilterTest, NonFiniteColourAndGuideSamplesAreLeftOut) {
  const Passes base = random_passes(12, 9, 13);
  struct Case {
    const char* what;
    Image Passes::*pass;
    int channel;
  };
  const Case cases[] = {{"colour R", &Passes::colour, 0}, {"colour G", &Passes::colour, 1},
                        {"colour B", &Passes::colour, 2}, {"normal x", &Passes::normal, 0},
                        {"normal y", &Passes::normal, 1}, {"normal z", &Passes::normal, 2},
                        {"depth", &Passes::depth, 0}};
  for (const Case& cs : cases)
    for (float bad : {kNaN, kInf, -kInf}) {
      Passes ps = base;
      Image& img = ps.*cs.pass;
      for (auto [x, y] : {std::pair{0, 0}, {5, 4}, {6, 4}, {11, 8}, {3, 7}}) img.at(x, y, cs.channel) = bad;
      const Frame f = frame_of(ps);
      for (int r : {1, 2}) {
        const Result res = run_guided(f, {{"radius", std::int64_t(r)}});
        EXPECT_EQ(res.repaired, 0u) << cs.what;
        EXPECT_EQ(res.stats.invalid_pixels, 5u) << cs.what;
        expect_all_finite(res.out, cs.what);
        expect_close(res.out, oracle(f, "normal_depth", r, 0.01), 1e-4,
                     std::string(cs.what) + " = " + std::to_string(bad) + " r=" + std::to_string(r));
      }
    }
}

TEST(GuidedFilterTest, PixelsWithNoValidPixelNearby) {
  // A 12x12 hole (colour NaN in its left half, guide NaN in its right half) in a
  // 30x30 frame, radius 1: pixels farther than 2 inside the hole have no window
  // with a valid pixel; they keep their input colour where finite, else 0.
  Passes ps = random_passes(30, 30, 14);
  for (int y = 9; y < 21; ++y)
    for (int x = 9; x < 21; ++x) {
      if (x < 15)
        ps.colour.at(x, y, 1) = kNaN;
      else
        ps.depth.at(x, y, 0) = kInf;
    }
  const Frame f = frame_of(ps);
  const Result res = run_guided(f, {{"radius", std::int64_t(1)}});
  EXPECT_EQ(res.repaired, 0u);
  expect_all_finite(res.out, "hole");
  // Deep inside the colour-NaN half: 0 for the NaN channel, the input for the others.
  EXPECT_EQ(res.out.at(12, 15, 1), 0.0f);
  EXPECT_EQ(res.out.at(12, 15, 0), ps.colour.at(12, 15, 0));
  // Deep inside the guide-NaN half: the input colour, untouched.
  for (int c = 0; c < 3; ++c) EXPECT_EQ(res.out.at(17, 15, c), ps.colour.at(17, 15, c));
  expect_close(res.out, oracle(f, "normal_depth", 1, 0.01), 1e-4, "hole vs oracle");
}

TEST(GuidedFilterTest, EverythingInvalid) {
  Passes ps = random_passes(8, 6, 15);
  Passes nan_colour = ps;
  for (float& v : nan_colour.colour.storage()) v = kNaN;
  Result res = run_guided(frame_of(nan_colour), {{"radius", std::int64_t(2)}});
  EXPECT_EQ(res.repaired, 0u);
  for (float v : res.out.storage()) EXPECT_EQ(v, 0.0f);
  Passes nan_guide = ps;
  for (float& v : nan_guide.normal.storage()) v = kNaN;
  for (float& v : nan_guide.depth.storage()) v = kNaN;
  res = run_guided(frame_of(nan_guide), {{"radius", std::int64_t(2)}});
  EXPECT_EQ(res.repaired, 0u);
  EXPECT_EQ(res.out.storage(), ps.colour.storage());
  // An all-NaN normal alone is an absent pass: the guide is the depth (constant_feature_skip_test).
  nan_guide.depth = ps.depth;
  res = run_guided(frame_of(nan_guide), {{"radius", std::int64_t(2)}});
  expect_close(res.out, run_guided(frame_of(nan_guide), {{"radius", std::int64_t(2)}, {"guide", std::string("depth")}}).out,
               1e-6, "NaN normal");
}

TEST(GuidedFilterTest, AllEqualFeaturesAndEpsilonAtItsLimits) {
  Passes ps = random_passes(16, 12, 16);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 16; ++x) {
      ps.normal.at(x, y, 0) = 0.0f;
      ps.normal.at(x, y, 1) = 0.0f;
      ps.normal.at(x, y, 2) = 1.0f;
      ps.depth.at(x, y, 0) = 2.0f;
    }
  ps.colour.at(3, 3, 0) = kNaN;
  ps.colour.at(10, 7, 2) = kInf;
  const Frame f = frame_of(ps);
  for (double eps : {1e-8, 1e6}) {
    const Result res = run_guided(f, {{"radius", std::int64_t(2)}, {"epsilon", eps}});
    EXPECT_EQ(res.repaired, 0u);
    expect_close(res.out, oracle(f, "normal_depth", 2, eps), 1e-4, "all-equal features eps=" + std::to_string(eps));
  }
  // Random features at the limits too; eps = 1e6 leaves a ~ 0: box of box means.
  const Frame g = frame_of(random_passes(16, 12, 17));
  for (double eps : {1e-8, 1e6}) {
    const Result res = run_guided(g, {{"radius", std::int64_t(2)}, {"epsilon", eps}});
    EXPECT_EQ(res.repaired, 0u);
    expect_close(res.out, oracle(g, "normal_depth", 2, eps), 1e-4, "random features eps=" + std::to_string(eps));
  }
  expect_close(run_guided(g, {{"radius", std::int64_t(2)}, {"epsilon", 1e6}}).out,
               box_of_box(g.image(Role::Colour), 2), 1e-4, "eps=1e6 is box of box");
}

TEST(GuidedFilterTest, ExtremeMagnitudesDoNotOverflow) {
  // Colour at +-3e38 mixed with ordinary values: sums in double, output clamped.
  Passes ps = random_passes(12, 9, 18);
  for (int x = 0; x < 12; ++x) ps.colour.at(x, 4, x % 3) = (x % 2 ? 3.0e38f : -3.0e38f);
  ps.depth.at(2, 2, 0) = 3.0e38f;  // one huge depth: flattens the depth channel
  ps.depth.at(9, 6, 0) = 1e-38f;
  const Frame f = frame_of(ps);
  for (int r : {1, 3}) {
    const Result res = run_guided(f, {{"radius", std::int64_t(r)}});
    EXPECT_EQ(res.repaired, 0u);
    expect_all_finite(res.out, "extremes");
  }
  // Subnormal and tiny guides.
  Passes tiny = random_passes(12, 9, 19);
  for (float& v : tiny.depth.storage()) v *= 1e-40f;
  for (float& v : tiny.normal.storage()) v *= 1e-30f;
  const Frame t = frame_of(tiny);
  const Result res = run_guided(t, {{"radius", std::int64_t(2)}});
  EXPECT_EQ(res.repaired, 0u);
  expect_close(res.out, oracle(t, "normal_depth", 2, 0.01), 1e-4, "tiny guides");
}

TEST(GuidedFilterTest, FireflyDoesNotLeakPastTwoRadii) {
  // One 1e30 pixel among values near 1: it goes to the outlier sums, so every
  // pixel farther than 2r from it gets exactly what it gets without it, and the
  // pixels within 2r are spread (finite).
  const Passes ps = random_passes(64, 64, 20);
  const int r = 3;
  const Result clean = run_guided(frame_of(ps), {{"radius", std::int64_t(r)}});
  EXPECT_EQ(clean.stats.outlier_pixels, 0u);
  Passes fire = ps;
  const int fx = 20, fy = 21;
  fire.colour.at(fx, fy, 0) = 1e30f;
  const Result res = run_guided(frame_of(fire), {{"radius", std::int64_t(r)}});
  EXPECT_EQ(res.repaired, 0u);
  EXPECT_EQ(res.stats.outlier_pixels, 1u);
  int far = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const bool near = std::abs(x - fx) <= 2 * r && std::abs(y - fy) <= 2 * r;
      for (int c = 0; c < 3; ++c) {
        const float got = res.out.at(x, y, c), want = clean.out.at(x, y, c);
        ASSERT_TRUE(std::isfinite(got));
        if (!near) {
          ASSERT_NEAR(got, want, 1e-5 * std::max(1.0f, std::fabs(want))) << x << "," << y << " c" << c;
          ++far;
        }
      }
    }
  EXPECT_GT(far, 0);
  EXPECT_GT(res.out.at(fx, fy, 0), 1e20f);  // spread, not lost
  // The oracle agrees near the firefly too (relative to its size).
  Passes small = ps;
  small.colour = Image(16, 16, 3);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c) small.colour.at(x, y, c) = ps.colour.at(x, y, c);
  small.normal = random_normals(16, 16, 21);
  small.depth = random_image(16, 16, 1, 22, 1.0f, 6.0f);
  small.albedo = Image();
  small.position = Image();
  small.colour.at(5, 6, 1) = 1e30f;
  small.depth.at(12, 3, 0) = kNaN;  // and a pixel without a guide: both kinds of extra sums
  const Frame sf = frame_of(small);
  const Result sres = run_guided(sf, {{"radius", std::int64_t(2)}});
  const Image want = oracle(sf, "normal_depth", 2, 0.01);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c) {
        const bool near = std::abs(x - 5) <= 4 && std::abs(y - 6) <= 4;
        const double scale = near ? 1e30 : 1.0;
        ASSERT_NEAR(sres.out.at(x, y, c), want.at(x, y, c), 1e-4 * std::max(scale, double(std::fabs(want.at(x, y, c)))))
            << x << "," << y << " c" << c;
      }
}

TEST(GuidedFilterTest, ClampLimitsFireflies) {
  Passes ps = random_passes(20, 20, 23);
  ps.colour.at(10, 10, 0) = 1e6f;
  Passes clamped = ps;
  for (float& v : clamped.colour.storage()) v = std::clamp(v, -2.0f, 2.0f);
  const Result a = run_guided(frame_of(ps), {{"radius", std::int64_t(2)}, {"clamp", 2.0}});
  const Result b = run_guided(frame_of(clamped), {{"radius", std::int64_t(2)}});
  expect_close(a.out, b.out, 1e-6, "clamp = pre-clamped colour");
}

TEST(GuidedFilterTest, ZeroAlbedoWithDemodulation) {
  Passes ps = random_passes(12, 9, 24);
  for (float& v : ps.albedo.storage()) v = 0.0f;
  ps.albedo.at(3, 3, 1) = kNaN;
  const Frame f = frame_of(ps);
  for (const char* g : {"normal_depth", "normal_depth_albedo", "albedo"}) {
    const Result res = run_guided(f, {{"guide", std::string(g)}, {"radius", std::int64_t(2)}, {"demodulate", true}});
    EXPECT_EQ(res.repaired, 0u) << g;
    expect_all_finite(res.out, g);
  }
}

// ---------------------------------------------------------------------------
// Threads, roi, parameters, errors

TEST(GuidedFilterTest, SameResultOnAnyThreadCount) {
  // Bit for bit. The second frame is ill-conditioned on purpose (depth almost a
  // linear function of the normals, eps at its minimum), so that the smallest
  // rounding difference in the sums would show in the float output.
  Passes sharp = random_passes(150, 300, 25);
  for (int y = 0; y < 300; ++y)
    for (int x = 0; x < 150; ++x)
      sharp.depth.at(x, y, 0) = 3.0f + sharp.normal.at(x, y, 0) - 2.0f * sharp.normal.at(x, y, 1) +
                                1e-4f * float((x * 7 + y * 13) % 5);
  for (float& v : sharp.colour.storage()) v = std::exp(8.0f * v);
  for (const Frame& f : {frame_of(random_passes(150, 300, 25)), frame_of(sharp)})
    for (int r : {1, 4, 9})
      for (double eps : {0.01, 1e-8}) {
        const Params p{{"radius", std::int64_t(r)}, {"epsilon", eps}};
        const Result one = run_guided(f, p, 1);
        const Result two = run_guided(f, p, 2);
        const Result all = run_guided(f, p, 0);
        EXPECT_GE(one.stats.bands, 2) << r;
        EXPECT_EQ(one.out.storage(), two.out.storage()) << "radius " << r << " eps " << eps;
        EXPECT_EQ(one.out.storage(), all.out.storage()) << "radius " << r << " eps " << eps;
      }
}

TEST(GuidedFilterTest, RoiOnlyChangesPixelsInside) {
  const Passes ps = random_passes(40, 30, 26);
  const Frame f = frame_of(ps);
  const Result full = run_guided(f, {{"radius", std::int64_t(3)}});
  for (Roi roi : {Roi{5, 7, 22, 19}, Roi{0, 0, 40, 1}, Roi{39, 0, 40, 30}, Roi{0, 0, 3, 3}}) {
    const Result part = run_guided(f, {{"radius", std::int64_t(3)}}, 2, roi);
    const Roi in = roi.clipped(40, 30);
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 40; ++x)
        for (int c = 0; c < 3; ++c) {
          const bool inside = x >= in.x0 && x < in.x1 && y >= in.y0 && y < in.y1;
          if (inside)
            ASSERT_NEAR(part.out.at(x, y, c), full.out.at(x, y, c), 1e-5 * std::max(1.0f, std::fabs(full.out.at(x, y, c))));
          else
            ASSERT_EQ(part.out.at(x, y, c), ps.colour.at(x, y, c)) << x << "," << y;
        }
  }
}

TEST(GuidedFilterTest, MissingGuidePassesAreNamed) {
  Passes ps = random_passes(8, 6, 27);
  Passes no_depth = ps;
  no_depth.depth = Image();
  try {
    run_guided(frame_of(no_depth), {});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::MissingPass);
    EXPECT_NE(std::string(e.what()).find("depth"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("guide=normal_depth"), std::string::npos) << e.what();
  }
  Passes colour_only;
  colour_only.colour = ps.colour;
  try {
    run_guided(frame_of(colour_only), {{"guide", std::string("normal_position")}});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::MissingPass);
    EXPECT_NE(std::string(e.what()).find("normal, position passes"), std::string::npos) << e.what();
  }
  // A colour-only frame is fine with a colour guide, and a frame with the chosen
  // guide's passes is fine without the others.
  EXPECT_NO_THROW(run_guided(frame_of(colour_only), {{"guide", std::string("luminance")}}));
  EXPECT_NO_THROW(run_guided(frame_of(no_depth), {{"guide", std::string("normal")}}));
  EXPECT_EQ(GuidedFilter::guide_passes("normal_depth"), (std::vector<Role>{Role::Normal, Role::Depth}));
  EXPECT_TRUE(GuidedFilter::guide_passes("colour").empty());
}

TEST(GuidedFilterTest, ParameterTableAndRegistry) {
  auto f = make_filter("guided");
  const FilterInfo& info = f->info();
  EXPECT_EQ(info.name, "guided");
  EXPECT_FALSE(info.nonfinite_policy.empty());
  EXPECT_EQ(info.required, std::vector<Role>{Role::Colour});
  for (const char* p : {"guide", "radius", "epsilon", "clamp", "demodulate", "albedo_floor", "holes"})
    EXPECT_TRUE(f->params().has(p)) << p;
  EXPECT_THROW(f->set("radius", std::int64_t(0)), Error);
  EXPECT_THROW(f->set("epsilon", -1e-9), Error);
  EXPECT_THROW(f->set("epsilon_scale", 0.0), Error);
  EXPECT_THROW(f->set_text("guide", "rgb"), Error);
}

TEST(GuidedFilterTest, GuideNormalisationIsDocumented) {
  // Depth: centred, divided by its std; normals: centred, divided by max(1, rms std).
  Passes ps = random_passes(20, 10, 28);
  for (float& v : ps.depth.storage()) v = v * 100.0f + 7.0f;
  const Result res = run_guided(frame_of(ps), {{"radius", std::int64_t(1)}});
  ASSERT_EQ(res.stats.guide_scale.size(), 4u);
  double m = 0, v = 0;
  for (float d : ps.depth.storage()) m += d;
  m /= ps.depth.storage().size();
  for (float d : ps.depth.storage()) v += (d - m) * (d - m);
  EXPECT_NEAR(res.stats.guide_mean[3], m, 1e-9 * m);
  EXPECT_NEAR(res.stats.guide_scale[3], std::sqrt(v / ps.depth.storage().size()), 1e-9 * m);
  for (int j = 0; j < 3; ++j) EXPECT_EQ(res.stats.guide_scale[j], 1.0);  // unit normals spread < 1
}

// ---------------------------------------------------------------------------
// Defaults: the guide with the colour, demodulation, epsilon from the noise

Result run_with_defaults(const Frame& frame, const Params& params) {
  GuidedFilter f;
  Result r;
  static_cast<testutil::Result&>(r) = testutil::run_filter(f, frame, params, 1);
  r.stats = f.stats();
  return r;
}

// A flat grey frame (luminance 1) with white Gaussian noise of a known sigma per channel,
// normals and depth of a tilted plane.
Passes noisy_plane(int w, int h, double sigma, unsigned seed) {
  Passes ps;
  ps.colour = Image(w, h, 3);
  ps.normal = Image(w, h, 3);
  ps.depth = Image(w, h, 1);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, float(sigma));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) ps.colour.at(x, y, c) = 1.0f + noise(rng);
      ps.normal.at(x, y, 2) = 1.0f;
      ps.depth.at(x, y, 0) = 2.0f + 0.01f * float(x + y);
    }
  return ps;
}

TEST(GuidedFilterTest, DefaultsFollowTheNoise) {
  auto f = make_filter("guided");
  EXPECT_EQ(f->params().get_enum("guide"), "normal_depth_colour");
  EXPECT_EQ(f->params().get_int("radius"), 4);
  EXPECT_EQ(f->params().get_float("epsilon"), 0.0);  // 0 = from the noise
  EXPECT_EQ(f->params().get_float("epsilon_scale"), 30.0);
  EXPECT_TRUE(f->params().get_bool("demodulate"));
  // Other filters keep demodulate=false.
  EXPECT_FALSE(make_filter("bilateral")->params().get_bool("demodulate"));
  EXPECT_EQ(guided::auto_epsilon(30.0, 0.0), 1e-8);  // a noise-free frame: the smallest ridge
  EXPECT_EQ(guided::auto_epsilon(30.0, 0.01), 30.0 * 0.01);
  EXPECT_EQ(guided::auto_epsilon(30.0, kInf), 1e6);
  EXPECT_EQ(guided::auto_epsilon(30.0, kNaN), 1e6);
}

// The estimator against noise of a known variance: on a flat frame of luminance 1 the
// median relative noise variance is sigma^2 / (1 + 1e-3) (a median of chi^2 values
// rescaled to their mean: within 35%), it grows with sigma^2, and the level is 1.
TEST(GuidedFilterTest, FrameNoiseMeetsTheKnownNoise) {
  double last = 0;
  for (double sigma : {0.02, 0.05, 0.2}) {
    SCOPED_TRACE(sigma);
    const Passes ps = noisy_plane(96, 64, sigma, 40);
    const guided::FrameNoise fn = guided::frame_noise(ps.colour, 2);
    EXPECT_NEAR(fn.relative / (sigma * sigma), 1.0, 0.35);
    EXPECT_GT(fn.relative, last * 4.0);
    EXPECT_NEAR(fn.level, 1.0, 0.05);
    last = fn.relative;
  }
  Image grey(8, 8, 3);
  for (float& v : grey.storage()) v = 3.0f;
  EXPECT_EQ(guided::frame_noise(grey, 1).relative, 0.0);  // noise-free
  EXPECT_EQ(guided::frame_noise(grey, 1).level, 0.0);
}

// epsilon=0 runs exactly as epsilon = epsilon_scale x the median relative noise variance of
// the colour it gets; a noisier frame is smoothed harder (closer to its mean).
TEST(GuidedFilterTest, EpsilonFromTheNoiseIsTheDocumentedRule) {
  for (double sigma : {0.02, 0.2}) {
    SCOPED_TRACE(sigma);
    const Frame f = frame_of(noisy_plane(48, 32, sigma, 41));
    // At the frame's own exposure (the rule is on the colour the filter gets; prepare/exposure.h
    // would scale this plane, mean luminance above 1, by 1/2).
    const Params off = {{"exposure", std::string("off")}};
    const Result autoe = run_with_defaults(f, off);
    const double eps = guided::auto_epsilon(30.0, guided::frame_noise(f.image(Role::Colour), 1).relative);
    ASSERT_FALSE(autoe.stats.guide_scale.empty());
    EXPECT_NEAR(autoe.stats.guide_scale.back(), 1.0, 0.05);  // the colour guide: its level, not its std sigma
    // Without a colour channel in the guide the level plays no part: the rule is epsilon alone.
    const Params nd = testutil::with(off, {{"guide", std::string("normal_depth")}});
    expect_close(run_with_defaults(f, nd).out, run_with_defaults(f, testutil::with(nd, {{"epsilon", eps}})).out, 0.0,
                 "auto epsilon");
    bool noted = false;
    for (const std::string& n : autoe.notes) noted = noted || n.find("from the noise") != std::string::npos;
    EXPECT_TRUE(noted);
    // The residual noise: with epsilon ~ 30 noise variances of the colour guide, the slope on
    // the colour is about 1 / 31 on a flat frame, and the window mean leaves 1 / 81.
    double err = 0;
    for (float v : autoe.out.storage()) err += (v - 1.0) * (v - 1.0);
    err /= double(autoe.out.storage().size());
    EXPECT_LT(err, 0.1 * sigma * sigma);
  }
}

TEST(GuidedFilterTest, DemodulatesByDefaultWhenThereIsAnAlbedo) {
  const Frame f = frame_of(random_passes(16, 12, 42));
  const Result def = run_with_defaults(f, {});
  const Result on = run_with_defaults(f, {{"demodulate", true}});
  const Result off = run_with_defaults(f, {{"demodulate", false}});
  expect_close(def.out, on.out, 0.0, "default = demodulate=true");
  EXPECT_GT(testutil::changed(def.out, off.out), 0.1);
  // No albedo pass: the default skips the step with a note; demodulate=true given is an error.
  Passes no_albedo = random_passes(16, 12, 42);
  no_albedo.albedo = Image();
  const Frame g = frame_of(no_albedo);
  Result skipped;
  ASSERT_NO_THROW(skipped = run_with_defaults(g, {}));
  expect_close(skipped.out, run_with_defaults(g, {{"demodulate", false}}).out, 0.0, "skipped = demodulate=false");
  bool noted = false;
  for (const std::string& n : skipped.notes) noted = noted || n.find("demodulation skipped") != std::string::npos;
  EXPECT_TRUE(noted);
  GuidedFilter explicit_on;
  explicit_on.set("demodulate", true);
  explicit_on.commit();
  EXPECT_FALSE(explicit_on.missing_passes(g).empty());
  try {
    run_with_defaults(g, {{"demodulate", true}});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::MissingPass);
    EXPECT_NE(std::string(e.what()).find("demodulate=true"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("test.exr"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mcr
