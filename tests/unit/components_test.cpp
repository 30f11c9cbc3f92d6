// components=light_passes (pipeline/components.h, pipeline/reconstruction.h): each light
// component filtered alone, times its colour pass, plus emission and environment. Oracles:
// the box mean written out plainly per component; the components' own filters run alone on
// frames the test builds; the sum of the layers recomputed here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "expect_error.h"
#include "feature_filter_testutil.h"
#include "io/channel_roles.h"
#include "pipeline/components.h"
#include "pipeline/reconstruction.h"

namespace mcr {
namespace {

using testutil::add_pass;
using testutil::box_oracle;
using testutil::random_image;

struct Parts {
  Role direct, indirect, colour;
};
const Parts kParts[3] = {{Role::DiffuseDirect, Role::DiffuseIndirect, Role::DiffuseColour},
                         {Role::GlossyDirect, Role::GlossyIndirect, Role::GlossyColour},
                         {Role::TransmissionDirect, Role::TransmissionIndirect, Role::TransmissionColour}};

Image sum_of(const Image& a, const Image& b) {
  Image s(a.width(), a.height(), 3);
  for (std::size_t i = 0; i < s.storage().size(); ++i) s.storage()[i] = a.storage()[i] + b.storage()[i];
  return s;
}

// A frame with every light pass (component k's light scaled by 1 + 3k, so the three differ
// in level), Combined by Blender's identity, and the features bmfr and accumulation need.
Frame light_frame(int w, int h, unsigned seed) {
  Frame f;
  f.width = w;
  f.height = h;
  f.path = "lights.exr";
  Image combined(w, h, 3);
  for (int k = 0; k < 3; ++k) {
    Image d = random_image(w, h, 3, seed + 10 * k, 0.0f, 1.0f + 3.0f * k);
    Image i = random_image(w, h, 3, seed + 10 * k + 1, 0.0f, 0.5f);
    Image c = random_image(w, h, 3, seed + 10 * k + 2, 0.05f, 0.9f);
    const Image light = sum_of(d, i);
    for (std::size_t j = 0; j < combined.storage().size(); ++j) combined.storage()[j] += light.storage()[j] * c.storage()[j];
    add_pass(f, kParts[k].direct, d);
    add_pass(f, kParts[k].indirect, i);
    add_pass(f, kParts[k].colour, c);
  }
  Image emit = random_image(w, h, 3, seed + 40, 0.0f, 0.3f), env = random_image(w, h, 3, seed + 41, 0.0f, 0.2f);
  for (std::size_t j = 0; j < combined.storage().size(); ++j) combined.storage()[j] += emit.storage()[j] + env.storage()[j];
  add_pass(f, Role::Emission, emit);
  add_pass(f, Role::Environment, env);
  add_pass(f, Role::Colour, combined);
  Image n(w, h, 3, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) n.at(x, y, x < w / 2 ? 2 : 0) = 1.0f;
  add_pass(f, Role::Normal, n);
  add_pass(f, Role::Position, random_image(w, h, 3, seed + 50, 0.0f, 0.05f));
  add_pass(f, Role::Albedo, random_image(w, h, 3, seed + 51, 0.1f, 1.0f));
  add_pass(f, Role::Motion, Image(w, h, 2, 0.0f));
  add_pass(f, Role::Variance, Image(w, h, 1, 100.0f));
  return f;
}

// Component k of `f` as an ordinary frame, built here: colour = direct + indirect (only one
// of them for `part`; times the colour pass when `remodulated`), albedo = its colour pass,
// the other features.
Frame alone(const Frame& f, int k, LightPart part = LightPart::Both, bool remodulated = false) {
  Frame g;
  g.width = f.width;
  g.height = f.height;
  g.path = f.path;
  const Image& d = f.image(kParts[k].direct);
  const Image& i = f.image(kParts[k].indirect);
  Image light = part == LightPart::Direct ? d : part == LightPart::Indirect ? i : sum_of(d, i);
  if (remodulated)
    for (std::size_t j = 0; j < light.storage().size(); ++j) light.storage()[j] *= f.image(kParts[k].colour).storage()[j];
  add_pass(g, Role::Colour, light);
  add_pass(g, Role::Albedo, f.image(kParts[k].colour));
  for (Role r : {Role::Normal, Role::Position, Role::Motion}) add_pass(g, r, f.image(r));
  return g;
}

std::unique_ptr<Reconstruction> reconstruction(const std::string& filter,
                                               std::vector<std::pair<std::string, std::string>> params,
                                               bool light_passes, bool accumulate = false) {
  if (light_passes) params.push_back({"components", "light_passes"});
  return std::make_unique<Reconstruction>(make_committed_filter(filter, params), accumulate);
}

TEST(Components, BoxPerComponentTimesItsColourPlusEmissionAndEnvironment) {
  const Frame f = light_frame(23, 17, 7);
  auto rec = reconstruction("box", {{"radius", "2"}, {"step_back", "false"}}, true);
  std::vector<ComponentImage> layers;
  const Image beauty = rec->run(f, {}, &layers);
  ASSERT_EQ(layers.size(), 5u);
  for (int k = 0; k < 3; ++k) {
    const Image want_light = box_oracle(sum_of(f.image(kParts[k].direct), f.image(kParts[k].indirect)), 2);
    const Image& col = f.image(kParts[k].colour);
    for (std::size_t j = 0; j < col.storage().size(); ++j) {
      const double want = double(want_light.storage()[j]) * col.storage()[j];
      ASSERT_NEAR(layers[std::size_t(k)].rgb.storage()[j], want, 1e-5 * std::abs(want) + 1e-7) << k << " " << j;
    }
  }
  EXPECT_EQ(layers[3].rgb.storage(), f.image(Role::Emission).storage());
  EXPECT_EQ(layers[4].rgb.storage(), f.image(Role::Environment).storage());
  // The beauty is the layers' sum: compositors add them up and must get it back.
  for (std::size_t j = 0; j < beauty.storage().size(); ++j) {
    double s = 0;
    for (const ComponentImage& l : layers) s += l.rgb.storage()[j];
    ASSERT_NEAR(beauty.storage()[j], s, 1e-5 * std::abs(s)) << j;
  }
  // Not the beauty filtered whole (the colour passes vary per pixel).
  const Image whole = reconstruction("box", {{"radius", "2"}, {"step_back", "false"}}, false)->run(f);
  double diff = 0;
  for (std::size_t j = 0; j < whole.storage().size(); ++j) diff = std::max(diff, double(std::abs(whole.storage()[j] - beauty.storage()[j])));
  EXPECT_GT(diff, 1e-3);
  bool noted = false;
  for (const std::string& n : rec->notes()) noted = noted || n.find("components=light_passes") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(Components, DemodulationIsTurnedOffAndSaidSo) {
  const Frame f = light_frame(16, 12, 3);
  auto on = reconstruction("atrous", {{"demodulate", "true"}}, true);
  auto off = reconstruction("atrous", {}, true);
  EXPECT_EQ(on->run(f).storage(), off->run(f).storage());
  EXPECT_FALSE(on->filter().params().get_bool("demodulate"));
  bool noted = false;
  for (const std::string& n : on->notes()) noted = noted || n.find("demodulate=true has no effect") != std::string::npos;
  EXPECT_TRUE(noted);
  // bmfr divides by its albedo itself (and multiplies back before its TAA): it keeps that
  // and is given each component times its colour pass (TemporalHistoriesArePerComponent).
  auto bmfr = reconstruction("bmfr", {}, true);
  EXPECT_TRUE(bmfr->filter().params().get_bool("albedo_demodulation"));
  EXPECT_TRUE(bmfr->filter().demodulates_itself());
  EXPECT_FALSE(reconstruction("bmfr", {{"albedo_demodulation", "false"}}, true)->filter().demodulates_itself());
  EXPECT_NE(bmfr->parameters_text().find("components=light_passes"), std::string::npos);
}

TEST(Components, EveryMissingLightPassIsNamedWithTheFile) {
  Frame f = light_frame(8, 8, 1);
  f.passes.erase(std::remove_if(f.passes.begin(), f.passes.end(), [](const Pass& p) {
                   return p.role == Role::GlossyIndirect || p.role == Role::Environment;
                 }),
                 f.passes.end());
  auto rec = reconstruction("bmfr", {}, true);
  testutil::expect_error(Errc::MissingPass, {"GlossInd", "glossy_indirect", "Env", "environment", "lights.exr"},
                         [&] { rec->run(f); });
  const std::string msg = testutil::expect_error(Errc::MissingPass, [&] { rec->run(f); });
  EXPECT_EQ(msg.find("DiffDir"), std::string::npos) << msg;
  // Without light passes nothing is asked of them.
  EXPECT_NO_THROW(reconstruction("box", {}, false)->run(f));
}

// One history per stage: two frames through the split equal each stage's own filter run
// alone on the same two frames (diffuse: direct + indirect; glossy and transmission: the
// direct and the indirect light each alone, added after filtering). bmfr, which divides by
// its albedo itself, is given each light times its colour pass and its result is the layer;
// any other filter (and bmfr with albedo_demodulation=false) the light, times the colour after.
TEST(Components, TemporalHistoriesArePerComponent) {
  const Frame f1 = light_frame(24, 20, 11), f2 = light_frame(24, 20, 12);
  struct Case {
    std::string filter;
    std::vector<std::pair<std::string, std::string>> params;
    bool accumulate, remodulated;
  };
  const std::pair<std::string, std::string> bs{"block_size", "8"}, fe{"features", "with_albedo"};
  for (const Case& c : {Case{"bmfr", {bs, fe}, false, true}, Case{"bmfr", {bs, fe, {"albedo_demodulation", "false"}}, false, false},
                        Case{"box", {{"radius", "0"}, {"step_back", "false"}}, true, false}}) {
    SCOPED_TRACE(c.filter + (c.remodulated ? " remodulated" : ""));
    auto split = reconstruction(c.filter, c.params, true, c.accumulate);
    // [k][0]: diffuse direct + indirect, else direct; [k][1]: indirect.
    std::unique_ptr<Reconstruction> single[3][2];
    for (auto& k : single)
      for (auto& p : k) p = reconstruction(c.filter, c.params, false, c.accumulate);
    std::vector<ComponentImage> layers;
    for (const Frame* f : {&f1, &f2}) {
      split->run(*f, {}, &layers);
      for (int k = 0; k < 3; ++k) {
        Image light;
        if (k == 0) {
          light = single[k][0]->run(alone(*f, k, LightPart::Both, c.remodulated));
        } else {
          light = single[k][0]->run(alone(*f, k, LightPart::Direct, c.remodulated));
          const Image indirect = single[k][1]->run(alone(*f, k, LightPart::Indirect, c.remodulated));
          for (std::size_t j = 0; j < light.storage().size(); ++j) light.storage()[j] += indirect.storage()[j];
        }
        const Image& col = f->image(kParts[k].colour);
        for (std::size_t j = 0; j < col.storage().size(); ++j)
          ASSERT_EQ(layers[std::size_t(k)].rgb.storage()[j],
                    c.remodulated ? light.storage()[j] : light.storage()[j] * col.storage()[j])
              << k << " " << j;
      }
    }
  }
}

// Diffuse light is filtered as direct + indirect, glossy and transmission light as direct and
// indirect apart. Oracle: box with radius 0 and clamp=1 keeps min(v, 1) per channel, so
// min(d + i, 1) (summed) and min(d, 1) + min(i, 1) (apart) differ where d + i > 1.
TEST(Components, GlossyAndTransmissionDirectAndIndirectAreFilteredApart) {
  const Frame f = light_frame(13, 9, 21);
  auto rec = reconstruction("box", {{"radius", "0"}, {"step_back", "false"}, {"firefly_k", "0"}, {"clamp", "1"}}, true);
  std::vector<ComponentImage> layers;
  rec->run(f, {}, &layers);
  auto clamp1 = [](float v) { return std::min(std::max(v, -1.0f), 1.0f); };
  int apart_differs = 0;
  for (int k = 0; k < 3; ++k) {
    const Image& d = f.image(kParts[k].direct);
    const Image& i = f.image(kParts[k].indirect);
    const Image& col = f.image(kParts[k].colour);
    for (std::size_t j = 0; j < col.storage().size(); ++j) {
      const float dj = d.storage()[j], ij = i.storage()[j];
      const float light = k == 0 ? clamp1(dj + ij) : clamp1(dj) + clamp1(ij);
      ASSERT_EQ(layers[std::size_t(k)].rgb.storage()[j], light * col.storage()[j]) << k << " " << j;
      apart_differs += k > 0 && clamp1(dj) + clamp1(ij) != clamp1(dj + ij);
    }
  }
  EXPECT_GT(apart_differs, 10);  // the frame does tell the two apart
  // The notes name the stage they come from.
  std::string notes;
  for (const std::string& n : rec->notes()) notes += n + "\n";
  EXPECT_NE(notes.find("direct and indirect apart"), std::string::npos) << notes;
  std::vector<std::string> names;
  for (const LightStage& s : light_stages()) names.push_back(light_stage_name(s));
  const std::vector<std::string> want = {"diffuse", "glossy direct", "glossy indirect", "transmission direct",
                                         "transmission indirect"};
  EXPECT_EQ(names, want);
}

TEST(Components, ComponentFrameCarriesFeaturesItsColourAsAlbedoNotTheBeautysVariance) {
  const Frame f = light_frame(8, 6, 5);
  const Frame g = component_frame(f, light_components()[1], 1);
  EXPECT_EQ(g.image(Role::Colour).storage(), sum_of(f.image(Role::GlossyDirect), f.image(Role::GlossyIndirect)).storage());
  for (Role r : {Role::Normal, Role::Position, Role::Albedo, Role::Motion}) EXPECT_TRUE(g.has(r)) << role_name(r);
  EXPECT_EQ(g.image(Role::Albedo).storage(), f.image(Role::GlossyColour).storage());  // not Denoising Albedo
  EXPECT_FALSE(g.has(Role::Variance));
  // The colour passes go along (bmfr tells mirrors by them); the other light passes do not.
  EXPECT_TRUE(g.has(Role::GlossyColour) && g.has(Role::DiffuseColour));
  EXPECT_FALSE(g.has(Role::GlossyDirect) || g.has(Role::DiffuseDirect) || g.has(Role::Emission));
  // A part alone: its light only, the same features.
  const Frame d = component_frame(f, light_components()[1], 1, LightPart::Direct);
  const Frame i = component_frame(f, light_components()[1], 1, LightPart::Indirect);
  EXPECT_EQ(d.image(Role::Colour).storage(), f.image(Role::GlossyDirect).storage());
  EXPECT_EQ(i.image(Role::Colour).storage(), f.image(Role::GlossyIndirect).storage());
  EXPECT_EQ(i.image(Role::Albedo).storage(), f.image(Role::GlossyColour).storage());
}

TEST(Components, NothingNonFiniteLeavesTheRecombination) {
  Frame f = light_frame(6, 5, 9);
  for (Pass& p : f.passes) {
    if (p.role == Role::DiffuseColour) p.image.at(1, 1, 0) = testutil::kNaN;
    if (p.role == Role::Emission) p.image.at(2, 2, 1) = testutil::kInf;
    if (p.role == Role::GlossyColour) p.image.at(3, 3, 2) = 3e38f;
  }
  std::vector<ComponentImage> layers;
  const Image beauty = reconstruction("box", {}, true)->run(f, {}, &layers);
  for (float v : beauty.storage()) ASSERT_TRUE(std::isfinite(v));
  for (const ComponentImage& l : layers)
    for (float v : l.rgb.storage()) ASSERT_TRUE(std::isfinite(v)) << l.name;
}

TEST(Components, BlenderLightPassNamesHaveRoles) {
  const std::vector<std::string> names = {"ViewLayer.DiffDir.R", "ViewLayer.DiffDir.G", "ViewLayer.DiffDir.B",
                                          "ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.B",
                                          "ViewLayer.Emit.R",    "ViewLayer.Emit.G",    "ViewLayer.Emit.B"};
  std::vector<Role> roles;
  for (const ChannelGroup& g : group_channels(names))
    for (const RoleMatch& m : classify_group(g)) roles.push_back(m.role);
  const std::vector<Role> want = {Role::DiffuseDirect, Role::Albedo, Role::DiffuseColour, Role::Emission};
  EXPECT_EQ(roles, want);  // DiffCol: the diffuse colour pass and still the albedo of last resort
  EXPECT_EQ(role_from_name("transmission_color"), Role::TransmissionColour);
  EXPECT_EQ(role_from_name("environment"), Role::Environment);
}

}  // namespace
}  // namespace mcr
