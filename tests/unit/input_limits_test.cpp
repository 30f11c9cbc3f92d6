// Limits from the input (io/input_limits.h): only regular files are read, a header
// cannot ask for more memory than its file can hold (or MCRECON_MAX_MEMORY allows),
// deep sample counts are checked before the samples are allocated; thread counts
// are clamped to the hardware and negative ones refused (util/parallel.h).
//
// The hostile files are tiny real EXRs written here with OpenImageIO whose header
// is then patched to claim a larger data window or tile size.
#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <tbb/info.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "deep_file_testutil.h"
#include "expect_error.h"
#include "io/frame_reader.h"
#include "io/input_limits.h"
#include "scratch_dir.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/thread_count.h"

namespace mcr {
namespace {

namespace fs = std::filesystem;
using testutil::contains;
using testutil::expect_error;
using testutil::ScratchDir;

// Sets MCRECON_MAX_MEMORY for one scope (unset = the file's own bound).
class MaxMemory {
 public:
  explicit MaxMemory(const char* value) {
    if (value) ::setenv("MCRECON_MAX_MEMORY", value, 1);
    else ::unsetenv("MCRECON_MAX_MEMORY");
  }
  ~MaxMemory() { ::unsetenv("MCRECON_MAX_MEMORY"); }
};

// A w x h image of `channels` channels, every value v, in the given compression.
void write_flat(const std::string& path, int w, int h, int channels, const std::string& compression,
                OIIO::TypeDesc type = OIIO::TypeFloat, int tile = 0, float v = 0.5f) {
  OIIO::ImageSpec spec(w, h, channels, type);
  spec.attribute("compression", compression);
  if (tile > 0) spec.tile_width = spec.tile_height = tile;
  std::vector<float> px(std::size_t(w) * h * channels, v);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out && out->open(path, spec) && out->write_image(OIIO::TypeFloat, px.data())) << OIIO::geterror();
  out->close();
}

// Two parts of w x h RGBA float, named so their channels stay apart.
void write_two_parts(const std::string& path, int w, int h) {
  std::vector<OIIO::ImageSpec> specs(2, OIIO::ImageSpec(w, h, 4, OIIO::TypeFloat));
  specs[0].attribute("name", "one");
  specs[1].attribute("name", "two");
  for (auto& s : specs) s.attribute("compression", "zip");
  std::vector<float> px(std::size_t(w) * h * 4, 0.25f);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out && out->open(path, 2, specs.data())) << OIIO::geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeFloat, px.data()));
  ASSERT_TRUE(out->open(path, specs[1], OIIO::ImageOutput::AppendSubimage));
  ASSERT_TRUE(out->write_image(OIIO::TypeFloat, px.data()));
  out->close();
}

std::string file_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// Rewrites every occurrence of attribute `name` of `type` in an EXR header: the
// int32 fields that follow its size field. Returns how many were patched.
int patch_attribute(const std::string& path, const std::string& name, const std::string& type,
                    const std::vector<std::int32_t>& fields) {
  std::string bytes = file_bytes(path);
  const std::string key = name + std::string(1, '\0') + type + std::string(1, '\0');
  int patched = 0;
  for (std::size_t at = bytes.find(key); at != std::string::npos; at = bytes.find(key, at + 1)) {
    std::memcpy(&bytes[at + key.size() + 4], fields.data(), fields.size() * 4);  // after the int32 size
    ++patched;
  }
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  return patched;
}

// Makes the file claim a w x h data window (display window too), the way a hostile
// file would: every part's chunkCount matches it and zeros pad the file so the chunk
// offset tables fit (OpenEXR opens it; the pixel data is simply missing).
// lines: scanlines per chunk of the file's compression (zip 16, zips 1).
void claim_size(const std::string& path, int w, int h, int lines) {
  const int parts = patch_attribute(path, "dataWindow", "box2i", {0, 0, w - 1, h - 1});
  EXPECT_GE(parts, 1);
  EXPECT_EQ(patch_attribute(path, "displayWindow", "box2i", {0, 0, w - 1, h - 1}), parts);
  const std::int32_t chunks = (h + lines - 1) / lines;
  patch_attribute(path, "chunkCount", "int", {chunks});  // multi-part and deep files have one
  std::ofstream(path, std::ios::binary | std::ios::app) << std::string(std::size_t(parts) * chunks * 8, '\0');
}

// ------------------------------------------------------------------ regular files only

TEST(InputLimits, FifoIsRefusedWithoutOpeningIt) {
  ScratchDir dir("mcrecon_limits");
  const std::string fifo = dir.path("pipe.exr");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // open() of a FIFO with no writer blocks forever: returning at all shows no open() happened.
  expect_error(Errc::NotAnImage, {"'" + fifo + "'", "not a regular file (a FIFO)"}, [&] { read_frame(fifo); });
  expect_error(Errc::NotAnImage, {"'" + fifo + "'", "FIFO"}, [&] { read_pass_file(fifo, Role::Albedo); });
  // A loose pass given as --pass albedo=pipe.exr.
  const std::string good = dir.path("good.exr");
  write_flat(good, 4, 4, 3, "zip");
  ReadOptions ro;
  ro.overrides.push_back(parse_pass_override("albedo=" + fifo));
  expect_error(Errc::NotAnImage, {"'" + fifo + "'", "FIFO"}, [&] { read_frame(good, ro); });
}

TEST(InputLimits, DevicesDirectoriesAndSymlinks) {
  ScratchDir dir("mcrecon_limits");
  for (const char* dev : {"/dev/zero", "/dev/urandom"})
    expect_error(Errc::NotAnImage, {std::string("'") + dev + "'", "not a regular file (a character device)"},
                 [&] { read_frame(dev); });
  expect_error(Errc::NotAnImage, {"it is a directory"}, [&] { read_frame(dir.str()); });
  expect_error(Errc::FileNotFound, {"no such file"}, [&] { read_frame(dir.path("missing.exr")); });

  const std::string good = dir.path("good.exr"), link = dir.path("link.exr"), devlink = dir.path("zero.exr");
  write_flat(good, 2, 2, 3, "zip");
  fs::create_symlink(good, link);
  EXPECT_EQ(read_frame(link).width, 2);  // a symlink to a regular file is read
  fs::create_symlink("/dev/zero", devlink);
  expect_error(Errc::NotAnImage, {"'" + devlink + "'", "character device"}, [&] { read_frame(devlink); });
}

// ------------------------------------------------------------------ memory from the file

TEST(InputLimits, OnePixelFileReads) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("one.exr");
  write_flat(f, 1, 1, 4, "zip");
  const Frame frame = read_frame(f);
  EXPECT_EQ(frame.width, 1);
  EXPECT_EQ(frame.image(Role::Colour).data()[0], 0.5f);
}

TEST(InputLimits, HeaderAskingMoreThanTheFileHoldsIsRefused) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("small.exr");
  write_flat(f, 8, 8, 4, "zip");
  // 6000x6000x4 float = 576 MB from a file of a few KB: under the old fixed 32 GB
  // cap, so the old reader allocated it; zip holds at most 4096 float bytes a byte.
  claim_size(f, 6000, 6000, 16);
  const double size = double(fs::file_size(f));
  ASSERT_LT(size * max_expansion("openexr", "zip") + InputBudget::kFloor, 576e6);
  const std::string msg = expect_error(Errc::ReadFailed, [&] { read_frame(f); });
  for (const std::string& part : std::vector<std::string>{"cannot read '" + f + "'", "its header asks for 6000x6000x4 float (576 MB)",
                                 "the " + byte_text(size) + " file can hold at most ~", "set MCRECON_MAX_MEMORY"})
    EXPECT_TRUE(contains(msg, part)) << "'" << part << "' not in: " << msg;
  // The same for the 160 GB of the issue (the message shows the size readably).
  write_flat(f, 8, 8, 4, "zip");
  claim_size(f, 100000, 100000, 16);
  expect_error(Errc::ReadFailed, {"100000x100000x4 float (160 GB)", "can hold at most"}, [&] { read_frame(f); });
}

TEST(InputLimits, MaxMemoryReplacesTheFileBound) {
  ScratchDir dir("mcrecon_limits");
  const std::string legit = dir.path("legit.exr");
  write_flat(legit, 256, 256, 4, "none");  // 1 MB of float pixels in a 1 MB file
  {
    MaxMemory m("500K");
    expect_error(Errc::ReadFailed, {"'" + legit + "'", "256x256x4 float (1.05 MB)", "MCRECON_MAX_MEMORY=500K allows 500 KB"},
                 [&] { read_frame(legit); });
  }
  const std::string f = dir.path("small.exr");
  write_flat(f, 8, 8, 4, "zip");
  claim_size(f, 6000, 6000, 16);
  {
    MaxMemory m("2G");  // allowed now: whatever happens next is not the limit
    try {
      read_frame(f);
    } catch (const Error& e) {
      EXPECT_FALSE(contains(e.what(), "can hold at most") || contains(e.what(), "allows")) << e.what();
    }
  }
  {
    MaxMemory m("lots");
    expect_error(Errc::InvalidArgument, {"MCRECON_MAX_MEMORY='lots'", "500M"}, [&] { read_frame(legit); });
  }
}

TEST(InputLimits, EveryPartCounts) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("parts.exr");
  write_two_parts(f, 8, 8);
  // Each part 2000x2000x4 float = 64 MB fits alone (the floor + a few KB x 4096); both parts do not.
  claim_size(f, 2000, 2000, 16);
  expect_error(Errc::ReadFailed, {"'" + f + "'", "2000x2000x8 float in 2 parts (128 MB)"}, [&] { read_frame(f); });
}

TEST(InputLimits, HugeTilesAreRefused) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("tiled.exr");
  write_flat(f, 16, 16, 4, "zip", OIIO::TypeFloat, 16);
  // An 16x16 image in 5000x5000 tiles: a tiled read buffers a whole tile (400 MB).
  ASSERT_EQ(patch_attribute(f, "tiles", "tiledesc", {5000, 5000}), 1);
  expect_error(Errc::ReadFailed, {"'" + f + "'", "tiles of 5000x5000x4 float"}, [&] { read_frame(f); });
}

TEST(InputLimits, DeepSampleCountsAreCheckedBeforeTheSamples) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("deep.exr");
  write_deep_file(f, 32, 32, 100, 0.01f);  // 102400 samples x 4 channels = 1.64 MB as float
  EXPECT_EQ(read_frame(f).deep->total_samples(), 102400u);
  {
    // The header (32x32 pixels, tables included) fits 1 MB; the samples do not.
    MaxMemory m("1M");
    expect_error(Errc::ReadFailed, {"'" + f + "'", "its sample counts ask for 102400 deep samples x 4 float channels (1.64 MB)",
                                    "MCRECON_MAX_MEMORY=1M allows 1 MB"},
                 [&] { read_frame(f); });
  }
  // A deep header claiming a huge window: its per-pixel tables alone exceed the file.
  claim_size(f, 20000, 20000, 1);
  expect_error(Errc::ReadFailed, {"'" + f + "'", "20000x20000x4 float", "can hold at most"}, [&] { read_frame(f); });
}

// ------------------------------------------------------------------ OpenEXR header pre-check
// OpenEXR allocates what a header declares before comparing it with the file;
// check_exr_header_sizes refuses such claims before OpenImageIO/OpenEXR open the file.

std::string le32(std::int32_t v) {
  std::string b(4, '\0');
  for (int i = 0; i < 4; ++i) b[std::size_t(i)] = char((std::uint32_t(v) >> (8 * i)) & 0xff);
  return b;
}

// name\0 type\0 int32 size, value.
std::string exr_attribute(const std::string& name, const std::string& type, std::int32_t size, const std::string& value) {
  return name + std::string(1, '\0') + type + std::string(1, '\0') + le32(size) + value;
}

// The magic number, version 2 with `flags`, then `body` (attributes and header ends).
void write_exr_bytes(const std::string& path, const std::string& body, std::int32_t flags = 0) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << std::string("\x76\x2f\x31\x01", 4) << le32(2 | flags)
                                                           << body;
}

// Reading `f` every way (frame, loose pass, the check alone) fails with all of `parts`.
void expect_refused(const std::string& f, const std::vector<std::string>& parts) {
  expect_error(Errc::ReadFailed, parts, [&] { read_frame(f); });
  expect_error(Errc::ReadFailed, parts, [&] { read_pass_file(f, Role::Colour); });
  expect_error(Errc::ReadFailed, parts, [&] { check_exr_header_sizes(f); });
}

TEST(InputLimits, AttributeSizePastTheEndOfTheFileIsRefusedBeforeOpening) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("claim.exr");
  // A real file with a string attribute, whose declared size then claims 842019328 bytes
  // (OpenEXR would allocate them before reading).
  {
    OIIO::ImageSpec spec(8, 8, 4, OIIO::TypeFloat);
    spec.attribute("note", "abc");
    std::vector<float> px(8 * 8 * 4, 0.5f);
    auto out = OIIO::ImageOutput::create(f);
    ASSERT_TRUE(out && out->open(f, spec) && out->write_image(OIIO::TypeFloat, px.data())) << OIIO::geterror();
    out->close();
  }
  EXPECT_NO_THROW(check_exr_header_sizes(f));  // the file as written passes
  EXPECT_EQ(read_frame(f).width, 8);
  std::string bytes = file_bytes(f);
  const std::string key = std::string("note\0string\0", 12);
  const auto at = bytes.find(key);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at + key.size(), 4, le32(842019328));
  std::ofstream(f, std::ios::binary | std::ios::trunc) << bytes;
  const std::uint64_t left = bytes.size() - (at + key.size() + 4);
  expect_refused(f, {"'" + f + "'", "header attribute 'note' claims 842019328 bytes but only " +
                                        std::to_string(left) + " of the file's " + std::to_string(bytes.size()) +
                                        " bytes follow it"});
  // Negative sizes too.
  bytes.replace(at + key.size(), 4, le32(-5));
  std::ofstream(f, std::ios::binary | std::ios::trunc) << bytes;
  expect_refused(f, {"'" + f + "'", "header attribute 'note' claims -5 bytes"});
}

TEST(InputLimits, MalformedHeaderNamesAreRefused) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("names.exr");
  write_exr_bytes(f, "dataWin");  // the file ends inside a name
  expect_refused(f, {"'" + f + "'", "the name of header attribute 1 'dataWin' has no terminator"});
  write_exr_bytes(f, exr_attribute("owner", "string", 2, "me") + "lineOrder");
  expect_refused(f, {"the name of header attribute 2 'lineOrder' has no terminator"});
  write_exr_bytes(f, std::string("owner\0stri", 10));  // ... or inside a type
  expect_refused(f, {"the type of header attribute 'owner' 'stri' has no terminator"});
  write_exr_bytes(f, exr_attribute(std::string(300, 'n'), "string", 2, "me") + std::string(1, '\0'));
  expect_refused(f, {"'" + f + "'", "the name of header attribute 1 '" + std::string(32, 'n') + "...' is longer than 255 bytes"});
  write_exr_bytes(f, std::string("owner\0string\0\x02\0", 15));  // a size cut short
  expect_refused(f, {"the size of header attribute 'owner' is cut off by the end of the file"});
}

// OpenEXR reads fixed-size values and channel lists by their layout, ignoring the size
// the header declares, and the next attribute starts where it stopped: the check walks
// the header the same way (a fuzzed file hid an 842 MB claim behind a channel list).
TEST(InputLimits, TheHeaderIsWalkedAsOpenExrWalksIt) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("walk.exr");
  const std::string zero(1, '\0');
  const std::string channel = "R" + zero + le32(2) + std::string(4, '\0') + le32(1) + le32(1);  // float, 1x1 sampling
  const std::string claim = exr_attribute("\x13", "", 842019328, "") + std::string(64, 'x');
  // A channel list declared 4 bytes long, 19 in fact.
  write_exr_bytes(f, exr_attribute("channels", "chlist", 4, channel + zero) + claim);
  expect_refused(f, {"'" + f + "'", "header attribute '\\x13' claims 842019328 bytes but only 64 of the file's"});
  // A data window declared 0 bytes long, 16 in fact.
  write_exr_bytes(f, exr_attribute("dataWindow", "box2i", 0, le32(0) + le32(0) + le32(7) + le32(7)) + claim);
  expect_refused(f, {"header attribute '\\x13' claims 842019328 bytes but only 64 of the file's"});
  // A data window declared 200 bytes long: OpenEXR still reads 16, then the claim.
  write_exr_bytes(f, exr_attribute("dataWindow", "box2i", 200, le32(0) + le32(0) + le32(7) + le32(7)) + claim +
                         std::string(200, 'y'));
  expect_refused(f, {"header attribute '\\x13' claims 842019328 bytes but only 264 of the file's"});
}

// OpenImageIO 2.4 aborts the process on a channel of a pixel type it does not know.
TEST(InputLimits, UnknownChannelPixelTypesAreRefusedBeforeOpening) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("ptype.exr");
  write_flat(f, 4, 4, 4, "zip");
  std::string bytes = file_bytes(f);
  const auto at = bytes.find(std::string("G\0", 2) + le32(2));  // channel G, float
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at + 2, 4, le32(3));
  std::ofstream(f, std::ios::binary | std::ios::trunc) << bytes;
  expect_refused(f, {"'" + f + "'", "channel 'G' has pixel type 3 (OpenEXR's are 0 uint, 1 half, 2 float)"});
}

TEST(InputLimits, ClaimsInsideAnAttributeAreRefused) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("inside.exr");
  // A string vector whose one string claims a million bytes in an 8-byte value.
  write_exr_bytes(f, exr_attribute("views", "stringvector", 8, le32(1000000) + "abcd") + std::string(1, '\0'));
  expect_refused(f, {"'" + f + "'", "header attribute 'views' holds a string that claims 1000000 bytes but only 4 of "
                                    "the attribute's 8 bytes follow it"});
  // A 60000x60000 preview (14.4 GB) in 16 bytes.
  write_exr_bytes(f, exr_attribute("preview", "preview", 16, le32(60000) + le32(60000) + "rgbargba") + std::string(1, '\0'));
  expect_refused(f, {"header attribute 'preview' claims a 60000x60000 preview (14.4 GB) in 16 bytes"});
}

TEST(InputLimits, EveryPartOfAMultiPartHeaderIsChecked) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("parts.exr");
  write_two_parts(f, 8, 8);
  EXPECT_NO_THROW(check_exr_header_sizes(f));
  // The same attribute in part 1 only claims too much.
  const std::string part0 = exr_attribute("name", "string", 3, "one") + std::string(1, '\0');
  const std::string part1 = exr_attribute("name", "string", 3, "two") + exr_attribute("note", "string", 99999, "x") +
                            std::string(1, '\0');
  write_exr_bytes(f, part0 + part1 + std::string(1, '\0'), 0x1000);
  expect_refused(f, {"'" + f + "'", "header attribute 'note' in part 1 claims 99999 bytes"});
}

TEST(InputLimits, TilesLargerThanTheDataWindowAreRefusedBeforeOpening) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("tiled.exr");
  write_flat(f, 16, 16, 4, "zip", OIIO::TypeFloat, 16);
  EXPECT_NO_THROW(check_exr_header_sizes(f));
  // 2048x16 tiles of 4 float channels (512 KB) fit the budget but not a 16x16 image.
  ASSERT_EQ(patch_attribute(f, "tiles", "tiledesc", {2048, 16}), 1);
  expect_refused(f, {"'" + f + "'", "its header asks for tiles of 2048x16 pixels, larger than its 16x16 data window"});
  // A usual tile size on a small image reads.
  write_flat(f, 5, 4, 4, "zip", OIIO::TypeFloat, 64);
  EXPECT_EQ(read_frame(f).width, 5);
}

TEST(InputLimits, HugeDeepTilesAreRefusedBeforeOpening) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("deep_tiled.exr");
  // A 5x4 deep tiled file (5 channels) whose header then claims 67108866x2 tiles: OpenEXR
  // would allocate tile buffers of that size when the file opens.
  {
    OIIO::ImageSpec spec(5, 4, 5, OIIO::TypeHalf);
    spec.channelnames = {"R", "G", "B", "A", "Z"};
    spec.alpha_channel = 3;
    spec.z_channel = 4;
    spec.deep = true;
    spec.tile_width = spec.tile_height = 16;
    spec.attribute("compression", "zips");
    OIIO::DeepData dd(spec);
    for (int p = 0; p < 20; ++p) {
      dd.set_samples(p, 1);
      for (int c = 0; c < 5; ++c) dd.set_deep_value(p, c, 0, 0.5f);
    }
    auto out = OIIO::ImageOutput::create(f);
    ASSERT_TRUE(out && out->open(f, spec) && out->write_deep_image(dd)) << OIIO::geterror();
    out->close();
  }
  EXPECT_EQ(read_frame(f).deep->total_samples(), 20u);
  ASSERT_EQ(patch_attribute(f, "tiles", "tiledesc", {67108866, 2}), 1);
  expect_refused(f, {"'" + f + "'", "its header asks for tiles of 67108866x2x5 float (2.68 GB)", "can hold at most"});
}

TEST(InputLimits, WideScanlinesAreRefusedBeforeOpening) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("wide.exr");
  write_flat(f, 8, 8, 4, "zip");  // 16 scanlines a chunk
  // 100 million pixels wide: OpenEXR would allocate line buffers of 8 x 1.6 GB when it opens the file.
  ASSERT_EQ(patch_attribute(f, "dataWindow", "box2i", {0, 0, 99999999, 7}), 1);
  expect_refused(f, {"'" + f + "'", "its header asks for scanlines of 100000000x4 float, read 8 at a time (12.8 GB)",
                     "can hold at most"});
}

TEST(InputLimits, DataWindowsWhoseOffsetTableExceedsTheFileAreRefusedBeforeOpening) {
  ScratchDir dir("mcrecon_limits");
  const std::string f = dir.path("tall.exr");
  write_flat(f, 8, 8, 4, "zips");  // one scanline a chunk: 8 bytes of offset table a line
  const auto size = fs::file_size(f);
  // 100 million lines: OpenEXR would allocate an 800 MB offset table when it opens the file.
  ASSERT_EQ(patch_attribute(f, "dataWindow", "box2i", {0, 0, 7, 99999999}), 1);
  expect_refused(f, {"'" + f + "'", "a 8x100000000 data window in 100000000 chunks, whose table of offsets alone (800 MB) "
                                    "exceeds the " + byte_text(double(size)) + " file"});
  // Tiles: 16x16 tiles over 160000x160000 pixels are 10000^2 offsets (800 MB).
  write_flat(f, 16, 16, 4, "zip", OIIO::TypeFloat, 16);
  ASSERT_EQ(patch_attribute(f, "dataWindow", "box2i", {0, 0, 159999, 159999}), 1);
  expect_refused(f, {"'" + f + "'", "in 100000000 tiles, whose table of offsets alone (800 MB)"});
}

// Each compression's bound against the best ratio it reaches here: a constant
// image (float bytes per file byte), with margin to spare for larger images.
TEST(InputLimits, BoundsExceedMeasuredRatios) {
  ScratchDir dir("mcrecon_limits");
  for (const char* c : {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"}) {
    const std::string f = dir.path(std::string(c) + ".exr");
    write_flat(f, 512, 512, 4, c, OIIO::TypeHalf, 512, 0.0f);
    const double ratio = 512.0 * 512 * 4 * 4 / double(fs::file_size(f));
    EXPECT_GT(max_expansion("openexr", c), 1.5 * ratio) << c << ": measured " << ratio;
    EXPECT_EQ(read_frame(f).width, 512) << c;  // and such a file still reads
  }
}

TEST(InputLimits, ByteCounts) {
  EXPECT_EQ(parse_byte_count("8G", "x"), 8000000000u);
  EXPECT_EQ(parse_byte_count("2GiB", "x"), 2147483648u);
  EXPECT_EQ(parse_byte_count("1.5m", "x"), 1500000u);
  EXPECT_EQ(parse_byte_count("500000", "x"), 500000u);
  for (const char* bad : {"", "lots", "-1G", "0", "8X", "8GG", "1e30"})
    expect_error(Errc::InvalidArgument, {std::string("x='") + bad + "'"}, [&] { parse_byte_count(bad, "x"); });
  EXPECT_EQ(byte_text(1.6e11), "160 GB");
  EXPECT_EQ(byte_text(800000), "800 KB");
  EXPECT_EQ(byte_text(12), "12 bytes");
}

// ------------------------------------------------------------------ threads

TEST(InputLimits, ThreadCountsAreClampedToTheHardware) {
  const int cores = tbb::info::default_concurrency();
  EXPECT_EQ(arena_threads(100000), cores);
  EXPECT_EQ(arena_threads(100000000), cores);
  EXPECT_EQ(arena_threads(1), 1);
  EXPECT_EQ(arena_threads(0), tbb::task_arena::automatic);
  std::vector<int> seen(1000, 0);
  parallel_rows(0, 1000, 100000000, [&](int y) { seen[std::size_t(y)] += 1; });
  EXPECT_EQ(std::vector<int>(1000, 1), seen);
}

TEST(InputLimits, NegativeThreadCountsAreRefused) {
  EXPECT_EQ(checked_thread_count(0, "threads=0"), 0);
  EXPECT_EQ(checked_thread_count(100000, "threads=100000"), 100000);
  expect_error(Errc::InvalidArgument, {"threads=-1: expected 0 (all cores) or a positive count"},
               [] { checked_thread_count(-1, "threads=-1"); });
}

}  // namespace
}  // namespace mcr
