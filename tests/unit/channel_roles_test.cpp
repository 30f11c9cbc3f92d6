// Role detection from channel names: Blender multilayer, plain files, short names.
#include "io/channel_roles.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "blender_channels_testutil.h"

namespace mcr {
namespace {

const ChannelGroup* find_group(const std::vector<ChannelGroup>& groups, const std::string& name) {
  for (const ChannelGroup& g : groups)
    if (g.name() == name) return &g;
  return nullptr;
}

// Roles of the group named `name` among `channels`, with the channel names each role takes.
std::vector<std::pair<Role, std::vector<std::string>>> roles_of(const std::vector<std::string>& channels,
                                                                const std::string& name) {
  const auto groups = group_channels(channels);
  const ChannelGroup* g = find_group(groups, name);
  EXPECT_NE(g, nullptr) << "no group " << name;
  std::vector<std::pair<Role, std::vector<std::string>>> out;
  if (!g) return out;
  for (const RoleMatch& m : classify_group(*g)) {
    std::vector<std::string> names;
    for (int i : m.indices) names.push_back(channels[std::size_t(i)]);
    out.emplace_back(m.role, names);
  }
  return out;
}

using Names = std::vector<std::string>;

TEST(ChannelRolesTest, GroupsSplitLayerPassAndSuffix) {
  const Names ch = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "R", "My.Layer.Denoising Normal.X",
                    "N.X", "ViewLayer.Combined.B", "Z"};
  const auto groups = group_channels(ch);
  ASSERT_EQ(groups.size(), 4u);
  const ChannelGroup* vl = find_group(groups, "ViewLayer.Combined");
  ASSERT_NE(vl, nullptr);
  EXPECT_EQ(vl->layer, "ViewLayer");
  EXPECT_EQ(vl->pass, "Combined");
  EXPECT_EQ(vl->indices, (std::vector<int>{0, 1, 5}));
  EXPECT_EQ(vl->suffixes, (Names{"R", "G", "B"}));
  const ChannelGroup* dotted = find_group(groups, "My.Layer.Denoising Normal");
  ASSERT_NE(dotted, nullptr);  // a view layer name may itself contain dots
  EXPECT_EQ(dotted->layer, "My.Layer");
  EXPECT_EQ(dotted->pass, "Denoising Normal");
  const ChannelGroup* n = find_group(groups, "N");
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(n->layer, "");
  EXPECT_EQ(n->suffixes, (Names{"X"}));
  const ChannelGroup* bare = find_group(groups, "");
  ASSERT_NE(bare, nullptr);
  EXPECT_EQ(bare->indices, (std::vector<int>{2, 6}));
}

TEST(ChannelRolesTest, BlenderMultilayerPassesWithAnyLayerName) {
  for (const std::string layer : {"ViewLayer", "RenderLayer", "Main Layer", "shot.v2"}) {
    SCOPED_TRACE(layer);
    const std::string p = layer + ".";
    const Names ch = testutil::blender_layer(layer);
    auto combined = roles_of(ch, p + "Combined");
    ASSERT_EQ(combined.size(), 2u);
    EXPECT_EQ(combined[0].first, Role::Colour);
    EXPECT_EQ(combined[0].second, (Names{p + "Combined.R", p + "Combined.G", p + "Combined.B"}));
    EXPECT_EQ(combined[1].first, Role::Alpha);
    EXPECT_EQ(combined[1].second, (Names{p + "Combined.A"}));

    // The passes with one role each; where suffixes are given, the channels it takes.
    struct Single {
      const char* pass;
      Role role;
      Names suffixes;  // empty: the channels are not checked
    };
    const Single singles[] = {
        {"Denoising Albedo", Role::Albedo, {}}, {"Normal", Role::Normal, {"X", "Y", "Z"}},
        {"Denoising Normal", Role::Normal, {}}, {"Position", Role::Position, {}},
        {"Depth", Role::Depth, {}},             {"Denoising Depth", Role::Depth, {}},
        {"Vector", Role::Motion, {"X", "Y", "Z", "W"}},
    };
    for (const Single& s : singles) {
      SCOPED_TRACE(s.pass);
      const std::string group = p + s.pass;
      auto r = roles_of(ch, group);
      ASSERT_EQ(r.size(), 1u);
      EXPECT_EQ(r[0].first, s.role);
      if (s.suffixes.empty()) continue;
      Names want;
      for (const std::string& suffix : s.suffixes) want.push_back(group + "." + suffix);
      EXPECT_EQ(r[0].second, want);
    }
  }
}

TEST(ChannelRolesTest, SpacesAndPrioritiesOfBlenderCandidates) {
  const Names ch = {"L.Normal.X", "L.Normal.Y", "L.Normal.Z", "L.Denoising Normal.X", "L.Denoising Normal.Y",
                    "L.Denoising Normal.Z", "L.Depth.Z", "L.Denoising Depth.Z", "L.Albedo.R", "L.Albedo.G",
                    "L.Albedo.B", "L.Denoising Albedo.R", "L.Denoising Albedo.G", "L.Denoising Albedo.B"};
  const auto groups = group_channels(ch);
  auto match = [&](const std::string& name) {
    auto m = classify_group(*find_group(groups, name));
    EXPECT_EQ(m.size(), 1u) << name;
    return m.at(0);
  };
  EXPECT_EQ(match("L.Normal").space, Space::World);
  EXPECT_EQ(match("L.Denoising Normal").space, Space::Camera);
  EXPECT_GT(match("L.Denoising Normal").priority, match("L.Normal").priority);
  EXPECT_GT(match("L.Denoising Albedo").priority, match("L.Albedo").priority);
  EXPECT_GT(match("L.Depth").priority, match("L.Denoising Depth").priority);
}

TEST(ChannelRolesTest, ChannelOrderInTheFileDoesNotMatter) {
  // EXR stores channels sorted by name: B before G before R.
  const Names ch = {"L.Combined.A", "L.Combined.B", "L.Combined.G", "L.Combined.R", "L.Normal.Z", "L.Normal.X",
                    "L.Normal.Y"};
  auto c = roles_of(ch, "L.Combined");
  ASSERT_GE(c.size(), 1u);
  EXPECT_EQ(c[0].second, (Names{"L.Combined.R", "L.Combined.G", "L.Combined.B"}));
  auto n = roles_of(ch, "L.Normal");
  ASSERT_EQ(n.size(), 1u);
  EXPECT_EQ(n[0].second, (Names{"L.Normal.X", "L.Normal.Y", "L.Normal.Z"}));
}

TEST(ChannelRolesTest, PlainRgbazGivesColourAlphaDepth) {
  const Names ch = {"A", "B", "G", "R", "Z"};
  auto r = roles_of(ch, "");
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].first, Role::Colour);
  EXPECT_EQ(r[0].second, (Names{"R", "G", "B"}));
  EXPECT_EQ(r[1].first, Role::Alpha);
  EXPECT_EQ(r[1].second, (Names{"A"}));
  EXPECT_EQ(r[2].first, Role::Depth);
  EXPECT_EQ(r[2].second, (Names{"Z"}));
}

TEST(ChannelRolesTest, PlainRgbWithoutAlphaOrDepth) {
  auto r = roles_of({"R", "G", "B"}, "");
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, Role::Colour);
  EXPECT_TRUE(roles_of({"R", "G"}, "").empty());  // two colour channels are not a colour pass
}

TEST(ChannelRolesTest, ShortAndLowerCaseNames) {
  struct Case {
    Names channels;
    std::string group;
    Role role;
  };
  const Case cases[] = {
      {{"N.X", "N.Y", "N.Z"}, "N", Role::Normal},
      {{"albedo.R", "albedo.G", "albedo.B"}, "albedo", Role::Albedo},
      {{"P.X", "P.Y", "P.Z"}, "P", Role::Position},
      {{"normal.x", "normal.y", "normal.z"}, "normal", Role::Normal},
      {{"Normals.R", "Normals.G", "Normals.B"}, "Normals", Role::Normal},
      {{"depth.V"}, "depth", Role::Depth},
      {{"Variance.V"}, "Variance", Role::Variance},
      {{"motion.u", "motion.v"}, "motion", Role::Motion},
      {{"beauty.R", "beauty.G", "beauty.B"}, "beauty", Role::Colour},
      {{"sample_count.Y"}, "sample_count", Role::SampleCount},
  };
  for (const Case& c : cases) {
    auto r = roles_of(c.channels, c.group);
    ASSERT_GE(r.size(), 1u) << c.group;
    EXPECT_EQ(r[0].first, c.role) << c.group;
    EXPECT_EQ(r[0].second.size(), std::size_t(role_channels(c.role))) << c.group;
  }
}

TEST(ChannelRolesTest, UnknownOrIncompleteGroupsGiveNoRole) {
  EXPECT_TRUE(roles_of({"L.AO.R", "L.AO.G", "L.AO.B"}, "L.AO").empty());
  EXPECT_TRUE(roles_of({"L.Normal.X", "L.Normal.Y"}, "L.Normal").empty());  // Z missing
  EXPECT_TRUE(roles_of({"L.CryptoObject00.R", "L.CryptoObject00.G"}, "L.CryptoObject00").empty());
}

TEST(ChannelRolesTest, MotionTakesXyAndKeepsZwWhenPresent) {
  auto xy = roles_of({"L.Vector.X", "L.Vector.Y"}, "L.Vector");
  ASSERT_EQ(xy.size(), 1u);
  EXPECT_EQ(xy[0].second, (Names{"L.Vector.X", "L.Vector.Y"}));
}

TEST(ChannelRolesTest, ForceRoleTakesAnyWideEnoughGroup) {
  const auto groups = group_channels({"R", "G", "B", "A"});
  auto n = force_role(groups.at(0), Role::Normal);
  ASSERT_TRUE(n.has_value());
  EXPECT_EQ(n->role, Role::Normal);
  EXPECT_EQ(n->indices, (std::vector<int>{0, 1, 2}));  // by suffix order R,G,B
  auto d = force_role(groups.at(0), Role::Depth);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->indices.size(), 1u);

  const auto one = group_channels({"L.Depth.Z"});
  EXPECT_FALSE(force_role(one.at(0), Role::Normal).has_value());
  EXPECT_TRUE(force_role(one.at(0), Role::Depth).has_value());

  const auto odd = group_channels({"L.Stuff.a", "L.Stuff.b", "L.Stuff.c"});
  auto o = force_role(odd.at(0), Role::Albedo);
  ASSERT_TRUE(o.has_value());
  EXPECT_EQ(o->indices, (std::vector<int>{0, 1, 2}));  // file order when suffixes say nothing
}

TEST(ChannelRolesTest, RoleNamesRoundTrip) {
  for (Role r : kAllRoles) {
    auto back = role_from_name(role_name(r));
    ASSERT_TRUE(back.has_value()) << role_name(r);
    EXPECT_EQ(*back, r);
  }
  EXPECT_EQ(role_from_name("color"), Role::Colour);
  EXPECT_EQ(role_from_name("NORMAL"), Role::Normal);
  EXPECT_FALSE(role_from_name("nosuchrole").has_value());
}

}  // namespace
}  // namespace mcr
