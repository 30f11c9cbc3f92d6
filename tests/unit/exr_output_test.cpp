// What an output may be (io/exr_output.h): the compressions OpenImageIO writes, .exr names,
// and whether an existing output reads completely (--resume).
#include "io/exr_output.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "expect_error.h"
#include "io/frame_writer.h"
#include "scratch_dir.h"

namespace mcr {
namespace {

using testutil::expect_error;

Frame noisy_frame(int w, int h) {
  Frame f;
  f.width = w;
  f.height = h;
  Pass p;
  p.role = Role::Colour;
  p.name = "colour";
  p.image = Image(w, h, 3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) p.image.at(x, y, c) = u(rng);
  f.put(std::move(p));
  return f;
}

std::string compression_in_header(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return "(unreadable: " + OIIO::geterror() + ")";
  return in->spec().get_string_attribute("compression");
}

// Every name the check lets through is one OpenImageIO's EXR writer really uses (it writes
// zip, silently, for a name it does not know): the header read back names it.
TEST(ExrOutput, EveryAcceptedCompressionIsWrittenAsNamed) {
  testutil::ScratchDir dir("mcr_exr_output");
  const Frame f = noisy_frame(40, 33);
  for (const char* text : {"none", "rle", "zip", "zips", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab", "ZIP", "zip:1",
                           "zips:9", "dwaa:45", "DWAB:200.5"}) {
    SCOPED_TRACE(text);
    const std::string name = checked_exr_compression(text);
    WriteOptions wo;
    wo.compression = name;
    const std::string out = dir.path("c.exr");
    write_result(out, f.image(Role::Colour), f, wo);
    EXPECT_EQ(compression_in_header(out), name.substr(0, name.find(':')));
  }
  // zip's level reaches the file: level 1 and 9 compress noise to different sizes.
  WriteOptions wo;
  wo.compression = checked_exr_compression("zip:1");
  write_result(dir.path("z1.exr"), f.image(Role::Colour), f, wo);
  wo.compression = checked_exr_compression("zip:9");
  write_result(dir.path("z9.exr"), f.image(Role::Colour), f, wo);
  EXPECT_NE(std::filesystem::file_size(dir.path("z1.exr")), std::filesystem::file_size(dir.path("z9.exr")));
}

TEST(ExrOutput, UnknownCompressionsAndLevelsAreRefusedWithTheValidNames) {
  for (const char* text : {"bogus", "", "zip2", "jpeg", "zip:", "zip:0", "zip:10", "zip:2.5", "zip:x", "dwaa:0",
                           "dwaa:-3", "dwab:inf", "piz:5", "none:1", "zip:9:9"}) {
    SCOPED_TRACE(text);
    const std::string msg = expect_error(Errc::InvalidArgument, [&] { checked_exr_compression(text); });
    EXPECT_NE(msg.find("compression '" + std::string(text) + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("none, rle, zip, zips, piz, pxr24, b44, b44a, dwaa, dwab"), std::string::npos) << msg;
  }
}

TEST(ExrOutput, OutputNamesMustEndInExr) {
  for (const char* ok : {"out.exr", "dir/out.EXR", "o_####.exr", "a.b.Exr", "./x.exr"}) check_exr_name(ok);
  for (const char* bad : {"out.xyz", "out.png", "out", ".exr", "dir.exr/out", "out.exr.tmp", "outexr", "d/.exr"}) {
    SCOPED_TRACE(bad);
    const std::string msg = expect_error(Errc::InvalidArgument, [&] { check_exr_name(bad); });
    EXPECT_EQ(msg, "output '" + std::string(bad) + "': mcrecon writes OpenEXR; use a .exr name");
  }
}

TEST(ExrOutput, OnlyAFileThatReadsCompletelyIsComplete) {
  testutil::ScratchDir dir("mcr_exr_output");
  const Frame f = noisy_frame(64, 48);
  const std::string out = dir.path("o.exr");
  write_result(out, f.image(Role::Colour), f);
  EXPECT_EQ(incomplete_file_reason(out), "");
  std::string bytes;
  {
    std::ifstream in(out, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  // Cut in the header, the offset table, the pixel data and at the last byte.
  for (std::size_t n : {std::size_t(0), std::size_t(100), bytes.size() / 2, bytes.size() - 1}) {
    SCOPED_TRACE(n);
    std::ofstream(out, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(n));
    const std::string why = incomplete_file_reason(out);
    EXPECT_NE(why, "");
    EXPECT_NE(why.find("o.exr"), std::string::npos) << why;
  }
  EXPECT_NE(incomplete_file_reason(dir.path("missing.exr")), "");
}

}  // namespace
}  // namespace mcr
