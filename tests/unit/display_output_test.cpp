// Display-referred outputs: the format a name asks for, PNG/JPEG/TIFF through Blender's
// Standard view against the sRGB transfer computed here (srgb_testutil.h), exposure, gamma,
// alpha, bit depths, and the refusals (check_write).
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "expect_error.h"
#include "io/frame_writer.h"
#include "io/output_format.h"
#include "pass_testutil.h"
#include "scratch_dir.h"
#include "srgb_testutil.h"

namespace mcr {
namespace {

using namespace testutil;

struct Read {
  int width = 0, height = 0, channels = 0;
  std::string format;
  OIIO::TypeDesc type;
  std::vector<float> px;  // normalised to [0, 1]
  OIIO::ImageSpec spec;
  float at(int x, int y, int c) const { return px[(std::size_t(y) * width + x) * channels + c]; }
};

// Values as stored: straight (unassociated) alpha, as PNG and TIFF keep it.
Read read(const std::string& path) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) throw std::runtime_error("cannot open " + path + ": " + OIIO::geterror());
  Read r;
  r.spec = in->spec();
  r.width = r.spec.width;
  r.height = r.spec.height;
  r.channels = r.spec.nchannels;
  r.format = in->format_name();
  r.type = r.spec.format;
  r.px.resize(std::size_t(r.width) * r.height * r.channels);
  if (!in->read_image(0, 0, 0, r.channels, OIIO::TypeFloat, r.px.data())) throw std::runtime_error(in->geterror());
  return r;
}

// A ramp of linear values from 0 to 1.2 (the top is clipped by the view) in R, G, B.
Frame ramp_frame(int w, int h) {
  Frame f;
  f.width = w;
  f.height = h;
  f.path = "ramp.exr";
  Image c(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int ch = 0; ch < 3; ++ch) c.at(x, y, ch) = float(1.2 * double(y * w + x) / (w * h - 1) * (1.0 - 0.3 * ch));
  f.passes.push_back(make_pass(Role::Colour, "Combined", std::move(c)));
  return f;
}

TEST(OutputFormat, TheExtensionNamesTheFormat) {
  EXPECT_EQ(output_format("a.exr"), OutputFormat::Exr);
  EXPECT_EQ(output_format("dir.png/o_####.EXR"), OutputFormat::Exr);
  EXPECT_EQ(output_format("x.PNG"), OutputFormat::Png);
  EXPECT_EQ(output_format("x.jpg"), OutputFormat::Jpeg);
  EXPECT_EQ(output_format("x.JPEG"), OutputFormat::Jpeg);
  EXPECT_EQ(output_format("o_%04d.tif"), OutputFormat::Tiff);
  EXPECT_EQ(output_format("x.tiff"), OutputFormat::Tiff);
  for (const char* bad : {"out.xyz", "out", ".exr", "d.exr/out", "out.exr.tmp", "out.bmp", "x.png.bak"}) {
    SCOPED_TRACE(bad);
    const std::string msg = expect_error(Errc::InvalidArgument, [&] { output_format(bad); });
    EXPECT_NE(msg.find(std::string("'") + bad + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find(".exr"), std::string::npos) << msg;
    EXPECT_NE(msg.find(".png"), std::string::npos) << msg;
  }
}

TEST(DisplayOutput, PngIsTheStandardViewOfTheLinearResult) {
  const ScratchDir dir("mcrecon_display");
  const Frame f = ramp_frame(16, 8);
  write_result(dir.path("o.png"), f.image(Role::Colour), f);
  EXPECT_EQ(dir.listing(), std::vector<std::string>{"o.png"});  // no temp left
  const Read r = read(dir.path("o.png"));
  EXPECT_EQ(r.format, "png");
  EXPECT_EQ(r.type, OIIO::TypeUInt8);
  ASSERT_EQ(r.channels, 4);
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(std::lround(r.at(x, y, c) * 255), srgb_code(f.image(Role::Colour).at(x, y, c)))
            << x << "," << y << " channel " << c;
      ASSERT_EQ(r.at(x, y, 3), 1.0f);  // no alpha pass: opaque
    }
}

TEST(DisplayOutput, ExposureBeforeTheViewGammaAfter) {
  const ScratchDir dir("mcrecon_display");
  const Frame f = ramp_frame(16, 8);
  WriteOptions o;
  o.display.exposure = 1.0;
  o.display.gamma = 2.0;
  o.bits = 16;
  write_result(dir.path("o.png"), f.image(Role::Colour), f, o);
  const Read r = read(dir.path("o.png"));
  EXPECT_EQ(r.type, OIIO::TypeUInt16);
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const double v = 2.0 * f.image(Role::Colour).at(x, y, c);
        const double want = std::sqrt(srgb_encode(std::min(v, 1.0)));
        ASSERT_NEAR(r.at(x, y, c), want, 2e-3) << x << "," << y << " channel " << c;
      }
}

TEST(DisplayOutput, AlphaIsStoredStraightAsPngDoes) {
  const ScratchDir dir("mcrecon_display");
  Frame f = ramp_frame(4, 2);
  Image a(4, 2, 1, 0.5f);
  f.passes.push_back(make_pass(Role::Alpha, "Combined.A", std::move(a)));
  const Image premultiplied(4, 2, 3, 0.125f);  // straight 0.25 at alpha 0.5
  write_result(dir.path("o.png"), premultiplied, f);
  const Read r = read(dir.path("o.png"));
  ASSERT_EQ(r.channels, 4);
  EXPECT_NEAR(r.at(1, 1, 3), 0.5, 1.0 / 255);
  EXPECT_EQ(std::lround(r.at(1, 1, 0) * 255), srgb_code(0.25));
}

TEST(DisplayOutput, JpegIsRgbAndTiffSixteenBits) {
  const ScratchDir dir("mcrecon_display");
  const Frame f = ramp_frame(32, 16);
  write_result(dir.path("o.jpg"), f.image(Role::Colour), f);
  write_result(dir.path("o.tif"), f.image(Role::Colour), f);
  const Read j = read(dir.path("o.jpg"));
  EXPECT_EQ(j.format, "jpeg");
  ASSERT_EQ(j.channels, 3);
  const Read t = read(dir.path("o.tif"));
  EXPECT_EQ(t.format, "tiff");
  EXPECT_EQ(t.type, OIIO::TypeUInt16);
  ASSERT_EQ(t.channels, 4);
  double jpeg_err = 0;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const double want = srgb_encode(std::min(double(f.image(Role::Colour).at(x, y, c)), 1.0));
        // OCIO's CPU processor evaluates the sRGB curve to about 1e-4 (a fast pow).
        ASSERT_NEAR(t.at(x, y, c), want, 2e-4) << x << "," << y;
        jpeg_err = std::max(jpeg_err, std::abs(j.at(x, y, c) - want));
      }
  EXPECT_LT(jpeg_err, 12.0 / 255);  // lossy (quality 95, chroma subsampled)
}

TEST(DisplayOutput, TheFilmicViewIsNotTheStandardOne) {
  const ScratchDir dir("mcrecon_display");
  const Frame f = ramp_frame(16, 8);
  WriteOptions filmic;
  filmic.display.view = "Filmic";
  write_result(dir.path("s.png"), f.image(Role::Colour), f);
  write_result(dir.path("f.png"), f.image(Role::Colour), f, filmic);
  const Read s = read(dir.path("s.png")), m = read(dir.path("f.png"));
  int differ = 0;
  for (std::size_t i = 0; i < s.px.size(); ++i) differ += s.px[i] != m.px[i];
  EXPECT_GT(differ, int(s.px.size() / 2));
}

TEST(DisplayOutput, WhatADisplayFormatCannotHoldIsRefused) {
  const ScratchDir dir("mcrecon_display");
  const Frame f = ramp_frame(4, 2);
  WriteOptions keep;
  keep.keep_passes = true;
  expect_error(Errc::InvalidArgument, {"'" + dir.path("o.png") + "'", "PNG", "--keep-passes", ".exr"},
               [&] { check_write(dir.path("o.png"), keep); });
  WriteOptions layers;
  layers.layers.emplace_back("Denoised.Diffuse", &f.image(Role::Colour));
  expect_error(Errc::InvalidArgument, {"TIFF", "--keep-components"},
               [&] { write_result(dir.path("o.tif"), f.image(Role::Colour), f, layers); });
  WriteOptions sixteen;
  sixteen.bits = 16;
  expect_error(Errc::InvalidArgument, {"bit depth 16", "JPEG takes 8"}, [&] { check_write(dir.path("o.jpg"), sixteen); });
  expect_error(Errc::InvalidArgument, {"bit depth", "32-bit float"}, [&] { check_write(dir.path("o.exr"), sixteen); });
  WriteOptions view;
  view.display.view = "Filmc";
  expect_error(Errc::InvalidArgument, {"view 'Filmc'", "Standard, Filmic"}, [&] { check_write(dir.path("o.png"), view); });
  check_write(dir.path("o.exr"), view);  // the view is not read for EXR
  WriteOptions look;
  look.display.look = "Punchy";
  expect_error(Errc::InvalidArgument, {"look 'Punchy'", "Medium High Contrast"}, [&] { check_write(dir.path("o.png"), look); });
  WriteOptions config;
  config.display.config = dir.path("none.ocio");
  expect_error(Errc::FileNotFound, {"none.ocio"}, [&] { check_write(dir.path("o.png"), config); });
  WriteOptions gamma;
  gamma.display.gamma = 0;
  expect_error(Errc::InvalidArgument, {"gamma"}, [&] { check_write(dir.path("o.png"), gamma); });
  expect_error(Errc::InvalidArgument, {"'.bmp'"}, [&] { write_result(dir.path("o.bmp"), f.image(Role::Colour), f); });
  EXPECT_TRUE(dir.listing().empty());
}

}  // namespace
}  // namespace mcr
