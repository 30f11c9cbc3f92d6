// Two things a real light field has that a smooth synthetic one does not: a light that ends
// (a neighbour's sample may map to a point beyond it, which is no light at all) and a
// perspective view (the screen linearisation e1, e2 drifts over a 32-pixel window; the world
// axes give the exact displacement). Both against closed forms, for sheared4d and sheared.
#include <gtest/gtest.h>

#include <cmath>

#include "filters/lightfield/sheared.h"
#include "filters/lightfield/sheared4d.h"
#include "lightfield_testutil.h"

namespace mcr {
namespace {

using testutil::make_lightfield;

using LfRun = void (*)(const LightField&, const lf::Options&, const Roi&, int, Image&, lf::Counts*);

Image run(LfRun fn, const LightField& lf) {
  lf::Options o;
  o.max_width = 32;
  Image out(lf.width, lf.height, 3);
  fn(lf, o, Roi::all(lf.width, lf.height), 0, out, nullptr);
  return out;
}

// A shadow edge of one slope s (x units = pixels) across the middle: lit where y1 + (X1 - 32)/s <= c. The pixel sees the
// Gaussian light (sigma 0.5) on [-1, 1]: h = the light's mass below min(1, c - (X1 - 32)/s) over its mass.
constexpr float kS = 4, kC = 0.2f;
LightField shadow_edge(int l) {
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 64, 8, l, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 5);
  testutil::set_slopes(lf, kS, kS);
  // A little shading across the light (odd in y2: the exact value keeps), so that no pixel is
  // "converged" and skipped.
  testutil::fill_values(lf, [](double X1, double, double y1, double y2) { return y1 + (X1 - 32) / kS <= kC ? 1.0 + 0.05 * y2 : 0.0; });
  return lf;
}

double light_mass(double a, double b, double sigma) {  // integral of the Gaussian over [a, b]
  return 0.5 * (std::erf(b / (sigma * std::sqrt(2.0))) - std::erf(a / (sigma * std::sqrt(2.0))));
}

Image shadow_edge_exact(const LightField& lf) {
  Image out(lf.width, lf.height, 3);
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double X1, X2;
    testutil::x_units(lf, p, &X1, &X2);
    const double top = std::min(1.0, std::max(-1.0, kC - (X1 - 32) / kS));
    const double v = light_mass(-1, top, 0.5) / light_mass(-1, 1, 0.5);
    out.data()[p * 3] = float(v), out.data()[p * 3 + 1] = float(0.8 * v), out.data()[p * 3 + 2] = float(0.6 * v);
  }
  return out;
}

TEST(LightFieldEdges, TheLightEndsWhereItsSamplesEnd) {
  // 16-pixel radius: a lit pixel gathers samples that map up to 4 light units away, past the
  // light's edge where its neighbours are in shadow. Without the cut those darken it.
  const LightField lf = shadow_edge(8);
  const Image exact = shadow_edge_exact(lf);
  const double own = testutil::rms_diff(exact, testutil::plain_mean(lf), 2);
  for (LfRun fn : {&sheared4d_lightfield, &sheared_lightfield}) {
    const double err = testutil::rms_diff(exact, run(fn, lf), 2);
    // The fully lit pixels stay lit.
    const Image got = run(fn, lf);
    double lit_err = 0;
    for (int x = 0; x < lf.width; ++x) {
      double X1, X2;
      testutil::x_units(lf, std::size_t(4 * lf.width + x), &X1, &X2);
      if (kC - (X1 - 32) / kS > 1.05 && kC - (X1 - 32) / kS < 3) lit_err = std::max(lit_err, std::fabs(double(got.at(x, 4, 0)) - 1.0));
    }
    std::printf("shadow edge: unweighted mean %.4f, filter %.4f, worst fully lit pixel %.4f\n", own, err, lit_err);
    EXPECT_LT(err, 0.02);
    EXPECT_LT(lit_err, 0.01);
  }
}

// A receiver seen in perspective: world X along the row grows faster than the pixel index
// (X = a px + b px^2), Y = a py, with screen axes e1 that hold at the image centre only (a
// renderer's one linearisation): the displacement from the world positions stays exact.
constexpr double kA = 0.05, kB = 0.002, kSlope = 8, kK = 20;
LightField perspective(bool world_axes) {
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 64, 8, 4, 1.0f, 0.2f, true);
  testutil::jitter_samples(lf, 9);
  testutil::set_slopes(lf, float(kSlope), float(kSlope));
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    const double px = double(p % 64) + 0.5, py = double(p / 64) + 0.5;
    lf.px[p] = float(kA * px + kB * px * px);
    lf.py[p] = float(kA * py);
    lf.e1x[p] = float(1.0 / (kA + 2 * kB * 32.0));  // the image centre's: off by up to 2x at the edges
    lf.e2y[p] = float(1.0 / kA);
  }
  if (world_axes) {
    lf.w1x.assign(lf.pixels(), 1.0f), lf.w1y.assign(lf.pixels(), 0.0f), lf.w1z.assign(lf.pixels(), 0.0f);
    lf.w2x.assign(lf.pixels(), 0.0f), lf.w2y.assign(lf.pixels(), 1.0f), lf.w2z.assign(lf.pixels(), 0.0f);
  }
  const std::size_t spp = std::size_t(lf.spp());
  for (std::size_t p = 0; p < lf.pixels(); ++p)
    for (std::size_t k = p * spp; k < (p + 1) * spp; ++k) {
      const double v = 0.5 + 0.3 * std::sin(kK * (lf.y1[k] + lf.px[p] / kSlope));
      lf.r[k] = float(v), lf.g[k] = float(0.8 * v), lf.b[k] = float(0.6 * v);
    }
  return lf;
}

TEST(LightFieldEdges, WorldAxesGiveTheExactDisplacementUnderPerspective) {
  const LightField with = perspective(true), without = perspective(false);
  ASSERT_TRUE(with.has_world_axes());
  ASSERT_FALSE(without.has_world_axes());
  Image exact(64, 8, 3);
  for (std::size_t p = 0; p < with.pixels(); ++p) {
    const double v = 0.5 + 0.3 * std::exp(-kK * kK * 0.04 / 2) * std::sin(kK * with.px[p] / kSlope);
    exact.data()[p * 3] = float(v), exact.data()[p * 3 + 1] = float(0.8 * v), exact.data()[p * 3 + 2] = float(0.6 * v);
  }
  for (LfRun fn : {&sheared4d_lightfield, &sheared_lightfield}) {
    const double a = testutil::rms_diff(exact, run(fn, with), 2);
    const double b = testutil::rms_diff(exact, run(fn, without), 2);
    std::printf("perspective: world axes %.4f, screen linearisation %.4f, own means %.4f\n", a, b,
                testutil::rms_diff(exact, testutil::plain_mean(with), 2));
    // Both far below the unfiltered means (0.05); with world axes the filter reads the positions
    // (a wrong sign or axis there loses the closed form).
    EXPECT_LT(a, 0.0075);  // 0.0091 and 0.0081 with the displacement's sign flipped
    EXPECT_LT(b, 0.02);
  }
}

}  // namespace
}  // namespace mcr

#include "kernels/lightfield_input.h"

namespace mcr {
namespace {

// The same shadow edge under shading that changes across the window (S = 1 + 0.5 sin(0.2 X)):
// with the modulation (S at each pixel) the filter shears the visibility alone and multiplies S
// back; without it, a neighbour's shading is carried into the pixel.
TEST(LightFieldEdges, TheModulationKeepsTheShadingOutOfTheShear) {
  auto shading = [](double X1) { return 1.0 + 0.5 * std::sin(0.2 * X1); };
  LightField lf = shadow_edge(8);
  const Image vis_exact = shadow_edge_exact(lf);
  Image exact(lf.width, lf.height, 3);
  const std::size_t spp = std::size_t(lf.spp());
  lf.mod_r.resize(lf.pixels()), lf.mod_g.resize(lf.pixels()), lf.mod_b.resize(lf.pixels());
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double X1, X2;
    testutil::x_units(lf, p, &X1, &X2);
    const float S = float(shading(X1));
    for (std::size_t k = p * spp; k < (p + 1) * spp; ++k) lf.r[k] *= S, lf.g[k] *= S, lf.b[k] *= S;
    lf.mod_r[p] = S, lf.mod_g[p] = 0.8f * S, lf.mod_b[p] = 0.6f * S;  // the unoccluded light, as the generator writes
    for (int c = 0; c < 3; ++c) exact.data()[p * 3 + std::size_t(c)] = vis_exact.data()[p * 3 + std::size_t(c)] * S;
  }
  auto filtered = [&](bool with_mod) {
    LightField in = lf;
    if (!with_mod) in.mod_r.clear(), in.mod_g.clear(), in.mod_b.clear();
    Frame frame;
    frame.width = in.width, frame.height = in.height, frame.path = "edge.exr";
    frame.deep = std::make_shared<DeepSamples>(encode_lightfield(in));
    const LightField dec = *lf::lightfield_input(frame, "sheared");
    Image out(in.width, in.height, 3);
    lf::Options o;
    sheared_lightfield(dec, o, Roi::all(in.width, in.height), 0, out, nullptr);
    lf::remodulate(dec, Roi::all(in.width, in.height), out);
    return out;
  };
  const double with = testutil::rms_diff(exact, filtered(true), 2), without = testutil::rms_diff(exact, filtered(false), 2);
  std::printf("shading across the window: with the modulation %.4f, without %.4f\n", with, without);
  EXPECT_LT(with, 0.015);
  EXPECT_LT(with, without / 2);
}

}  // namespace
}  // namespace mcr
