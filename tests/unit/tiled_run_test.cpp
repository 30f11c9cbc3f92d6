// Tiled runs (pipeline/tiled_run.h): a frame in bands of rows gives the whole frame's pixels,
// bit for bit; the oracle is the filter's own whole-frame execute().
#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>

#include <algorithm>
#include <cstring>
#include <initializer_list>
#include <random>
#include <string>

#include "io/band_reader.h"
#include "io/frame_reader.h"
#include "kernels/feature_activity.h"
#include "pipeline/reconstruction.h"
#include "pipeline/tiled_run.h"
#include "scratch_dir.h"

namespace mcr {
namespace {

std::string sample(const std::string& scene) {
  return std::string(MCRECON_SOURCE_DIR) + "/samples/data/" + scene + "/" + scene + "_16spp.exr";
}

// Values that differ bit for bit.
long differing(const Image& a, const Image& b) {
  long n = 0;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const float u = a.at(x, y, c), v = b.at(x, y, c);
        n += std::memcmp(&u, &v, sizeof u) != 0;
      }
  return n;
}

class TiledRunTest : public ::testing::TestWithParam<const char*> {};

TEST_P(TiledRunTest, BandsGiveTheWholeFramesPixels) {
  for (const char* scene : {"room", "sunlit"}) {
    const Frame frame = read_frame(sample(scene));
    auto filter = make_committed_filter(GetParam(), {});
    const Image whole = filter->execute(frame);
    FrameRows rows(frame);
    TiledOptions o;
    o.band_rows = 64;  // three bands of the 192 rows
    const Image tiled = run_tiled(*filter, rows, o);
    EXPECT_EQ(differing(whole, tiled), 0) << scene;
  }
}

// A render far below or above display exposure is scaled by the whole frame's level
// (prepare/exposure.h), which no band sees alone: a first pass measures it.
TEST_P(TiledRunTest, ADimOrBrightFrameIsScaledByTheWholeFramesLevel) {
  for (float k : {1.0f / 64.0f, 48.0f}) {
    Frame frame = read_frame(sample("room"));
    for (Pass& p : frame.passes)
      if (p.role == Role::Colour)
        for (int y = 0; y < frame.height; ++y)  // the top band brighter: its own level would differ
          for (int x = 0; x < frame.width; ++x)
            for (int c = 0; c < 3; ++c) p.image.at(x, y, c) *= k * (y < 64 ? 3.0f : 1.0f);
    auto filter = make_committed_filter(GetParam(), {});
    const Image whole = filter->execute(frame);
    bool scaled = false;
    for (const std::string& n : filter->notes()) scaled = scaled || n.rfind("exposure:", 0) == 0;
    EXPECT_TRUE(scaled) << k;
    FrameRows rows(frame);
    TiledOptions o;
    o.band_rows = 64;
    EXPECT_EQ(differing(whole, run_tiled(*filter, rows, o)), 0) << k;
  }
}

// The normal pass constant over everything the first band reads (its rows and halo), varying
// below: the band alone would drop its weight (kernels/feature_activity.h); the frame's
// spread keeps it.
TEST_P(TiledRunTest, APassConstantInOneBandIsJudgedOverTheFrame) {
  Frame frame = read_frame(sample("room"));
  auto probe = make_committed_filter(GetParam(), {});
  const int constant_rows = std::min(frame.height - 2, 64 + probe->band_halo());
  for (Pass& p : frame.passes)
    if (p.role == Role::Normal)
      for (int y = 0; y < constant_rows; ++y)
        for (int x = 0; x < frame.width; ++x)
          for (int c = 0; c < p.image.channels(); ++c) p.image.at(x, y, c) = c == 2 ? 1.0f : 0.0f;
  auto filter = make_committed_filter(GetParam(), {});
  const Image whole = filter->execute(frame);
  FrameRows rows(frame);
  TiledOptions o;
  o.band_rows = 64;
  EXPECT_EQ(differing(whole, run_tiled(*filter, rows, o)), 0);
}

// A frame taller than guided's 256-row sum bands (three copies of a sample's left 96 columns
// stacked): bands that start off that grid still sum as the whole frame does.
TEST_P(TiledRunTest, ATallFramesBandsGiveItsPixels) {
  const Frame one = read_frame(sample("room"));
  const int w = 96, copies = 3;
  Frame tall = one.header(w, one.height * copies);
  for (const Pass& p : one.passes) {
    Image im(w, one.height * copies, p.image.channels());
    for (int k = 0; k < copies; ++k)
      for (int y = 0; y < one.height; ++y)
        std::memcpy(im.pixel(0, k * one.height + y), p.image.pixel(0, y), sizeof(float) * std::size_t(w) * std::size_t(p.image.channels()));
    tall.passes.push_back(with_pixels(p, std::move(im)));
  }
  auto filter = make_committed_filter(GetParam(), {});
  const Image whole = filter->execute(tall);
  FrameRows rows(tall);
  for (int band_rows : {64, 192}) {
    TiledOptions o;
    o.band_rows = band_rows;
    EXPECT_EQ(differing(whole, run_tiled(*filter, rows, o)), 0) << band_rows << "-row bands";
  }
}

INSTANTIATE_TEST_SUITE_P(Filters, TiledRunTest,
                         ::testing::Values("box", "gaussian", "bilateral", "atrous", "guided", "pwaf"));

TEST(TiledRun, ActivityOverTheFrameAnswersAsTheScan) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1e-3f, 1e-3f);
  for (int trial = 0; trial < 40; ++trial) {
    Image im(23, 17, 3);
    const float spread = trial % 4 == 0 ? 0.0f : trial % 4 == 1 ? 1e-5f : 1.0f;
    for (int y = 0; y < 17; ++y)
      for (int x = 0; x < 23; ++x)
        for (int c = 0; c < 3; ++c) im.at(x, y, c) = 0.5f + spread * u(rng) * 1000.0f;
    if (trial % 5 == 0) im.at(3, 4, 1) = std::numeric_limits<float>::quiet_NaN();
    if (trial % 7 == 0) im.at(0, 0, 0) = std::numeric_limits<float>::infinity();
    WholeFrameRange r;
    for (int y0 = 0; y0 < 17; y0 += 5) extend_frame_range(im, 3, Roi{0, y0, 23, std::min(17, y0 + 5)}, r);
    for (double tol : {0.0, 1e-6, 1e-3, 1.0}) {
      const FeatureActivity scan = feature_activity(im, 3, Roi::all(23, 17), tol, 1);
      const FeatureActivity frame = activity_over_frame(r, tol);
      EXPECT_EQ(int(scan.kind), int(frame.kind)) << trial << " " << tol;
      if (scan.kind == Activity::Constant) {
        EXPECT_EQ(scan.some_nonfinite, frame.some_nonfinite);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(scan.value[c], frame.value[c]);
      }
    }
  }
}

// Whether rows [y0, y1) of `whole`'s passes of these roles are `part`'s, bit for bit.
::testing::AssertionResult holds_rows(const Frame& part, const Frame& whole, std::initializer_list<Role> roles, int y0, int y1) {
  for (Role r : roles) {
    const Image& a = part.image(r);
    const Image& b = whole.image(r);
    if (a.channels() != b.channels() || a.height() != y1 - y0)
      return ::testing::AssertionFailure() << role_name(r) << ": another shape";
    if (std::memcmp(a.data(), b.pixel(0, y0), sizeof(float) * std::size_t(a.width()) * std::size_t(y1 - y0) * std::size_t(a.channels())))
      return ::testing::AssertionFailure() << role_name(r) << " rows " << y0 << ".." << y1 << " differ";
  }
  return ::testing::AssertionSuccess();
}

TEST(TiledRun, AFilesBandsHoldItsRows) {
  const std::string path = sample("glossy");
  const Frame frame = read_frame(path);
  FileBands bands(path, {}, {Role::Normal, Role::Albedo, Role::Depth});
  EXPECT_EQ(bands.width(), frame.width);
  EXPECT_EQ(bands.height(), frame.height);
  const Frame part = bands.rows(37, 101);
  ASSERT_EQ(part.height, 64);
  EXPECT_TRUE(holds_rows(part, frame, {Role::Colour, Role::Normal, Role::Albedo, Role::Depth}, 37, 101));
  EXPECT_FALSE(part.has(Role::Position));  // not asked for: not decoded
  EXPECT_LT(bands.kept_channels(), bands.file_channels());
}

// Consecutive bands share rows, which the reader copies from the last band instead of
// decoding them again: the same pixels either way.
TEST(TiledRun, OverlappingBandsOfAFileHoldItsRows) {
  const std::string path = sample("glossy");
  const Frame frame = read_frame(path);
  FileBands bands(path, {}, {Role::Normal});
  bands.overlap_hint(50);
  for (const auto& [y0, y1] : {std::pair<int, int>{0, 80}, {40, 130}, {100, 192}, {0, 64}}) {
    EXPECT_TRUE(holds_rows(bands.rows(y0, y1), frame, {Role::Colour, Role::Normal}, y0, y1));
  }
}

// A tiled EXR (OpenImageIO reads tiles only on their grid): bands that start and end inside
// rows of tiles hold the file's rows.
TEST(TiledRun, ATiledFilesBandsHoldItsRows) {
  testutil::ScratchDir dir("mcrecon_tiled_bands");
  const std::string path = dir.path("tiled.exr");
  {
    OIIO::ImageBuf src(sample("glossy"));
    ASSERT_TRUE(src.read(0, 0, true, OIIO::TypeDesc::FLOAT));
    src.set_write_tiles(16, 16);
    ASSERT_TRUE(src.write(path));
  }
  const Frame frame = read_frame(path);
  FileBands bands(path, {}, {Role::Normal});
  bands.overlap_hint(40);
  for (const auto& [y0, y1] : {std::pair<int, int>{5, 77}, {50, 192}}) {
    EXPECT_TRUE(holds_rows(bands.rows(y0, y1), frame, {Role::Colour, Role::Normal}, y0, y1));
  }
}

TEST(TiledRun, BandsAreAlignedAndCoverTheFrame) {
  const BandPlan p = plan_bands(3072, 100, 59);
  EXPECT_EQ(p.band_rows, 128);
  EXPECT_EQ(p.bands, 24);
  EXPECT_EQ(plan_bands(50, 64, 10).band_rows, 50);
  EXPECT_EQ(plan_bands(50, 64, 10).bands, 1);
}

}  // namespace
}  // namespace mcr
