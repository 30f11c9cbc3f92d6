// Display previews: Blender's OCIO config, sRGB display, Standard view, against the sRGB
// transfer function computed here; the strip's layout (tiles left to right, black gaps,
// 8-bit RGB PNG) and the errors.
#include "io/preview.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "expect_error.h"
#include "scratch_dir.h"
#include "srgb_testutil.h"

namespace mcr {
namespace {

using namespace testutil;

int expected_code(double linear) { return srgb_code(linear); }

struct Png {
  int width = 0, height = 0, channels = 0;
  OIIO::TypeDesc format;
  std::string format_name;
  std::vector<unsigned char> px;
  int at(int x, int y, int c) const { return px[(std::size_t(y) * width + x) * channels + c]; }
};

Png read_png(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error("cannot open " + path + ": " + OIIO::geterror());
  Png p;
  const OIIO::ImageSpec& s = in->spec();
  p.width = s.width;
  p.height = s.height;
  p.channels = s.nchannels;
  p.format = s.format;
  p.format_name = in->format_name();
  p.px.resize(std::size_t(s.width) * s.height * s.nchannels);
  if (!in->read_image(0, 0, 0, s.nchannels, OIIO::TypeUInt8, p.px.data())) throw std::runtime_error(in->geterror());
  return p;
}

// Tile pixel (x, y) channel c: linear values at the centres of chosen 8-bit codes (so a LUT
// that approximates the transfer cannot round to a neighbour), plus out-of-range ones.
double tile_value(int tile, int x, int y, int c) {
  static const int codes[] = {0, 3, 10, 37, 64, 100, 128, 170, 200, 230, 250, 255};
  const int k = (tile * 7 + y * 5 + x * 3 + c) % 14;
  if (k == 12) return 3.5;   // above 1: white
  if (k == 13) return -0.5;  // below 0: black
  return srgb_decode(codes[k] / 255.0);
}

Image make_tile(int tile, int w, int h, int channels) {
  Image im(w, h, channels, 0.25f);  // alpha (channel 3) is not shown
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = float(tile_value(tile, x, y, c));
  return im;
}

TEST(Preview, StandardViewIsTheSrgbTransferAndTilesSitSideBySide) {
  const ScratchDir dir("mcrecon_preview");
  const Image a = make_tile(0, 3, 4, 3), b = make_tile(1, 2, 4, 4), c = make_tile(2, 5, 4, 3);
  DisplayOptions opt;
  opt.gap = 2;
  const std::string out = dir.path("strip.png");
  write_side_by_side_png(out, {&a, &b, &c}, opt);
  EXPECT_EQ(dir.listing(), std::vector<std::string>{"strip.png"});  // no temp file left
  const Png png = read_png(out);
  EXPECT_EQ(png.format_name, "png");
  EXPECT_EQ(png.format, OIIO::TypeUInt8);
  ASSERT_EQ(png.channels, 3);
  ASSERT_EQ(png.height, 4);
  ASSERT_EQ(png.width, 3 + 2 + 2 + 2 + 5);
  const int x0[3] = {0, 5, 9}, widths[3] = {3, 2, 5};
  for (int t = 0; t < 3; ++t)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < widths[t]; ++x)
        for (int ch = 0; ch < 3; ++ch)
          ASSERT_EQ(png.at(x0[t] + x, y, ch), expected_code(tile_value(t, x, y, ch)))
              << "tile " << t << " pixel " << x << "," << y << " channel " << ch;
  for (int gx : {3, 4, 7, 8})
    for (int y = 0; y < 4; ++y)
      for (int ch = 0; ch < 3; ++ch) ASSERT_EQ(png.at(gx, y, ch), 0) << "gap column " << gx;
}

TEST(Preview, DefaultGapIsFourPixels) {
  const ScratchDir dir("mcrecon_preview");
  const Image a = make_tile(0, 2, 3, 3);
  write_side_by_side_png(dir.path("two.png"), {&a, &a});
  const Png png = read_png(dir.path("two.png"));
  EXPECT_EQ(png.width, 2 + 4 + 2);
  EXPECT_EQ(png.height, 3);
}

TEST(Preview, Errors) {
  const ScratchDir dir("mcrecon_preview");
  const Image a(3, 4, 3, 0.5f), taller(3, 5, 3, 0.5f);
  expect_error(Errc::SizeMismatch, {"height"}, [&] { write_side_by_side_png(dir.path("x.png"), {&a, &taller}); });
  expect_error(Errc::Internal, {"no tiles"}, [&] { write_side_by_side_png(dir.path("x.png"), {}); });
  DisplayOptions missing;
  missing.config = dir.path("nowhere.ocio");
  expect_error(Errc::FileNotFound, {missing.config}, [&] { write_side_by_side_png(dir.path("x.png"), {&a}, missing); });
  DisplayOptions bad_view;
  bad_view.view = "NoSuchView";
  expect_error(Errc::InvalidArgument, {"NoSuchView"}, [&] { write_side_by_side_png(dir.path("x.png"), {&a}, bad_view); });
  EXPECT_TRUE(dir.listing().empty());
}

}  // namespace
}  // namespace mcr
