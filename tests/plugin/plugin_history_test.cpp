// The plugin's temporal-history rule (plugin/history.h) with a fake temporal
// filter inside a Reconstruction: which frames continue history and which start
// fresh (reset()); accumulation makes a spatial filter's stream temporal.
#include <gtest/gtest.h>

#include "history.h"

namespace mcr::plugin {
namespace {

const FilterInfo& fake_info(bool temporal) {
  static const FilterInfo t = [] {
    FilterInfo i;
    i.name = "fake_temporal";
    i.params = with_common_params({});
    i.required = {Role::Colour};
    i.temporal = true;
    return i;
  }();
  static const FilterInfo s = [] {
    FilterInfo i = t;
    i.name = "fake_spatial";
    i.temporal = false;
    return i;
  }();
  return temporal ? t : s;
}

// Counts resets and how many frames ran since the last one (its "history").
class FakeFilter : public Filter {
 public:
  explicit FakeFilter(bool temporal) : Filter(fake_info(temporal)) { commit(); }
  int resets = 0, history = 0;

 protected:
  void reset_history() override {
    ++resets;
    history = 0;
  }
  void run(const Frame&, const Image&, const Roi&, Image&, int) override { ++history; }
};

StreamHistory::Factory fake(bool temporal, int* made = nullptr, bool accumulate = false) {
  return [=] {
    if (made) ++*made;
    return std::make_unique<Reconstruction>(std::make_unique<FakeFilter>(temporal), accumulate);
  };
}

FakeFilter& fake_of(const StreamHistory::Lease& lease) {
  return static_cast<FakeFilter&>(lease.reconstruction->filter());
}

// acquire + "run" + done, returning whether history continued.
bool step(StreamHistory& h, const std::string& key, const std::string& path, bool temporal = true,
          bool accumulate = false) {
  auto lease = h.acquire(key, path, fake(temporal, nullptr, accumulate));
  ++fake_of(lease).history;
  h.done();
  return lease.continued;
}

TEST(PluginHistory, FrameNumberIsTheLastDigitRunOfTheFileName) {
  FrameName f = split_frame_number("/data/shot2/anim_1spp_0005.exr");
  ASSERT_TRUE(f.number);
  EXPECT_EQ(*f.number, 5);
  EXPECT_EQ(f.pattern, "/data/shot2/anim_1spp_####.exr");
  f = split_frame_number("render.1001.exr");
  EXPECT_EQ(*f.number, 1001);
  EXPECT_EQ(f.pattern, "render.####.exr");
  f = split_frame_number("/data/shot2/render.exr");  // digits in the directory do not count
  EXPECT_FALSE(f.number);
  EXPECT_EQ(f.pattern, "/data/shot2/render.exr");
}

TEST(PluginHistory, InOrderFramesContinue) {
  StreamHistory h;
  EXPECT_FALSE(step(h, "bmfr", "a_0001.exr"));
  for (int f = 2; f <= 16; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "a_%04d.exr", f);
    EXPECT_TRUE(step(h, "bmfr", name)) << name;
  }
  auto lease = h.acquire("bmfr", "a_0017.exr", fake(true));
  EXPECT_TRUE(lease.continued);
  EXPECT_EQ(fake_of(lease).history, 16);  // one object kept all frames
  EXPECT_EQ(fake_of(lease).resets, 1);    // only before frame 1
}

TEST(PluginHistory, GapsRepeatsAndBackwardsStartFresh) {
  StreamHistory h;
  EXPECT_FALSE(step(h, "k", "a_0001.exr"));
  EXPECT_TRUE(step(h, "k", "a_0002.exr"));
  EXPECT_FALSE(step(h, "k", "a_0004.exr"));  // gap
  EXPECT_FALSE(step(h, "k", "a_0004.exr"));  // same frame again
  EXPECT_FALSE(step(h, "k", "a_0003.exr"));  // backwards
  EXPECT_TRUE(step(h, "k", "a_0004.exr"));   // 3 -> 4 in order again
  auto lease = h.acquire("k", "a_0005.exr", fake(true));
  EXPECT_EQ(fake_of(lease).history, 2);  // frames 3 and 4 only
}

TEST(PluginHistory, OtherSettingsOrPatternAreOtherStreams) {
  StreamHistory h;
  EXPECT_FALSE(step(h, "filter=bmfr a=1", "a_0001.exr"));
  EXPECT_FALSE(step(h, "filter=bmfr a=2", "a_0002.exr"));  // other parameters: fresh
  EXPECT_FALSE(step(h, "filter=bmfr a=1", "b_0002.exr"));  // other sequence: fresh
  EXPECT_TRUE(step(h, "filter=bmfr a=1", "a_0002.exr"));   // the first stream is still there
  EXPECT_EQ(h.streams(), 3u);
}

TEST(PluginHistory, NamesWithoutFrameNumberAlwaysStartFresh) {
  StreamHistory h;
  EXPECT_FALSE(step(h, "k", "render.exr"));
  EXPECT_FALSE(step(h, "k", "render.exr"));
}

TEST(PluginHistory, AFailedFrameDropsHistory) {
  StreamHistory h;
  EXPECT_FALSE(step(h, "k", "a_0001.exr"));
  h.acquire("k", "a_0002.exr", fake(true));
  h.failed();
  EXPECT_FALSE(step(h, "k", "a_0003.exr"));
  EXPECT_TRUE(step(h, "k", "a_0004.exr"));
}

TEST(PluginHistory, NonTemporalFiltersNeverContinue) {
  StreamHistory h;
  EXPECT_FALSE(step(h, "k", "a_0001.exr", false));
  EXPECT_FALSE(step(h, "k", "a_0002.exr", false));
}

TEST(PluginHistory, AccumulationMakesASpatialFilterTemporal) {
  StreamHistory h;
  EXPECT_FALSE(step(h, "k accumulate=1", "a_0001.exr", false, true));
  EXPECT_TRUE(step(h, "k accumulate=1", "a_0002.exr", false, true));
  EXPECT_FALSE(step(h, "k accumulate=1", "a_0004.exr", false, true));  // gap: reset
  auto lease = h.acquire("k accumulate=1", "a_0005.exr", fake(false, nullptr, true));
  EXPECT_TRUE(lease.continued);
  EXPECT_TRUE(lease.reconstruction->accumulates());
  EXPECT_EQ(fake_of(lease).resets, 2);  // before frames 1 and 4: the reset reaches the filter
}

TEST(PluginHistory, OldStreamsAreDropped) {
  StreamHistory h(2);
  int made = 0;
  for (const char* k : {"a", "b", "c", "a"}) {
    h.acquire(k, "x_0001.exr", fake(true, &made));
    h.done();
  }
  EXPECT_EQ(h.streams(), 2u);
  EXPECT_EQ(made, 4);  // "a" was dropped when "c" came, and made again
}

}  // namespace
}  // namespace mcr::plugin
