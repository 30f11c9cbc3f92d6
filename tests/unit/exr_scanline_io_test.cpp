// The scanline EXR I/O (io/exr_scanline_io.h, io/exr_zip.h) against OpenImageIO and OpenEXR's
// own codec: files OpenImageIO writes read back bit for bit, files written here read back bit
// for bit through OpenImageIO with the same header, corrupt chunks are errors naming the file.
#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <openexr.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "expect_error.h"
#include "io/atomic_write.h"
#include "io/exr_scanline_io.h"
#include "io/exr_zip.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "scratch_dir.h"
#include "util/error.h"

namespace mcr {
namespace {

using namespace OIIO;
using testutil::expect_error;
using testutil::ScratchDir;

const std::vector<std::string> kNames = {"R", "G", "B", "A", "Depth.V", "Normal.X", "Normal.Y", "ViewLayer.Denoising Normal.Z"};

// Channel c's type in the test files: colour half, the rest float (as Blender writes them).
TypeDesc type_of(std::size_t c) { return c < 4 ? TypeHalf : TypeFloat; }

// Native pixels of kNames: `smooth` compresses (zip chunks stored compressed), otherwise
// random bits (chunks stored raw), NaN and Inf payloads included.
std::vector<unsigned char> native_pixels(int w, int h, bool smooth, std::size_t& stride) {
  stride = 0;
  for (std::size_t c = 0; c < kNames.size(); ++c) stride += type_of(c).size();
  std::vector<unsigned char> px(std::size_t(w) * std::size_t(h) * stride);
  std::mt19937 rng(7);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      unsigned char* p = px.data() + (std::size_t(y) * std::size_t(w) + std::size_t(x)) * stride;
      for (std::size_t c = 0; c < kNames.size(); ++c) {
        const float v = float(c) + 0.01f * float(x) + 0.1f * float(y);
        if (type_of(c) == TypeHalf) {
          const std::uint16_t bits = smooth ? Imath::half(v).bits() : std::uint16_t(rng());
          std::memcpy(p, &bits, 2);
          p += 2;
        } else {
          std::uint32_t bits;
          if (smooth) std::memcpy(&bits, &v, 4);
          else bits = std::uint32_t(rng());
          std::memcpy(p, &bits, 4);
          p += 4;
        }
      }
    }
  return px;
}

void write_with_oiio(const std::string& path, int w, int h, const std::string& compression,
                     const std::vector<unsigned char>& px) {
  ImageSpec spec(w, h, int(kNames.size()), TypeFloat);
  spec.channelnames = kNames;
  spec.channelformats.clear();
  for (std::size_t c = 0; c < kNames.size(); ++c) spec.channelformats.push_back(type_of(c));
  spec.x = -3, spec.y = 5;
  spec.attribute("compression", compression);
  auto out = ImageOutput::create(path);
  ASSERT_TRUE(out && out->open(path, spec)) << (out ? out->geterror() : OIIO::geterror());
  ASSERT_TRUE(out->write_image(TypeUnknown, px.data()));
  ASSERT_TRUE(out->close());
}

NativeLayout layout_of(std::size_t stride) {
  NativeLayout l;
  l.names = kNames;
  l.stride = stride;
  std::size_t at = 0;
  for (std::size_t c = 0; c < kNames.size(); ++c) {
    l.offset.push_back(at);
    l.is_half.push_back(type_of(c) == TypeHalf);
    at += type_of(c).size();
  }
  return l;
}

TEST(ExrZipTest, EncodeThenDecodeGivesTheBytesBackAtEveryLength) {
  std::mt19937 rng(3);
  for (std::size_t n : {1u, 2u, 3u, 17u, 1000u, 4097u}) {
    std::vector<std::uint8_t> raw(n), packed, back(n);
    for (std::size_t i = 0; i < n; ++i) raw[i] = std::uint8_t(i % 7 == 0 ? rng() : i / 5);  // mostly compressible
    const std::size_t size = exr_zip::encode(raw.data(), n, 4, packed);
    if (size == 0) {  // too short to shrink: stored raw
      EXPECT_LT(n, 100u);
      continue;
    }
    ASSERT_LT(size, n);
    ASSERT_TRUE(exr_zip::decode(packed.data(), size, back.data(), n)) << n;
    EXPECT_EQ(back, raw) << n;
    // One byte too few or too many expected: not this chunk.
    std::vector<std::uint8_t> other(n + 1);
    EXPECT_FALSE(exr_zip::decode(packed.data(), size, other.data(), n + 1));
    EXPECT_FALSE(exr_zip::decode(packed.data(), size, other.data(), n - 1));
  }
}

// Files OpenImageIO (OpenEXR's zlib codec) wrote, read here: every byte as OpenImageIO reads them.
TEST(ExrScanlineIoTest, ReadsWhatOpenImageIoWritesBitForBit) {
  ScratchDir dir("mcrecon_exr_io");
  const int w = 29, h = 37;  // 37 rows: the last zip chunk holds 5
  for (const char* compression : {"zip", "zips", "none"})
    for (bool smooth : {true, false}) {
      SCOPED_TRACE(std::string(compression) + (smooth ? " smooth" : " random bits"));
      std::size_t stride = 0;
      const std::vector<unsigned char> px = native_pixels(w, h, smooth, stride);
      const std::string path = dir.path(std::string("in_") + compression + ".exr");
      write_with_oiio(path, w, h, compression, px);
      std::vector<unsigned char> got(px.size(), 0xAB);
      ASSERT_TRUE(read_exr_scanlines(path, w, h, layout_of(stride), got.data()));
      EXPECT_TRUE(got == px);
    }
}

// Rows read a range at a time (bands) are the whole read's rows, from any row to any row.
TEST(ExrScanlineIoTest, RowRangesAreTheWholeReadsRows) {
  ScratchDir dir("mcrecon_exr_io");
  const int w = 13, h = 53;
  std::size_t stride = 0;
  const std::vector<unsigned char> px = native_pixels(w, h, true, stride);
  const std::size_t row = std::size_t(w) * stride;
  for (const char* compression : {"zip", "zips"}) {
    SCOPED_TRACE(compression);
    write_with_oiio(dir.path("in.exr"), w, h, compression, px);
    const auto reader = ExrScanlineReader::open(dir.path("in.exr"), w, h, layout_of(stride));
    ASSERT_TRUE(reader);
    EXPECT_EQ(reader->chunk_rows(), std::string(compression) == "zip" ? 16 : 1);
    for (const auto& [y0, y1] : std::vector<std::pair<int, int>>{{0, 53}, {0, 1}, {5, 21}, {16, 32}, {15, 17}, {47, 53}, {52, 53}}) {
      std::vector<unsigned char> got(std::size_t(y1 - y0) * row, 0xCD);
      reader->read(y0, y1, got.data());
      EXPECT_TRUE(std::equal(got.begin(), got.end(), px.begin() + std::ptrdiff_t(std::size_t(y0) * row))) << y0 << ".." << y1;
    }
  }
}

TEST(ExrScanlineIoTest, OtherFilesAreLeftToOpenImageIo) {
  ScratchDir dir("mcrecon_exr_io");
  std::size_t stride = 0;
  const std::vector<unsigned char> px = native_pixels(8, 8, true, stride);
  std::vector<unsigned char> got(px.size());
  write_with_oiio(dir.path("piz.exr"), 8, 8, "piz", px);
  EXPECT_FALSE(read_exr_scanlines(dir.path("piz.exr"), 8, 8, layout_of(stride), got.data()));
  write_with_oiio(dir.path("zip.exr"), 8, 8, "zip", px);
  NativeLayout wrong = layout_of(stride);
  wrong.is_half[0] = 0;  // the caller expects float where the file holds half
  EXPECT_FALSE(read_exr_scanlines(dir.path("zip.exr"), 8, 8, wrong, got.data()));
  set_exr_scanline_io(false);
  EXPECT_FALSE(read_exr_scanlines(dir.path("zip.exr"), 8, 8, layout_of(stride), got.data()));
  set_exr_scanline_io(true);
}

// The byte offset of chunk k's data (after its y and size fields), from OpenEXR's chunk table.
std::uint64_t chunk_data_offset(const std::string& path, int y) {
  exr_context_t ctxt = nullptr;
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  EXPECT_EQ(exr_start_read(&ctxt, path.c_str(), &init), EXR_ERR_SUCCESS);
  exr_chunk_info_t ci;
  EXPECT_EQ(exr_read_scanline_chunk_info(ctxt, 0, y, &ci), EXR_ERR_SUCCESS);
  exr_finish(&ctxt);
  return ci.data_offset;
}

TEST(ExrScanlineIoTest, CorruptOrTruncatedChunksAreReadErrorsNamingTheFileAndRows) {
  ScratchDir dir("mcrecon_exr_io");
  const int w = 64, h = 48;
  std::size_t stride = 0;
  const std::vector<unsigned char> px = native_pixels(w, h, true, stride);
  const std::string path = dir.path("zip.exr");
  write_with_oiio(path, w, h, "zip", px);
  std::vector<unsigned char> got(px.size());
  const std::uint64_t at = chunk_data_offset(path, 5 + 16);  // the second chunk (data window from y 5)
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(at + 20));
    const char junk[8] = {'\x13', '\x37', '\x00', '\xff', '\x42', '\x24', '\x99', '\x01'};
    f.write(junk, sizeof junk);
  }
  expect_error(Errc::ReadFailed, {path, "rows from 21"}, [&] { read_exr_scanlines(path, w, h, layout_of(stride), got.data()); });
  expect_error(Errc::ReadFailed, {path}, [&] { read_frame(path); });

  // A damaged offset table is refused too (OpenEXRCore would rebuild it; OpenImageIO refuses).
  write_with_oiio(path, w, h, "zip", px);
  ASSERT_TRUE(read_exr_scanlines(path, w, h, layout_of(stride), got.data()));
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    const std::uint64_t table = chunk_data_offset(path, 5) - 8 - 3 * 8;  // three chunks, the first right after
    f.seekg(std::streamoff(table + 8));
    std::uint64_t second = 0;
    f.read(reinterpret_cast<char*>(&second), 8);
    ASSERT_EQ(second + 8, chunk_data_offset(path, 5 + 16));
    second += std::uint64_t(1) << 40;  // far past the end: OpenEXRCore rebuilds the table
    f.seekp(std::streamoff(table + 8));
    f.write(reinterpret_cast<const char*>(&second), 8);
  }
  expect_error(Errc::ReadFailed, {path, "offset table"}, [&] { read_exr_scanlines(path, w, h, layout_of(stride), got.data()); });

  write_with_oiio(path, w, h, "zip", px);
  std::filesystem::resize_file(path, chunk_data_offset(path, 5 + 32) + 10);  // the last chunk cut short
  expect_error(Errc::ReadFailed, {path}, [&] { read_exr_scanlines(path, w, h, layout_of(stride), got.data()); });
}

// Float pixels of nc channels: random bits (NaN and Inf payloads included) or smooth values.
std::vector<float> float_pixels(int w, int h, int nc, bool smooth) {
  std::vector<float> px(std::size_t(w) * std::size_t(h) * std::size_t(nc));
  std::mt19937 rng(11);
  for (std::size_t i = 0; i < px.size(); ++i) {
    const std::uint32_t bits = std::uint32_t(rng());
    if (smooth) px[i] = float(i % std::size_t(nc)) + 0.001f * float(i / std::size_t(nc));
    else std::memcpy(&px[i], &bits, 4);
  }
  return px;
}

// Written here, read by OpenImageIO (OpenEXR's zlib codec): the same bits, windows and header.
TEST(ExrScanlineIoTest, WritesWhatOpenImageIoReadsBitForBitWithTheSameHeader) {
  ScratchDir dir("mcrecon_exr_io");
  const int w = 33, h = 35;
  const std::vector<std::string> names = {"R", "G", "B", "A", "denoised_diffuse_direct_and_indirect.R", "Albedo.B"};  // not sorted, one over 31 bytes
  const int nc = int(names.size());
  const PixelWindow window{7, -2, 0, 0, 40, 30};
  const std::vector<std::pair<std::string, std::string>> attrs = {{"mcreconFilter", "pwaf"}, {"mcreconParameters", "a=1 b=2"}};
  for (const char* compression : {"zip", "zips", "none", "zip:9"})
    for (bool smooth : {true, false}) {
      SCOPED_TRACE(std::string(compression) + (smooth ? " smooth" : " random bits"));
      const std::vector<float> px = float_pixels(w, h, nc, smooth);
      const std::string path = dir.path("out.exr");
      ASSERT_TRUE(exr_scanline_compression(compression));
      write_fd_atomic(path, [&](int fd) { return write_exr_scanlines(fd, path, w, h, window, names, px.data(), compression, attrs); });
      auto in = ImageInput::open(path);
      ASSERT_TRUE(in) << OIIO::geterror();
      const ImageSpec& spec = in->spec();
      EXPECT_EQ(spec.x, 7);
      EXPECT_EQ(spec.y, -2);
      EXPECT_EQ(spec.full_width, 40);
      EXPECT_EQ(spec.full_height, 30);
      EXPECT_EQ(spec.get_string_attribute("compression"), std::string(compression).substr(0, std::string(compression).find(':')));
      EXPECT_EQ(spec.get_string_attribute("mcreconFilter"), "pwaf");
      EXPECT_EQ(spec.get_string_attribute("mcreconParameters"), "a=1 b=2");
      EXPECT_EQ(spec.get_string_attribute("Software"), "mcrecon");
      EXPECT_FALSE(spec.get_string_attribute("DateTime").empty());
      std::vector<float> got(px.size());
      std::vector<float> by_name(px.size());
      ASSERT_TRUE(in->read_image(0, 0, 0, nc, TypeFloat, got.data())) << in->geterror();
      // OpenImageIO lists the channels its own way: compare by name.
      for (int c = 0; c < nc; ++c) {
        const int at = spec.channelindex(names[std::size_t(c)]);
        ASSERT_GE(at, 0) << names[std::size_t(c)];
        for (std::size_t p = 0; p < std::size_t(w) * std::size_t(h); ++p)
          by_name[p * std::size_t(nc) + std::size_t(c)] = got[p * std::size_t(nc) + std::size_t(at)];
      }
      EXPECT_EQ(std::memcmp(by_name.data(), px.data(), px.size() * sizeof(float)), 0);
    }
  EXPECT_FALSE(exr_scanline_compression("piz"));
  EXPECT_FALSE(exr_scanline_compression("dwaa:45"));
}

// The front-end path: a result written and read back is the same frame with the scanline
// I/O on and off (OpenImageIO both ways), file for file.
TEST(ExrScanlineIoTest, FramesReadAndWrittenEitherWayAreTheSame) {
  ScratchDir dir("mcrecon_exr_io");
  const int w = 21, h = 19;
  std::size_t stride = 0;
  const std::vector<unsigned char> px = native_pixels(w, h, true, stride);
  write_with_oiio(dir.path("in.exr"), w, h, "zip", px);
  Frame frames[2];
  for (int on = 0; on < 2; ++on) {
    set_exr_scanline_io(on == 1);
    ReadOptions all;
    all.keep_extra = true;
    frames[on] = read_frame(dir.path("in.exr"), all);
    WriteOptions keep;
    keep.keep_passes = true;
    write_result(dir.path("out" + std::to_string(on) + ".exr"), frames[on].find(Role::Colour)->image, frames[on], keep);
  }
  set_exr_scanline_io(true);
  ASSERT_EQ(frames[0].passes.size(), frames[1].passes.size());
  for (std::size_t i = 0; i < frames[0].passes.size(); ++i) {
    const Image& a = frames[0].passes[i].image;
    const Image& b = frames[1].passes[i].image;
    ASSERT_EQ(a.storage().size(), b.storage().size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.storage().size() * sizeof(float)), 0) << frames[0].passes[i].name;
  }
  std::vector<float> out[2];
  for (int on = 0; on < 2; ++on) {
    auto in = ImageInput::open(dir.path("out" + std::to_string(on) + ".exr"));
    ASSERT_TRUE(in);
    out[on].resize(std::size_t(w) * std::size_t(h) * std::size_t(in->spec().nchannels));
    ASSERT_TRUE(in->read_image(0, 0, 0, in->spec().nchannels, TypeFloat, out[on].data()));
    EXPECT_EQ(in->spec().y, 5);
  }
  EXPECT_EQ(out[0], out[1]);
}

}  // namespace
}  // namespace mcr
