// What a filter needs follows its settings (Filter::needs), is checked before any work,
// and settings that change nothing are reported (Filter::unused_settings).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "pipeline/reconstruction.h"
#include "util/error.h"

namespace mcr {
namespace {

bool has(const std::vector<Role>& v, Role r) { return std::find(v.begin(), v.end(), r) != v.end(); }

std::unique_ptr<Filter> committed(const std::string& name, const std::vector<std::pair<std::string, std::string>>& kv) {
  return make_committed_filter(name, kv);
}

TEST(FilterNeeds, FollowTheSettings) {
  EXPECT_FALSE(has(committed("box", {})->needs().required, Role::Albedo));
  EXPECT_TRUE(has(committed("box", {{"demodulate", "true"}})->needs().required, Role::Albedo));
  EXPECT_TRUE(has(committed("box", {{"holes", "sample_count"}})->needs().required, Role::SampleCount));
  EXPECT_TRUE(has(committed("box", {})->needs().optional, Role::SampleCount));  // holes=auto
  EXPECT_FALSE(has(committed("box", {{"holes", "none"}})->needs().optional, Role::SampleCount));

  const PassNeeds nd = committed("guided", {{"guide", "normal_depth"}})->needs();
  EXPECT_TRUE(has(nd.required, Role::Normal));
  EXPECT_TRUE(has(nd.required, Role::Depth));
  const PassNeeds def = committed("guided", {})->needs();  // the default guide takes what is there
  EXPECT_EQ(def.required, std::vector<Role>{Role::Colour});
  EXPECT_TRUE(has(def.optional, Role::Normal) && has(def.optional, Role::Depth));
  const PassNeeds lum = committed("guided", {{"guide", "luminance"}})->needs();
  EXPECT_EQ(lum.required, std::vector<Role>{Role::Colour});

  EXPECT_TRUE(has(committed("bilateral", {{"use_depth", "on"}})->needs().required, Role::Depth));
  EXPECT_FALSE(has(committed("bilateral", {})->needs().optional, Role::Depth));  // use_depth=off by default
  EXPECT_TRUE(has(committed("bilateral", {})->needs().optional, Role::Normal));
  EXPECT_FALSE(has(committed("bilateral", {{"use_normal", "off"}})->needs().optional, Role::Normal));

  EXPECT_TRUE(has(committed("bmfr", {{"features", "with_depth"}})->needs().required, Role::Depth));
  EXPECT_FALSE(has(committed("bmfr", {})->needs().required, Role::Depth));

  const Reconstruction acc(committed("box", {}), true);
  EXPECT_TRUE(has(acc.needs().required, Role::Position));
  EXPECT_TRUE(has(acc.needs().required, Role::Normal));
  EXPECT_TRUE(has(acc.needs().optional, Role::Motion));
}

// The missing pass is named with the setting that needs it, before any work.
TEST(FilterNeeds, MissingPassNamesTheSetting) {
  const Frame f = testutil::colour_frame(testutil::random_image(8, 6, 3, 1));
  auto expect_missing = [&](const std::string& name, const std::vector<std::pair<std::string, std::string>>& kv,
                            const std::string& text) {
    try {
      committed(name, kv)->execute(f);
      ADD_FAILURE() << name << ": no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Errc::MissingPass);
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("test.exr"), std::string::npos) << e.what();
    }
  };
  expect_missing("box", {{"demodulate", "true"}}, "albedo pass (for demodulate=true)");
  expect_missing("guided", {{"guide", "normal_depth"}}, "normal, depth passes (for guide=normal_depth");
  expect_missing("atrous", {{"use_depth", "on"}}, "depth pass (for use_depth=on)");
  expect_missing("bmfr", {}, "normal");
  Reconstruction acc(committed("box", {}), true);
  try {
    acc.run(f);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("position, normal passes (for accumulate)"), std::string::npos) << e.what();
  }
}

TEST(FilterNeeds, SettingsWithoutEffectAreReported) {
  auto unused = [](const std::string& name, const std::vector<std::pair<std::string, std::string>>& kv) {
    return committed(name, kv)->unused_settings();
  };
  auto mentions = [](const std::vector<std::string>& notes, const std::string& what) {
    for (const std::string& n : notes)
      if (n.find(what) != std::string::npos) return true;
    return false;
  };
  // firefly_k is on by default in the image filters, off in bmfr (its sample limit does that job).
  EXPECT_TRUE(unused("box", {{"firefly_radius", "5"}}).empty());
  EXPECT_TRUE(mentions(unused("box", {{"firefly_radius", "5"}, {"firefly_k", "0"}}),
                       "firefly_radius has no effect with firefly_k=0"));
  EXPECT_TRUE(unused("box", {{"firefly_radius", "5"}, {"firefly_k", "2"}}).empty());
  EXPECT_TRUE(mentions(unused("bmfr", {{"firefly_radius", "5"}}), "firefly_radius has no effect with firefly_k=0"));
  EXPECT_TRUE(mentions(unused("box", {{"albedo_prefilter_position", "0.1"}}), "albedo_prefilter_position"));
  EXPECT_TRUE(unused("box", {{"albedo_prefilter_position", "0.1"}, {"albedo_prefilter", "0.2"}}).empty());
  EXPECT_TRUE(mentions(unused("box", {{"albedo_floor", "0.05"}}), "albedo_floor has no effect with demodulate=false"));
  EXPECT_TRUE(mentions(unused("gaussian", {{"sigma_outer", "3"}}), "sigma_outer has no effect with foveated=false"));
  EXPECT_TRUE(unused("gaussian", {{"sigma_outer", "3"}, {"foveated", "true"}}).empty());
  EXPECT_TRUE(mentions(unused("bilateral", {{"ridge", "1"}}), "ridge has no effect with order=0"));
  EXPECT_TRUE(mentions(unused("bilateral", {{"depth_sigma", "1"}}), "depth_sigma has no effect with use_depth=off"));
  EXPECT_TRUE(mentions(unused("pwaf", {{"adaptive", "false"}, {"variance_max", "3"}}), "variance_max"));
  EXPECT_TRUE(mentions(unused("bmfr", {{"taa", "false"}, {"taa_alpha", "0.5"}}), "taa_alpha has no effect with taa=false"));
  // Defaults are never reported: only what was given.
  for (const std::string& name : filter_names()) EXPECT_TRUE(unused(name, {}).empty()) << name;
}

}  // namespace
}  // namespace mcr
