// BMFR: exact fits of colours that are linear in the features, stress inputs, thread
// independence, camera cuts and the parameter rules.
#include "filters/temporal/bmfr.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "filters/registry.h"
#include "pass_testutil.h"
#include "util/error.h"

namespace mcr {
namespace {

using testutil::make_pass;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// A curved surface seen by a static camera: positions, normals, and a colour that is
// exactly  0.4 + 0.2 n_x + 0.3 w_x - 0.1 w_y + 0.25 w_z^2  (per channel scaled).
struct Scene {
  Image colour, position, normal, albedo, motion;
};

Scene linear_scene(int w, int h, float shift = 0.0f) {
  Scene s{Image(w, h, 3), Image(w, h, 3), Image(w, h, 3), Image(w, h, 3, 1.0f), Image(w, h, 4)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float wx = 0.05f * (float(x) + shift), wy = 0.05f * float(y), wz = std::sin(0.13f * float(x) + 0.07f * float(y));
      float* p = s.position.pixel(x, y);
      p[0] = wx; p[1] = wy; p[2] = wz;
      float* n = s.normal.pixel(x, y);
      const float nx = std::cos(0.09f * float(x)) * 0.6f, nz = std::sqrt(1.0f - nx * nx);
      n[0] = nx; n[1] = 0.0f; n[2] = nz;
      const double v = 0.4 + 0.2 * nx + 0.3 * wx - 0.1 * wy + 0.25 * double(wz) * wz;
      for (int c = 0; c < 3; ++c) s.colour.pixel(x, y)[c] = float(v * (1.0 + 0.2 * c));
    }
  return s;
}

Frame frame_of(const Scene& s, bool albedo = true, bool motion = true) {
  Frame f;
  f.width = s.colour.width();
  f.height = s.colour.height();
  f.path = "synthetic.exr";
  f.passes.push_back(make_pass(Role::Colour, "Combined", s.colour));
  f.passes.push_back(make_pass(Role::Position, "Position", s.position, Space::World));
  f.passes.push_back(make_pass(Role::Normal, "Normal", s.normal, Space::World));
  if (albedo) f.passes.push_back(make_pass(Role::Albedo, "Denoising Albedo", s.albedo));
  if (motion) f.passes.push_back(make_pass(Role::Motion, "Vector", s.motion));
  return f;
}

std::unique_ptr<Filter> make_bmfr(std::initializer_list<std::pair<const char*, ParamValue>> params = {}) {
  auto f = make_filter("bmfr");
  for (const auto& kv : params) f->set(kv.first, kv.second);
  f->commit();
  return f;
}

double max_rel_error(const Image& got, const Image& want) {
  double e = 0;
  for (std::size_t i = 0; i < want.storage().size(); ++i)
    e = std::max(e, std::fabs(double(got.storage()[i]) - want.storage()[i]) / (std::fabs(want.storage()[i]) + 0.1));
  return e;
}

TEST(Bmfr, RegisteredWithItsTable) {
  const FilterInfo& info = filter_info("bmfr");
  EXPECT_TRUE(info.temporal);
  // Its own demodulation: the common step is not among its parameters.
  EXPECT_FALSE(info.steps.demodulate);
  EXPECT_TRUE(make_filter("bmfr")->params().has("albedo_floor"));
  EXPECT_FALSE(make_filter("bmfr")->params().has("demodulate"));
  EXPECT_FALSE(info.nonfinite_policy.empty());
}

TEST(Bmfr, ReproducesColourLinearInTheFeatures) {
  // Partial edge blocks (70 x 45 is not a multiple of any block size) and every offset.
  const Scene s = linear_scene(70, 45);
  for (const char* set : {"default", "with_albedo", "with_depth"}) {
    if (std::string(set) == "with_depth") continue;  // no depth pass here; see the error test
    for (double eps : {0.0, 0.01}) {
      auto f = make_bmfr({{"features", std::string(set)}, {"epsilon", eps}, {"block_size", std::int64_t(16)}});
      Image out;
      for (int k = 0; k < 6; ++k) out = f->execute(frame_of(s));
      EXPECT_LT(max_rel_error(out, s.colour), eps == 0 ? 1e-4 : 2e-2) << set << " eps " << eps;
      EXPECT_EQ(f->nonfinite_repaired(), 0u);
    }
  }
}

// Phase II by Eigen: on each block of the undisplaced grid (partial at the right and bottom),
// the least-squares fit of the colour to [1, n, w] over the block's pixels, clamped to
// [min(0, block min), max(0, block max)] as fit_clamp documents.
Image blockwise_first_order_fit(const Scene& s, int B) {
  const int w = s.colour.width(), h = s.colour.height();
  Image out(w, h, 3);
  for (int by = 0; by < h; by += B)
    for (int bx = 0; bx < w; bx += B) {
      const int x1 = std::min(w, bx + B), y1 = std::min(h, by + B);
      Eigen::MatrixXd A((x1 - bx) * (y1 - by), 7), Z(A.rows(), 3);
      for (int y = by, i = 0; y < y1; ++y)
        for (int x = bx; x < x1; ++x, ++i) {
          const float *n = s.normal.pixel(x, y), *p = s.position.pixel(x, y), *c = s.colour.pixel(x, y);
          A.row(i) << 1.0, n[0], n[1], n[2], p[0], p[1], p[2];
          Z.row(i) << c[0], c[1], c[2];
        }
      const Eigen::MatrixXd fit = A * A.colPivHouseholderQr().solve(Z);
      for (int y = by, i = 0; y < y1; ++y)
        for (int x = bx; x < x1; ++x, ++i)
          for (int c = 0; c < 3; ++c)
            out.at(x, y, c) = float(std::clamp(fit(i, c), std::min(0.0, Z.col(c).minCoeff()),
                                               std::max(0.0, Z.col(c).maxCoeff())));
    }
  return out;
}

TEST(Bmfr, FirstOrderFitIsTheBlockwiseLeastSquaresFit) {
  // First order cannot represent w_z^2: on the first frame (no history to accumulate), with no
  // regularisation noise, grid offset or TAA, the output is the per-block least-squares fit.
  const Scene s = linear_scene(70, 45);
  // step_back and the detail stage off: the fit itself is under test (on a still the step
  // back would blend it toward the input; the detail stage adds back what it misses).
  auto f = make_bmfr({{"features", std::string("first_order")}, {"epsilon", 0.0}, {"block_size", std::int64_t(16)},
                      {"offsets", false}, {"taa", false}, {"step_back", false}, {"residual_k", 0.0}});
  const Image want = blockwise_first_order_fit(s, 16);
  EXPECT_LT(max_rel_error(f->execute(frame_of(s)), want), 1e-5);
  EXPECT_GT(max_rel_error(want, s.colour), 1e-3);  // and the fit is not the input
}

TEST(Bmfr, OwnDemodulationReproducesATexturedLinearScene) {
  // bmfr divides by the albedo itself (albedo_demodulation, fused into phase I) and
  // multiplies back before TAA: illumination affine in the features times a checker
  // albedo (colour = albedo * illumination) is reproduced, the fit seeing the illumination;
  // without demodulation the checker is not in the feature span.
  Scene s = linear_scene(40, 40);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x)
      for (int c = 0; c < 3; ++c) {
        const float a = ((x / 3 + y / 3) % 2) ? 0.9f : 0.2f;
        s.albedo.pixel(x, y)[c] = a;
        s.colour.pixel(x, y)[c] *= a;
      }
  auto f = make_bmfr({{"epsilon", 0.0}, {"step_back", false}});  // the fit itself, not the step back
  EXPECT_LT(max_rel_error(f->execute(frame_of(s)), s.colour), 1e-4);
  auto plain = make_bmfr({{"epsilon", 0.0}, {"albedo_demodulation", false}, {"step_back", false}});
  EXPECT_GT(max_rel_error(plain->execute(frame_of(s)), s.colour), 1e-2);
}

TEST(Bmfr, MissingFeaturePassIsAnError) {
  auto f = make_bmfr({{"features", std::string("with_depth")}});
  try {
    f->execute(frame_of(linear_scene(8, 8)));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::MissingPass);
  }
}

void expect_finite(const Image& im, const std::string& what) {
  for (float v : im.storage()) ASSERT_TRUE(std::isfinite(v)) << what;
}

TEST(Bmfr, StressInputsStayFinite) {
  const std::vector<std::pair<int, int>> sizes = {{1, 1}, {1, 17}, {23, 1}, {2, 2}, {33, 31}};
  for (auto [w, h] : sizes) {
    for (int pass = 0; pass < 7; ++pass) {
      for (double eps : {0.0, 1e-4, 1.0}) {
        auto f = make_bmfr({{"epsilon", eps}, {"block_size", std::int64_t(8)}});
        for (int k = 0; k < 4; ++k) {
          Scene s = linear_scene(w, h, float(k));
          // Poison a few pixels in one pass (and everything in the last frame for pass 5).
          auto poison = [&](Image& im, float v) {
            for (std::size_t i = 0; i < im.storage().size(); i += 7) im.storage()[i] = (i / 7) % 2 ? v : -v;
          };
          switch (pass) {
            case 0: poison(s.colour, kNaN); poison(s.colour, kInf); break;
            case 1: poison(s.albedo, kNaN); break;
            case 2: poison(s.normal, kInf); break;
            case 3: poison(s.position, kNaN); break;
            case 4: poison(s.motion, kNaN); break;
            case 5: std::fill(s.albedo.storage().begin(), s.albedo.storage().end(), 0.0f); break;
            case 6:
              for (float& v : s.colour.storage()) v *= 1e30f;
              for (float& v : s.position.storage()) v *= 1e30f;
              break;
          }
          const Image out = f->execute(frame_of(s));
          const std::string what = std::to_string(w) + "x" + std::to_string(h) + " pass " + std::to_string(pass) +
                                   " eps " + std::to_string(eps) + " frame " + std::to_string(k);
          expect_finite(out, what);
          EXPECT_EQ(f->nonfinite_repaired(), 0u) << what;
        }
      }
    }
  }
}

TEST(Bmfr, AllColourNonFiniteGivesZeroNotNaN) {
  Scene s = linear_scene(20, 20);
  std::fill(s.colour.storage().begin(), s.colour.storage().end(), kNaN);
  auto f = make_bmfr();
  const Image out = f->execute(frame_of(s));
  for (float v : out.storage()) EXPECT_EQ(v, 0.0f);
  EXPECT_EQ(f->nonfinite_repaired(), 0u);
}

TEST(Bmfr, SameResultForOneAndTwoThreads) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto f1 = make_bmfr(), f2 = make_bmfr();
  for (int k = 0; k < 4; ++k) {
    Scene s = linear_scene(75, 50, float(k));
    for (int y = 0; y < 50; ++y)
      for (int x = 0; x < 75; ++x) s.motion.pixel(x, y)[0] = 1.0f;  // camera moving by one pixel
    for (float& v : s.colour.storage()) v *= 2.0f * u(rng);
    ExecOptions one, two;
    one.nthreads = 1;
    two.nthreads = 2;
    const Image a = f1->execute(frame_of(s), one), b = f2->execute(frame_of(s), two);
    ASSERT_EQ(a.storage(), b.storage()) << "frame " << k;
  }
}

TEST(Bmfr, DetectsCameraCutAndSizeChange) {
  auto f = make_bmfr();
  auto* b = dynamic_cast<BmfrFilter*>(f.get());
  ASSERT_NE(b, nullptr);
  Scene s = linear_scene(40, 30);
  f->execute(frame_of(s));
  f->execute(frame_of(s));
  EXPECT_FALSE(b->last_cut());
  // Another shot: every position elsewhere.
  Scene t = s;
  for (float& v : t.position.storage()) v += 50.0f;
  for (float& v : t.colour.storage()) v = 2.0f;
  const Image out = f->execute(frame_of(t));
  EXPECT_TRUE(b->last_cut());
  // Restarted: the old shot's light does not leak in.
  for (float v : out.storage()) EXPECT_NEAR(v, 2.0f, 1e-3);
  f->execute(frame_of(t));
  EXPECT_FALSE(b->last_cut());
  // Size change: runs and restarts.
  const Image small = f->execute(frame_of(linear_scene(17, 9)));
  EXPECT_EQ(small.width(), 17);
  expect_finite(small, "size change");
}

TEST(Bmfr, RoiKeepsTheInputOutside) {
  const Scene s = linear_scene(30, 20);
  auto f = make_bmfr();
  ExecOptions eo;
  eo.roi = {5, 5, 12, 9};
  const Image out = f->execute(frame_of(s), eo);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 30; ++x) {
      const bool in = x >= 5 && x < 12 && y >= 5 && y < 9;
      if (!in) EXPECT_EQ(out.at(x, y, 0), s.colour.at(x, y, 0));
    }
}

}  // namespace
}  // namespace mcr
