// Names and settings of the OIIO plugin (plugin/request.h): no OpenImageIO involved.
#include <gtest/gtest.h>

#include "request.h"
#include "util/error.h"

namespace mcr::plugin {
namespace {

Errc code_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code();
  }
  ADD_FAILURE() << "no mcr::Error thrown";
  return Errc::Internal;
}

TEST(PluginRequest, OnlyMcreconNamesAreOurs) {
  EXPECT_TRUE(is_plugin_name("render.exr.mcrecon"));
  EXPECT_TRUE(is_plugin_name("dir/render.exr.MCRECON?filter=box"));
  EXPECT_FALSE(is_plugin_name("render.exr"));
  EXPECT_FALSE(is_plugin_name(".mcrecon"));
  EXPECT_FALSE(is_plugin_name("render.exr?x=.mcrecon"));
  EXPECT_FALSE(is_plugin_name("render.mcrecon.exr"));
}

TEST(PluginRequest, SplitsTheQuery) {
  auto [source, kv] = split_name("d/r.exr.mcrecon?filter=box&radius=3&normal=ViewLayer.Normal");
  EXPECT_EQ(source, "d/r.exr");
  ASSERT_EQ(kv.size(), 3u);
  EXPECT_EQ(kv[1], (std::pair<std::string, std::string>("radius", "3")));
  EXPECT_EQ(kv[2].second, "ViewLayer.Normal");
  EXPECT_EQ(split_name("r.exr.mcrecon?a=b=c").second[0].second, "b=c");
  EXPECT_EQ(code_of([] { split_name("r.exr.mcrecon?filter=box&radius"); }), Errc::InvalidArgument);
  EXPECT_EQ(code_of([] { split_name("r.exr.mcrecon?filter=box&&a=1"); }), Errc::InvalidArgument);
}

TEST(PluginRequest, SortsKeysIntoFilterLayerPassesAndParameters) {
  Request r = make_request("r.exr", {{"filter", "box"}, {"radius", "3"}, {"layer", "VL"}, {"normal", "n.exr"},
                                     {"color", "VL.Noisy"}},
                           false);
  EXPECT_EQ(r.filter, "box");
  EXPECT_EQ(r.read.layer, "VL");
  ASSERT_EQ(r.read.overrides.size(), 2u);
  EXPECT_EQ(r.read.overrides[0].role, Role::Normal);
  EXPECT_EQ(r.read.overrides[1].role, Role::Colour);
  ASSERT_EQ(r.params.size(), 1u);
  EXPECT_EQ(r.params[0].first, "radius");
  EXPECT_EQ(code_of([] { make_request("r.exr", {{"radius", "3"}}, false); }), Errc::InvalidArgument);
  EXPECT_EQ(code_of([] { make_request("r.exr", {{"filter", "box"}, {"normal", ""}}, false); }), Errc::InvalidArgument);
  // keep_passes is an output setting; on input it is a (unknown) filter parameter.
  EXPECT_TRUE(make_request("o.exr", {{"filter", "box"}, {"keep_passes", "1"}}, true).keep_passes);
  EXPECT_EQ(make_request("o.exr", {{"filter", "box"}, {"keep_passes", "1"}}, false).params.size(), 1u);
}

TEST(PluginRequest, AccumulateOnBothSidesAndInTheSettingsKey) {
  for (bool output_side : {false, true}) {
    EXPECT_FALSE(make_request("r.exr", {{"filter", "box"}}, output_side).accumulate);
    for (const char* on : {"1", "true"})
      EXPECT_TRUE(make_request("r.exr", {{"filter", "box"}, {"accumulate", on}}, output_side).accumulate) << on;
    for (const char* off : {"0", "false"})
      EXPECT_FALSE(make_request("r.exr", {{"filter", "box"}, {"accumulate", "1"}, {"accumulate", off}}, output_side)
                       .accumulate)
          << off;  // the last one wins
    EXPECT_TRUE(make_request("r.exr", {{"filter", "box"}, {"accumulate", "1"}}, output_side).params.empty());
  }
  const Request on = make_request("r.exr", {{"filter", "box"}, {"accumulate", "1"}}, false);
  const Request off = make_request("r.exr", {{"filter", "box"}}, false);
  EXPECT_NE(settings_key(on, "radius=2"), settings_key(off, "radius=2"));
  EXPECT_TRUE(make_reconstruction(on)->accumulates());
  EXPECT_FALSE(make_reconstruction(off)->accumulates());
  EXPECT_EQ(make_reconstruction(on)->parameters_text().rfind("accumulate=true ", 0), 0u);
}

TEST(PluginRequest, HalfNamesTheOtherHalfBufferOnTheInputSideOnly) {
  const Request r = make_request("h0.exr", {{"filter", "box"}, {"half", "h1.exr"}}, false);
  EXPECT_EQ(r.read.second_half, "h1.exr");
  EXPECT_TRUE(r.params.empty());
  EXPECT_NE(settings_key(r, ""), settings_key(make_request("h0.exr", {{"filter", "box"}}, false), ""));
  EXPECT_EQ(code_of([] { make_request("h0.exr", {{"filter", "box"}, {"half", "h1.exr"}}, true); }),
            Errc::InvalidArgument);  // the output side is handed pixels
  EXPECT_EQ(code_of([] { make_request("h0.exr", {{"filter", "box"}, {"half", ""}}, false); }), Errc::InvalidArgument);
}

TEST(PluginRequest, BadSwitchValuesNameTheSettingAndTheText) {
  for (const char* key : {"accumulate", "keep_passes"}) {
    try {
      make_request("o_0001.963d536f.temp.exr", {{"filter", "box"}, {key, "maybe"}}, true);
      ADD_FAILURE() << key << "=maybe accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Errc::InvalidArgument);
      EXPECT_EQ(std::string(e.what()), std::string("'o_0001.exr': ") + key + " expects 0, 1, true or false, got 'maybe'");
    }
  }
}

// The output side's compression is checked when the request is made (OIIO would silently
// write zip for a name it does not know), with the CLI's check and message.
TEST(PluginRequest, CompressionIsCheckedOnTheOutputSide) {
  EXPECT_EQ(make_request("o.exr", {{"filter", "box"}, {"compression", "PIZ"}}, true).compression, "piz");
  EXPECT_EQ(make_request("o.exr", {{"filter", "box"}, {"compression", "dwaa:45"}}, true).compression, "dwaa:45");
  EXPECT_EQ(make_request("o.exr", {{"filter", "box"}}, true).compression, "zip");
  for (const char* c : {"bogus", "zip:0", "", "piz:2"}) {
    try {
      make_request("o.exr", {{"filter", "box"}, {"compression", c}}, true);
      ADD_FAILURE() << "compression=" << c << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Errc::InvalidArgument);
      EXPECT_NE(std::string(e.what()).find("compression '" + std::string(c) + "'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("zip, zips, piz"), std::string::npos) << e.what();
    }
  }
  // On the input side compression is no setting of the plugin: a filter parameter, refused there.
  EXPECT_EQ(make_request("x.exr", {{"filter", "box"}, {"compression", "bogus"}}, false).params.size(), 1u);
}

TEST(PluginRequest, NotesTextJoinsTheNotes) {
  EXPECT_EQ(notes_text({}), "");
  EXPECT_EQ(notes_text({"a has no effect", "b"}), "a has no effect; b");
  // firefly_k is on by default: off, firefly_radius is an unused setting.
  Request r = make_request("r.exr", {{"filter", "box"}, {"firefly_k", "0"}, {"firefly_radius", "5"}}, false);
  EXPECT_EQ(notes_text(make_reconstruction(r)->notes()), "firefly_radius has no effect with firefly_k=0");
}

TEST(PluginRequest, StripsOiiotoolTempNames) {
  EXPECT_EQ(strip_oiiotool_temp("/tmp/pt/o_0001.963d536f.temp.exr"), "/tmp/pt/o_0001.exr");
  EXPECT_EQ(strip_oiiotool_temp("o.ABCDEF01.temp"), "o");
  EXPECT_EQ(strip_oiiotool_temp("/tmp/pt/o_0001.exr"), "/tmp/pt/o_0001.exr");
  EXPECT_EQ(strip_oiiotool_temp("x.temp.exr"), "x.temp.exr");
  EXPECT_EQ(strip_oiiotool_temp("a.1234567g.temp.exr"), "a.1234567g.temp.exr");
}

TEST(PluginRequest, FloatTextRoundTrips) {
  EXPECT_EQ(float_text(0.1f), "0.1");
  EXPECT_EQ(float_text(3.0f), "3");
  EXPECT_EQ(std::strtof(float_text(1.0f / 3.0f).c_str(), nullptr), 1.0f / 3.0f);
}

}  // namespace
}  // namespace mcr::plugin
