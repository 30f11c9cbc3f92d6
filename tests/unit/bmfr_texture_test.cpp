// BMFR at texture edges of a surface with a specular layer: colour = albedo x light +
// specular, so the demodulated illumination light + specular / albedo keeps the texture.
// The albedo_luminance column lets the fit follow it; the smooth features alone blur it
// across the edges (closed forms below).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "filters/registry.h"
#include "filters/temporal/bmfr.h"
#include "pass_testutil.h"
#include "util/isa.h"

namespace mcr {
namespace {

using testutil::make_pass;

constexpr int kSide = 32;                     // two 16-pixel blocks each way
constexpr float kDark = 0.2f, kBright = 0.8f;  // the checker's two grey albedos
constexpr float kSpec = 0.1f;                 // specular light, white, untextured
float light(int c) { return 0.6f * (1.0f + 0.2f * float(c)); }  // diffuse light per channel

// A flat wall facing the camera, a one-pixel checker of two grey albedos, constant light.
struct Checker {
  Image colour{kSide, kSide, 3}, albedo{kSide, kSide, 3}, position{kSide, kSide, 3}, normal{kSide, kSide, 3},
      motion{kSide, kSide, 4, 0.0f};
  Checker() {
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x) {
        const float a = (x + y) % 2 ? kBright : kDark;
        for (int c = 0; c < 3; ++c) {
          albedo.pixel(x, y)[c] = a;
          colour.pixel(x, y)[c] = a * light(c) + kSpec;
        }
        float* p = position.pixel(x, y);
        p[0] = 0.05f * float(x);
        p[1] = 0.05f * float(y);
        p[2] = 2.0f;
        float* n = normal.pixel(x, y);
        n[0] = 0.0f;
        n[1] = 0.0f;
        n[2] = 1.0f;
      }
  }
  Frame frame() const {
    Frame f;
    f.width = f.height = kSide;
    f.path = "checker.exr";
    f.passes.push_back(make_pass(Role::Colour, "Combined", colour));
    f.passes.push_back(make_pass(Role::Position, "Position", position, Space::World));
    f.passes.push_back(make_pass(Role::Normal, "Normal", normal, Space::World));
    f.passes.push_back(make_pass(Role::Albedo, "Denoising Albedo", albedo));
    f.passes.push_back(make_pass(Role::Motion, "Vector", motion));
    return f;
  }
};

// The fit alone: no regularisation noise, no grid displacement (whole 16-pixel blocks),
// no TAA, no step back; three frames of a still scene (phase I and III accumulate).
Image run(const Checker& s, bool albedo_luminance) {
  auto f = make_filter("bmfr");
  f->set("albedo_luminance", albedo_luminance);
  f->set("epsilon", 0.0);
  f->set("offsets", false);
  f->set("block_size", std::int64_t(16));
  f->set("taa", false);
  f->set("step_back", false);
  f->set("residual_k", 0.0);  // the fit alone (the detail stage would add back what it misses)
  f->commit();
  Image out;
  for (int k = 0; k < 3; ++k) out = f->execute(s.frame());
  return out;
}

// Largest |out - colour| / colour over the pixels of one albedo.
double worst_rel_error(const Checker& s, const Image& out, float albedo) {
  double e = 0;
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x)
      if (s.albedo.pixel(x, y)[0] == albedo)
        for (int c = 0; c < 3; ++c) {
          const double want = s.colour.pixel(x, y)[c];
          e = std::max(e, std::fabs(double(out.pixel(x, y)[c]) - want) / want);
        }
  return e;
}

TEST(BmfrTexture, TheAlbedoColumnFitsASpecularLayerOverTexture) {
  // Illumination = light + spec / albedo; with two albedos 1/albedo is affine in the albedo
  // (1/a = (d + b)/(d b) - a/(d b)), so [1, albedo luminance] spans it: the fit is exact.
  const Checker s;
  const Image out = run(s, true);
  EXPECT_LT(worst_rel_error(s, out, kDark), 1e-4);
  EXPECT_LT(worst_rel_error(s, out, kBright), 1e-4);
}

TEST(BmfrTexture, WithoutTheAlbedoColumnTheEdgesTakeTheBlockMean) {
  // The oracle of the failure the column fixes. The one-pixel checker is orthogonal over a
  // 16 x 16 block to 1, x, y, x^2, y^2 (the normal and depth are constant), so the fit is
  // the block mean light + spec (1/d + 1/b) / 2, and the remodulated colour misses by
  // spec (a/a' - 1) / 2 (a' the other albedo): -0.0375 on the dark squares, +0.15 on the
  // bright ones.
  const Checker s;
  const Image out = run(s, false);
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) {
      const float a = s.albedo.pixel(x, y)[0], other = a == kDark ? kBright : kDark;
      const double miss = double(kSpec) * (double(a) / other - 1.0) / 2.0;
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(double(out.pixel(x, y)[c]) - s.colour.pixel(x, y)[c], miss, 1e-4) << x << "," << y << " c" << c;
    }
}

TEST(BmfrTexture, EveryInstructionSetGivesTheSameBits) {
  // The albedo luminance column has its own AVX2 gather (bmfr_fit_features.cpp).
  Checker s;
  for (int y = 0; y < kSide; ++y)  // an albedo that is not grey, and a light that varies
    for (int x = 0; x < kSide; ++x)
      for (int c = 0; c < 3; ++c) {
        float& a = s.albedo.pixel(x, y)[c];
        a *= 0.7f + 0.1f * float((x * 7 + y * 3 + c * 5) % 7);
        s.colour.pixel(x, y)[c] = a * light(c) * (1.0f + 0.01f * float(x)) + kSpec;
      }
  std::vector<Image> outs;
  for (Isa level : {Isa::Generic, Isa::Avx2})
    if (int(level) <= int(best_isa())) {
      const ScopedIsa use(level);
      outs.push_back(run(s, true));
    }
  for (const Image& o : outs) EXPECT_EQ(o.storage(), outs.front().storage());
}

}  // namespace
}  // namespace mcr
