// bilateral order=1 (weighted first-order regression on the features) against a
// per-pixel weighted least-squares oracle solved by Eigen, a closed form (colour
// affine in the features is reproduced exactly, order 0 is not), and stress cases.
#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>

#include "bilateral_reference.h"
#include "feature_filter_testutil.h"
#include "filters/image/bilateral.h"
#include "util/isa.h"

namespace mcr {
namespace {

using namespace testutil;

Params regression_params() {
  return {{"spatial_sigma", 1.5}, {"colour_sigma", 0.8}, {"normal_sigma", 1.0}, {"position_sigma", 1.5},
          {"albedo_sigma", 0.8},  {"use_depth", std::string("on")},          {"depth_sigma", 1.0},
          {"order", int64_t(1)},  {"ridge", 0.01}};
}

// The header's definition in double: weights from the features and the order-0
// result (the guide, from the brute-force order-0 reference, not from the filter under
// test), regressors scaled by sqrt(k_f), ridge lambda * sum w.
Image oracle(const Frame& frame, const Params& p) {
  Params p0 = p;
  p0["order"] = int64_t(0);
  const Image guide = bilateral_reference(frame, p0);
  BilateralFilter probe;
  for (const auto& [k, v] : p) probe.set(k, v);
  const ParamSet& ps = probe.params();
  const double ss = ps.get_float("spatial_sigma"), lambda = ps.get_float("ridge");
  const int r = int(std::ceil(3 * ss - 1e-6));
  const bool use_colour = ps.get_enum("use_colour") != "off";
  const double kc = 1.0 / (2 * std::pow(ps.get_float("colour_sigma"), 2));
  using F = OracleFeature;
  const std::vector<F> feats = oracle_features(frame, ps);
  int n = 1;
  for (const F& f : feats) n += f.ch;
  const Image& colour = frame.image(Role::Colour);
  Image out(frame.width, frame.height, 3);
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n, 3);
      double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, wsum = 0;
      for (int qy = std::max(0, y - r); qy <= std::min(frame.height - 1, y + r); ++qy)
        for (int qx = std::max(0, x - r); qx <= std::min(frame.width - 1, x + r); ++qx) {
          Eigen::VectorXd xq(n);
          xq(0) = 1;
          double e = (double(qx - x) * (qx - x) + double(qy - y) * (qy - y)) / (2 * ss * ss);
          int j = 1;
          for (const F& f : feats)
            for (int c = 0; c < f.ch; ++c, ++j) {
              xq(j) = (double(f.im->at(qx, qy, c)) - f.im->at(x, y, c)) * std::sqrt(f.k);
              e += xq(j) * xq(j);
            }
          if (use_colour)
            for (int c = 0; c < 3; ++c) e += kc * std::pow(double(guide.at(qx, qy, c)) - guide.at(x, y, c), 2);
          if (e >= 86) continue;  // the kernel's exp is exactly 0 there
          const double w = std::exp(-e);
          A += w * xq * xq.transpose();
          for (int c = 0; c < 3; ++c) {
            const double v = colour.at(qx, qy, c);
            B.col(c) += w * v * xq;
            lo[c] = std::min(lo[c], v);
            hi[c] = std::max(hi[c], v);
          }
          wsum += w;
        }
      for (int i = 1; i < n; ++i) A(i, i) += lambda * wsum;
      const Eigen::MatrixXd beta = A.ldlt().solve(B);
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = float(std::clamp(beta(0, c), lo[c], hi[c]));
    }
  return out;
}

void expect_near_images(const Image& got, const Image& want, double tol) {
  for (int y = 0; y < got.height(); ++y)
    for (int x = 0; x < got.width(); ++x)
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(got.at(x, y, c), want.at(x, y, c), tol * std::max(1.0f, std::fabs(want.at(x, y, c))))
            << "pixel " << x << "," << y << " channel " << c;
}

TEST(BilateralRegression, MatchesWeightedLeastSquaresOracle) {
  for (unsigned seed : {3u, 11u}) {
    const Frame f = full_frame(14, 11, seed);
    expect_near_images(run_filter<BilateralFilter>(f, regression_params()).out, oracle(f, regression_params()), 1e-5);
  }
  const Frame f = full_frame(9, 7, 5);
  const Params no_colour = with(regression_params(), {{"use_colour", std::string("off")}, {"ridge", 0.0}});
  expect_near_images(run_filter<BilateralFilter>(f, no_colour).out, oracle(f, no_colour), 1e-5);
}

// colour = affine function of albedo, position, normal: the first-order fit is exact
// at every pixel (ridge 0), the weighted mean is not.
TEST(BilateralRegression, ReproducesColourAffineInTheFeatures) {
  Frame f = full_frame(16, 12, 21);
  Image& col = pass_image(f, Role::Colour);
  const Image& alb = pass_image(f, Role::Albedo);
  const Image& pos = pass_image(f, Role::Position);
  const Image& nor = pass_image(f, Role::Normal);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c)
        col.at(x, y, c) = 0.2f + 0.3f * alb.at(x, y, c) + 0.1f * (c + 1) * pos.at(x, y, 0) - 0.2f * nor.at(x, y, 1);
  const Params p = with(regression_params(), {{"use_colour", std::string("off")}, {"use_depth", std::string("off")},
                                              {"ridge", 0.0}, {"position_sigma", 3.0}, {"normal_sigma", 2.0}});
  const Image first = run_filter<BilateralFilter>(f, p).out;
  const Image zero = run_filter<BilateralFilter>(f, with(p, {{"order", int64_t(0)}})).out;
  double worst0 = 0;
  for (std::size_t i = 0; i < col.storage().size(); ++i) {
    ASSERT_NEAR(first.storage()[i], col.storage()[i], 1e-4) << "value " << i;
    worst0 = std::max(worst0, double(std::fabs(zero.storage()[i] - col.storage()[i])));
  }
  EXPECT_GT(worst0, 1e-2) << "order 0 should average the ramp away";
}

TEST(BilateralRegression, ConstantImageAndDegenerateShapes) {
  for (float v : {0.0f, 0.375f, 1e-30f, 1e30f, FLT_MAX}) {
    Frame f = full_frame(11, 9, 4);
    for (float& c : pass_image(f, Role::Colour).storage()) c = v;
    Result r = run_filter<BilateralFilter>(f, regression_params());
    EXPECT_EQ(r.repaired, 0u);
    for (float o : r.out.storage()) ASSERT_NEAR(o, v, 1e-6 * std::fabs(v)) << "constant " << v;
  }
  for (auto [w, h] : {std::pair{1, 1}, std::pair{1, 9}, std::pair{9, 1}, std::pair{2, 1}}) {
    SCOPED_TRACE(testing::Message() << w << "x" << h);
    const Frame f = full_frame(w, h, unsigned(w * 7 + h));
    expect_near_images(run_filter<BilateralFilter>(f, regression_params()).out, oracle(f, regression_params()), 1e-5);
  }
}

TEST(BilateralRegression, ExtremeAndNonFiniteInputsGiveFiniteOutput) {
  Frame f = full_frame(20, 14, 8);
  pass_image(f, Role::Colour).at(3, 3, 0) = 1e30f;
  pass_image(f, Role::Colour).at(4, 3, 1) = 1e-30f;
  pass_image(f, Role::Colour).at(6, 6, 0) = kNaN;
  pass_image(f, Role::Colour).at(7, 6, 2) = kInf;
  pass_image(f, Role::Normal).at(10, 4, 1) = kNaN;
  pass_image(f, Role::Position).at(12, 8, 0) = -kInf;
  pass_image(f, Role::Position).at(2, 10, 2) = 1e30f;
  pass_image(f, Role::Albedo).at(15, 2, 0) = kNaN;
  pass_image(f, Role::Depth).at(5, 12, 0) = kInf;
  for (const Params& p : {regression_params(), with(regression_params(), {{"demodulate", true}, {"ridge", 0.0}})}) {
    Result r = run_filter<BilateralFilter>(f, p);
    EXPECT_EQ(r.repaired, 0u);
    for (float v : r.out.storage()) ASSERT_TRUE(std::isfinite(v));
  }
  // A pixel whose own feature is not finite gets the order-0 result (the documented fallback).
  Params p0 = regression_params();
  p0["order"] = int64_t(0);
  const Image zero = run_filter<BilateralFilter>(f, p0).out;
  const Image first = run_filter<BilateralFilter>(f, regression_params()).out;
  for (int c = 0; c < 3; ++c) EXPECT_EQ(first.at(10, 4, c), zero.at(10, 4, c));
}

TEST(BilateralRegression, ThreadsAndRegion) {
  const Frame f = full_frame(40, 30, 13);
  const Image one = run_filter<BilateralFilter>(f, regression_params(), 1).out;
  const Image two = run_filter<BilateralFilter>(f, regression_params(), 2).out;
  EXPECT_EQ(one.storage(), two.storage());
  const Roi roi{5, 4, 21, 17};
  const Image part = run_filter<BilateralFilter>(f, regression_params(), 2, roi).out;
  const Image& in = f.image(Role::Colour);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x)
      for (int c = 0; c < 3; ++c) {
        const bool inside = x >= roi.x0 && x < roi.x1 && y >= roi.y0 && y < roi.y1;
        ASSERT_EQ(part.at(x, y, c), inside ? one.at(x, y, c) : in.at(x, y, c)) << x << "," << y;
      }
}

// The generic and AVX2 builds of the fit against the oracle, and against each other to
// rounding (their sums may differ in the last bits); foveated (per-pixel spatial sigma
// and window) with the same bits for any thread count.
TEST(BilateralRegression, EveryInstructionSetAndFoveation) {
  const Frame f = full_frame(29, 17, 31);
  Frame g = f;
  pass_image(g, Role::Normal).at(3, 9, 2) = kNaN;
  const Params fov = with(regression_params(), {{"foveated", true}, {"spatial_sigma", 0.8},
                                                {"spatial_sigma_outer", 2.0}, {"inner_radius", 0.05}});
  std::vector<Image> outs, fovs;
  for (Isa level : {Isa::Generic, Isa::Avx2}) {
    if (int(level) > int(best_isa())) continue;
    const ScopedIsa use(level);
    SCOPED_TRACE(isa_name(level));
    outs.push_back(run_filter<BilateralFilter>(f, regression_params()).out);
    expect_near_images(outs.back(), oracle(f, regression_params()), 1e-5);
    fovs.push_back(run_filter<BilateralFilter>(g, fov, 1).out);
    EXPECT_EQ(fovs.back().storage(), run_filter<BilateralFilter>(g, fov, 2).out.storage());
    for (float v : fovs.back().storage()) ASSERT_TRUE(std::isfinite(v));
  }
  ASSERT_GE(outs.size(), 1u);
  for (std::size_t i = 1; i < outs.size(); ++i) {
    expect_near_images(outs[i], outs[0], 1e-5);
    expect_near_images(fovs[i], fovs[0], 1e-5);
  }
}

}  // namespace
}  // namespace mcr
