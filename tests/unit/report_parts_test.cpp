// The report's parts against independent oracles: crops find a planted error, mirrored tiling
// against the mirror index written out, peer templates split like a shell and their PFM exports
// read back by OpenImageIO, commands' exit codes and hangs.
#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>

#include <unistd.h>

#include <cstdio>
#include <limits>
#include <filesystem>

#include "expect_error.h"
#include "image/deep.h"
#include "report/peer_command.h"
#include "report/report_images.h"
#include "report/report_runs.h"
#include "report/scaling.h"

namespace mcr {

namespace fs = std::filesystem;
using testutil::expect_error;

// A sequence's frames may each run another filter under auto: the report says so, with counts.
TEST(ReportRuns, AutosChoicesOverFramesAreCounted) {
  EXPECT_EQ(choices_summary({"pwaf"}), "pwaf");
  EXPECT_EQ(choices_summary({"input", "input"}), "input");
  EXPECT_EQ(choices_summary({"atrous", "pwaf", "pwaf", "box", "pwaf", "atrous"}), "pwaf x3, atrous x2, box x1");
  EXPECT_EQ(choices_summary({"box", "pwaf"}), "box x1, pwaf x1");  // ties: in the order they came
  EXPECT_EQ(choices_summary({}), "");
}

TEST(ReportImages, ErrorMapIsTheRelMseTermPerPixel) {
  Image ref(3, 2, 3, 0.5f), img(3, 2, 3, 0.5f);
  img.at(1, 1, 0) = 1.5f;                           // (1.0)^2 / (0.25 + 0.01) / 3 channels
  img.at(2, 0, 2) = std::numeric_limits<float>::quiet_NaN();  // read as 0: 0.25 / 0.26 / 3
  const Image m = relative_error_map(ref, img);
  EXPECT_FLOAT_EQ(m.at(1, 1, 0), float(1.0 / 0.26 / 3));
  EXPECT_FLOAT_EQ(m.at(2, 0, 0), float(0.25 / 0.26 / 3));
  EXPECT_EQ(m.at(0, 0, 0), 0.f);
}

TEST(ReportImages, CropsFindThePlantedErrorsHighestFirstWithoutOverlap) {
  Image a(200, 150, 1, 0.001f), b(200, 150, 1, 0.0f);
  for (int y = 100; y < 108; ++y)  // 8x8 block of error 5 in one map, 4x4 of 1 in the other
    for (int x = 30; x < 38; ++x) a.at(x, y, 0) = 5;
  for (int y = 10; y < 14; ++y)
    for (int x = 150; x < 154; ++x) b.at(x, y, 0) = 1;
  const auto regions = highest_error_regions({&a, &b}, 2, 64, 16);
  ASSERT_EQ(regions.size(), 2u);
  auto inside = [](const Roi& r, int x0, int y0, int x1, int y1) {
    return r.x0 <= x0 && r.y0 <= y0 && r.x1 >= x1 && r.y1 >= y1;
  };
  EXPECT_TRUE(inside(regions[0].crop, 30, 100, 38, 108));
  EXPECT_TRUE(inside(regions[0].zoom, 30, 100, 38, 108));
  EXPECT_TRUE(inside(regions[1].crop, 150, 10, 154, 14));
  EXPECT_TRUE(inside(regions[1].zoom, 150, 10, 154, 14));
  EXPECT_EQ(regions[0].crop.width(), 64);
  EXPECT_EQ(regions[1].zoom.width(), 16);
  const Roi &p = regions[0].crop, &q = regions[1].crop;
  EXPECT_FALSE(p.x0 < q.x1 && q.x0 < p.x1 && p.y0 < q.y1 && q.y0 < p.y1);
  // A frame smaller than the window: one crop, the whole frame.
  Image small(40, 30, 1, 1.0f);
  const auto one = highest_error_regions({&small}, 2, 64, 16);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].crop, Roi::all(40, 30));
}

int mirror_oracle(int x, int n) {  // 0 1 2 | 2 1 0 | 0 1 2 ...
  const int tile = x / n, off = x % n;
  return tile % 2 == 0 ? off : n - 1 - off;
}

TEST(ReportScaling, MirroredTilingOfPassesAndDeepSamples) {
  Frame f;
  f.width = 3;
  f.height = 2;
  Pass colour;
  colour.role = Role::Colour;
  colour.image = Image(3, 2, 3);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < 3; ++c) colour.image.at(x, y, c) = float(100 * y + 10 * x + c);
  f.passes.push_back(colour);
  auto deep = std::make_shared<DeepSamples>();
  deep->width = 3;
  deep->height = 2;
  deep->channel_names = {"R"};
  deep->offsets = {0};
  deep->values.resize(1);
  for (int p = 0; p < 6; ++p) {  // pixel p holds p+1 samples of value p
    deep->offsets.push_back(deep->offsets.back() + std::uint64_t(p + 1));
    for (int s = 0; s <= p; ++s) deep->values[0].push_back(float(p));
  }
  f.deep = deep;
  const Frame t = mirrored_tiling(f, 8, 5);
  ASSERT_EQ(t.width, 8);
  const Image& img = t.image(Role::Colour);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(img.at(x, y, c), colour.image.at(mirror_oracle(x, 3), mirror_oracle(y, 2), c)) << x << "," << y;
  ASSERT_TRUE(t.deep);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 8; ++x) {
      const int p = mirror_oracle(y, 2) * 3 + mirror_oracle(x, 3);
      ASSERT_EQ(t.deep->samples(x, y), std::uint32_t(p + 1));
      for (std::uint32_t s = 0; s < t.deep->samples(x, y); ++s)
        ASSERT_EQ(t.deep->values[0][t.deep->first(x, y) + s], float(p));
    }
}

TEST(ReportPeers, TemplatesSplitLikeAShellAndBadOnesAreNamed) {
  const PeerCommand p = parse_peer("oidn=oidnDenoise --hdr {colour} 'a b' \"c\\\"d\" e\\ f -o {output.exr}");
  EXPECT_EQ(p.name, "oidn");
  const std::vector<std::string> words = {"oidnDenoise", "--hdr", "{colour}", "a b", "c\"d", "e f", "-o", "{output.exr}"};
  EXPECT_EQ(p.words, words);
  EXPECT_EQ(peer_roles(p), std::vector<Role>{Role::Colour});
  expect_error(Errc::InvalidArgument, {"needs {output}"}, [] { parse_peer("x=denoise {colour}"); });
  expect_error(Errc::InvalidArgument, {"unknown placeholder {colr}"}, [] { parse_peer("x=d {colr} {output}"); });
  expect_error(Errc::InvalidArgument, {"unbalanced quote"}, [] { parse_peer("x=d 'a {output}"); });
  expect_error(Errc::InvalidArgument, {"expected NAME=COMMAND"}, [] { parse_peer("just a command"); });
  expect_error(Errc::InvalidArgument, {"the format is exr or pfm"}, [] { parse_peer("x=d {colour.png} {output}"); });
}

TEST(ReportPeers, ExportedPassesReadBackExactly) {
  const fs::path dir = fs::temp_directory_path() / ("mcrecon_peer_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  Frame f;
  f.width = 5;
  f.height = 3;
  Pass colour, depth;
  colour.role = Role::Colour;
  colour.image = Image(5, 3, 4);
  depth.role = Role::Depth;
  depth.image = Image(5, 3, 1);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) {
      for (int c = 0; c < 4; ++c) colour.image.at(x, y, c) = 0.25f * float(x) + float(y) + 0.01f * float(c);
      depth.image.at(x, y, 0) = float(7 * y + x);
    }
  f.passes = {colour, depth};
  std::string output;
  const auto argv = peer_argv(parse_peer("t=tool {colour} {depth.exr} {output}"), f, dir.string(), output);
  ASSERT_EQ(argv.size(), 4u);
  EXPECT_EQ(output, (dir / "t_output.pfm").string());
  EXPECT_EQ(argv[3], output);
  OIIO::ImageBuf pfm(argv[1]), exr(argv[2]);
  ASSERT_TRUE(pfm.read(0, 0, true, OIIO::TypeFloat)) << pfm.geterror();
  ASSERT_TRUE(exr.read(0, 0, true, OIIO::TypeFloat)) << exr.geterror();
  EXPECT_EQ(pfm.spec().nchannels, 3);
  EXPECT_EQ(exr.spec().nchannels, 1);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(pfm.getchannel(x, y, 0, c), colour.image.at(x, y, c)) << x << "," << y;
      EXPECT_EQ(exr.getchannel(x, y, 0, 0), depth.image.at(x, y, 0));
    }
  Frame no_normal = f;
  std::string o2;
  expect_error(Errc::MissingPass, {"normal"}, [&] { peer_argv(parse_peer("t=tool {normal} {output}"), no_normal, dir.string(), o2); });
  fs::remove_all(dir);
}

TEST(ReportPeers, ExitCodesAndAHangingCommandIsKilled) {
  const std::string log = (fs::temp_directory_path() / ("mcrecon_cmd_" + std::to_string(::getpid()) + ".log")).string();
  const CommandRun ok = run_timed_command({"sh", "-c", "echo hello; exit 3"}, log, 60);
  EXPECT_EQ(ok.exit_code, 3);
  EXPECT_FALSE(ok.timed_out);
  EXPECT_NE(log_tail(log).find("hello"), std::string::npos);
  const CommandRun hang = run_timed_command({"tail", "-f", "/dev/null"}, log, 0.2);
  EXPECT_TRUE(hang.timed_out);
  EXPECT_EQ(hang.exit_code, -9);
  expect_error(Errc::Internal, {"cannot start"}, [&] { run_timed_command({"/nonexistent/peer-binary"}, log, 60); });
  std::remove(log.c_str());
}

}  // namespace mcr
