// The light-field deep EXR convention: what encode writes, read_frame + decode give back,
// and each malformed file (missing slopes, NaN coordinates, no samples, inconsistent l)
// refused with a message naming the file and the fault.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "expect_error.h"
#include "image/lightfield.h"
#include "io/deep_writer.h"
#include "io/frame_reader.h"

namespace mcr {
namespace {

namespace fs = std::filesystem;
using testutil::expect_error;

// 3 x 2 pixels, l = 2, every value distinct so a swapped channel or pixel shows.
LightField small_field(bool geometry) {
  LightField lf;
  lf.effect = LightFieldEffect::Dof;
  lf.y_range = 1;
  lf.sigma_y = 0.5;
  lf.resize(3, 2, 2, geometry);
  for (std::size_t s = 0; s < lf.samples(); ++s) {
    lf.r[s] = 0.1f * float(s);
    lf.g[s] = 0.2f * float(s) + 1;
    lf.b[s] = 0.3f * float(s) + 2;
    lf.y1[s] = (s % 2 ? 0.5f : -0.5f) + 0.01f * float(s % 4);
    lf.y2[s] = (s % 4 < 2 ? -0.5f : 0.5f) - 0.02f * float(s % 4);
  }
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    lf.smin[p] = -1.5f + float(p);
    lf.smax[p] = 2.5f + float(p);
    lf.e1x[p] = 1, lf.e1y[p] = 0.1f * float(p), lf.e2x[p] = -0.2f, lf.e2y[p] = 1;
    lf.depth[p] = 3 + float(p);
    if (geometry) {
      lf.px[p] = float(p), lf.py[p] = 2 * float(p), lf.pz[p] = -float(p);
      lf.nx[p] = 0, lf.ny[p] = 1, lf.nz[p] = 0;
    }
  }
  return lf;
}

class LightFieldFileTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("mcrecon_lf_" + std::to_string(::getpid()) + "_" + testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& n) const { return (dir_ / n).string(); }
  // Writes d and reads it back as the filters get it.
  LightField round_trip(const DeepSamples& d, std::size_t* repaired = nullptr) {
    const std::string f = path("lf.exr");
    write_deep_samples(d, f);
    const Frame frame = read_frame(f);
    EXPECT_TRUE(frame.deep && is_lightfield(*frame.deep));
    return decode_lightfield(*frame.deep, f, repaired);
  }
  fs::path dir_;
};

TEST_F(LightFieldFileTest, EveryChannelComesBackFromTheFile) {
  for (bool geometry : {false, true}) {
    const LightField a = small_field(geometry);
    const LightField b = round_trip(encode_lightfield(a));
    EXPECT_EQ(b.effect, LightFieldEffect::Dof);
    EXPECT_EQ(b.l, 2);
    EXPECT_EQ(b.width, 3);
    EXPECT_EQ(b.height, 2);
    EXPECT_FLOAT_EQ(b.y_range, 1);
    EXPECT_FLOAT_EQ(b.sigma_y, 0.5);
    EXPECT_EQ(b.has_geometry(), geometry);
    EXPECT_EQ(b.r, a.r);
    EXPECT_EQ(b.g, a.g);
    EXPECT_EQ(b.b, a.b);
    EXPECT_EQ(b.y1, a.y1);
    EXPECT_EQ(b.y2, a.y2);
    EXPECT_EQ(b.smin, a.smin);
    EXPECT_EQ(b.smax, a.smax);
    EXPECT_EQ(b.e1y, a.e1y);
    EXPECT_EQ(b.e2x, a.e2x);
    EXPECT_EQ(b.depth, a.depth);
    EXPECT_EQ(b.py, a.py);
    EXPECT_EQ(b.ny, a.ny);
  }
}

TEST_F(LightFieldFileTest, ANonFiniteValueTakesItsPixelsMean) {
  LightField a = small_field(false);
  a.r[4] = std::numeric_limits<float>::quiet_NaN();  // pixel 1, samples 4..7
  a.g[5] = std::numeric_limits<float>::infinity();
  std::size_t repaired = 0;
  const LightField b = round_trip(encode_lightfield(a), &repaired);
  EXPECT_EQ(repaired, 2u);
  EXPECT_FLOAT_EQ(b.r[4], (a.r[5] + a.r[6] + a.r[7]) / 3);
  EXPECT_FLOAT_EQ(b.g[5], (a.g[4] + a.g[6] + a.g[7]) / 3);
}

TEST_F(LightFieldFileTest, MissingSlopeChannelsAreNamed) {
  DeepSamples d = encode_lightfield(small_field(false));
  const int c = d.channel("lf.smax");
  d.channel_names.erase(d.channel_names.begin() + c);
  d.values.erase(d.values.begin() + c);
  const std::string f = path("noslope.exr");
  write_deep_samples(d, f);
  // Refused when read (the flat colour needs the coordinates), before any filter sees it.
  expect_error(Errc::MissingPass, {f, "lf.smax", "slope bounds"}, [&] { read_frame(f); });
}

TEST_F(LightFieldFileTest, NanCoordinatesAreRefusedWithThePixel) {
  DeepSamples d = encode_lightfield(small_field(false));
  d.values[d.channel("lf.y2")][9] = std::numeric_limits<float>::quiet_NaN();  // pixel 2 = (2, 0), sample 1
  expect_error(Errc::ReadFailed, {"pixel (2, 0)", "sample 1", "lf.y1, lf.y2"}, [&] { round_trip(d); });
  d = encode_lightfield(small_field(false));
  d.values[d.channel("lf.y1")][0] = 7;  // outside [-1, 1]
  expect_error(Errc::ReadFailed, {"pixel (0, 0)", "lf_y_range"}, [&] { round_trip(d); });
  d = encode_lightfield(small_field(false));
  d.values[d.channel("lf.y2")][23] = -1.5f;  // pixel 5 = (2, 1), sample 3
  expect_error(Errc::ReadFailed, {"pixel (2, 1)", "sample 3", "-1.5"}, [&] { round_trip(d); });
}

TEST_F(LightFieldFileTest, PixelsWithoutExactlyLSquaredSamplesAreRefused) {
  // Zero samples in a pixel, then a pixel with one more: both against mcrecon:lf_l = 2.
  DeepSamples d = encode_lightfield(small_field(false));
  DeepSamples none = d;
  for (auto& o : none.offsets) o = 0;
  for (auto& v : none.values) v.clear();
  expect_error(Errc::ReadFailed, {"pixel (0, 0) has 0 samples", "needs exactly 4"}, [&] { round_trip(none); });

  DeepSamples extra = d;  // pixel (1, 1) = index 4 gets a fifth sample
  const std::size_t at = std::size_t(extra.offsets[5]);
  for (auto& v : extra.values) v.insert(v.begin() + long(at), v[at - 1]);
  for (std::size_t p = 5; p < extra.offsets.size(); ++p) ++extra.offsets[p];
  expect_error(Errc::ReadFailed, {"pixel (1, 1) has 5 samples"}, [&] { round_trip(extra); });

  DeepSamples bad_l = d;
  bad_l.attributes["mcrecon:lf_l"] = "0";
  expect_error(Errc::ReadFailed, {"mcrecon:lf_l", "'0'"}, [&] { round_trip(bad_l); });
}

TEST_F(LightFieldFileTest, BoundsAndAttributesAreChecked) {
  DeepSamples d = encode_lightfield(small_field(false));
  d.attributes.erase("mcrecon:lf_sigma_y");
  expect_error(Errc::MissingPass, {"mcrecon:lf_sigma_y"}, [&] { round_trip(d); });
  d = encode_lightfield(small_field(false));
  d.attributes["mcrecon:lightfield"] = "motion";
  expect_error(Errc::ReadFailed, {"'motion'", "soft_shadows, dof, gi"}, [&] { round_trip(d); });
  d = encode_lightfield(small_field(false));
  for (int k = 0; k < 4; ++k) d.values[d.channel("lf.smin")][k] = 9;  // above smax 2.5 in pixel 0
  expect_error(Errc::ReadFailed, {"pixel (0, 0)", "lf.smin = 9"}, [&] { round_trip(d); });
  d = encode_lightfield(small_field(false));
  for (int k = 0; k < 4; ++k) d.values[d.channel("lf.e1x")][4 + k] = std::numeric_limits<float>::infinity();
  expect_error(Errc::ReadFailed, {"pixel (1, 0)", "lf.e1x"}, [&] { round_trip(d); });
}

}  // namespace
}  // namespace mcr

namespace mcr {
namespace {

// The flat colour of a light field is its unfiltered estimate: the samples weighted by the
// Gaussian light/aperture (a plain mean for gi, whose samples carry their weights).
TEST_F(LightFieldFileTest, TheFlatColourIsTheWeightedSampleMean) {
  for (LightFieldEffect e : {LightFieldEffect::Dof, LightFieldEffect::Gi}) {
    LightField a = small_field(false);
    a.effect = e;
    const std::string f = path("flat.exr");
    write_deep_samples(encode_lightfield(a), f);
    const Frame frame = read_frame(f);
    const Image& c = frame.image(Role::Colour);
    for (int p = 0; p < 6; ++p) {
      double sum = 0, wsum = 0;
      for (int k = 0; k < 4; ++k) {
        const int s = p * 4 + k;
        const double w = e == LightFieldEffect::Gi ? 1.0
                                                   : std::exp(-0.5 * (a.y1[s] / 0.5) * (a.y1[s] / 0.5)) *
                                                         std::exp(-0.5 * (a.y2[s] / 0.5) * (a.y2[s] / 0.5));
        sum += w * a.g[s], wsum += w;
      }
      EXPECT_NEAR(c.at(p % 3, p / 3, 1), sum / wsum, 1e-5) << effect_name(e) << " pixel " << p;
    }
  }
}

}  // namespace
}  // namespace mcr
