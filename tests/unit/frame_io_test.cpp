// Reading frames (layers, roles, overrides, deep files), writing results, output
// path checks and sequence helpers, on EXRs written here with OpenImageIO.
#include <OpenImageIO/deepdata.h>
#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "blender_channels_testutil.h"
#include "deep_file_testutil.h"
#include "expect_error.h"
#include "io/atomic_write.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "io/sequence.h"
#include "util/error.h"

namespace mcr {
namespace {

namespace fs = std::filesystem;
using Names = std::vector<std::string>;
using testutil::blender_layer;
using testutil::contains;
using testutil::expect_error;

// A fresh directory per test, removed afterwards.
class FrameIoTest : public testing::Test {
 protected:
  void SetUp() override {
    const auto* info = testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("mcrecon_frame_io_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path dir_;
};

// Value written to channel c of pixel (x,y): distinct per channel and pixel.
float value_of(int x, int y, int c) { return float(c) * 100.0f + float(y) + float(x) * 0.01f; }

void write_exr(const std::string& path, int w, int h, const Names& channels,
               const std::function<float(int, int, int)>& fn = value_of) {
  OIIO::ImageSpec spec(w, h, int(channels.size()), OIIO::TypeFloat);
  spec.channelnames = channels;
  spec.alpha_channel = -1;
  for (std::size_t i = 0; i < channels.size(); ++i)
    if (channels[i] == "A") spec.alpha_channel = int(i);
  std::vector<float> px(std::size_t(w) * h * channels.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < int(channels.size()); ++c)
        px[(std::size_t(y) * w + x) * channels.size() + c] = fn(x, y, c);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeFloat, px.data())) << out->geterror();
  out->close();
}

// Every channel of a file by name.
std::map<std::string, std::vector<float>> read_all(const std::string& path, int* w = nullptr, int* h = nullptr) {
  auto in = OIIO::ImageInput::open(path);
  EXPECT_TRUE(in) << OIIO::geterror();
  std::map<std::string, std::vector<float>> out;
  if (!in) return out;
  const OIIO::ImageSpec spec = in->spec();
  std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
  EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, px.data()));
  for (int c = 0; c < spec.nchannels; ++c) {
    auto& v = out[spec.channelnames[std::size_t(c)]];
    for (std::size_t i = 0; i < std::size_t(spec.width) * spec.height; ++i) v.push_back(px[i * spec.nchannels + c]);
  }
  if (w) *w = spec.width;
  if (h) *h = spec.height;
  return out;
}

Names concat(std::initializer_list<Names> lists) {
  Names out;
  for (const Names& l : lists) out.insert(out.end(), l.begin(), l.end());
  return out;
}

// The value a channel named `name` was written with, in a file written from `channels`.
float written(const Names& channels, const std::string& name, int x, int y) {
  const auto it = std::find(channels.begin(), channels.end(), name);
  EXPECT_NE(it, channels.end()) << name;
  return value_of(x, y, int(it - channels.begin()));
}

// ---------------------------------------------------------------- reading

TEST_F(FrameIoTest, BlenderMultilayerPicksTheViewLayerOverComposite) {
  const Names ch = concat({{"Composite.Combined.R", "Composite.Combined.G", "Composite.Combined.B",
                            "Composite.Combined.A"},
                           blender_layer("ViewLayer")});
  write_exr(path("ml.exr"), 6, 4, ch);
  const Frame f = read_frame(path("ml.exr"));
  EXPECT_EQ(f.width, 6);
  EXPECT_EQ(f.height, 4);
  EXPECT_EQ(f.layer, "ViewLayer");
  EXPECT_NE(std::find(f.layers.begin(), f.layers.end(), "Composite"), f.layers.end());
  const Pass& c = f.get(Role::Colour);
  EXPECT_EQ(c.channels, (Names{"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B"}));
  ASSERT_EQ(c.image.channels(), 3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) {
      EXPECT_EQ(c.image.at(x, y, 0), written(ch, "ViewLayer.Combined.R", x, y));
      EXPECT_EQ(c.image.at(x, y, 2), written(ch, "ViewLayer.Combined.B", x, y));
      EXPECT_EQ(f.image(Role::Alpha).at(x, y, 0), written(ch, "ViewLayer.Combined.A", x, y));
      EXPECT_EQ(f.image(Role::Motion).at(x, y, 3), written(ch, "ViewLayer.Vector.W", x, y));
    }
  EXPECT_EQ(f.get(Role::Albedo).name, "ViewLayer.Denoising Albedo");
  EXPECT_EQ(f.get(Role::Position).channels,
            (Names{"ViewLayer.Position.X", "ViewLayer.Position.Y", "ViewLayer.Position.Z"}));
  EXPECT_EQ(f.get(Role::Depth).name, "ViewLayer.Depth");
  EXPECT_EQ(f.get(Role::Motion).image.channels(), 4);
  EXPECT_FALSE(f.has(Role::Variance));
  EXPECT_FALSE(f.deep);
  for (const Pass& p : f.passes) EXPECT_EQ(p.source, path("ml.exr"));
}

TEST_F(FrameIoTest, PreferGeometryGivesWorldNormalPreferFeatureGivesDenoisingNormal) {
  const Names ch = blender_layer("RenderLayer");
  write_exr(path("ml.exr"), 3, 3, ch);
  const Frame f = read_frame(path("ml.exr"));
  const Pass& feature = f.get(Role::Normal, Prefer::Feature);
  const Pass& geometry = f.get(Role::Normal, Prefer::Geometry);
  EXPECT_EQ(feature.name, "RenderLayer.Denoising Normal");
  EXPECT_EQ(feature.space, Space::Camera);
  EXPECT_EQ(geometry.name, "RenderLayer.Normal");
  EXPECT_EQ(geometry.space, Space::World);
  EXPECT_EQ(geometry.image.at(1, 2, 1), written(ch, "RenderLayer.Normal.Y", 1, 2));
  EXPECT_EQ(feature.image.at(1, 2, 1), written(ch, "RenderLayer.Denoising Normal.Y", 1, 2));
}

TEST_F(FrameIoTest, LayerOptionChoosesASecondViewLayer) {
  const Names ch = concat({blender_layer("ViewLayer"),
                           {"Other.Combined.R", "Other.Combined.G", "Other.Combined.B", "Other.Normal.X",
                            "Other.Normal.Y", "Other.Normal.Z"}});
  write_exr(path("two.exr"), 4, 3, ch);
  ReadOptions ro;
  ro.layer = "Other";
  const Frame f = read_frame(path("two.exr"), ro);
  EXPECT_EQ(f.layer, "Other");
  EXPECT_EQ(f.get(Role::Colour).name, "Other.Combined");
  EXPECT_EQ(f.image(Role::Colour).at(3, 2, 1), written(ch, "Other.Combined.G", 3, 2));
  EXPECT_EQ(f.get(Role::Normal).name, "Other.Normal");
  EXPECT_FALSE(f.has(Role::Albedo));  // nothing leaks in from ViewLayer
  EXPECT_FALSE(f.has(Role::Alpha));

  ro.layer = "ViewLayer";
  EXPECT_EQ(read_frame(path("two.exr"), ro).get(Role::Colour).name, "ViewLayer.Combined");
  // Without --layer: one of the view layers (EXR sorts channel names, so "first" is by name),
  // with its own colour.
  const Frame d = read_frame(path("two.exr"));
  EXPECT_TRUE(d.layer == "Other" || d.layer == "ViewLayer") << d.layer;
  EXPECT_EQ(d.get(Role::Colour).name, d.layer + ".Combined");

  ro.layer = "Nope";
  const std::string msg = expect_error(Errc::MissingPass, [&] { read_frame(path("two.exr"), ro); });
  EXPECT_TRUE(contains(msg, "'Nope'")) << msg;
  EXPECT_TRUE(contains(msg, "two.exr")) << msg;
  EXPECT_TRUE(contains(msg, "Other")) << msg;
  EXPECT_TRUE(contains(msg, "ViewLayer")) << msg;
}

TEST_F(FrameIoTest, PlainRgbazFile) {
  const Names ch = {"R", "G", "B", "A", "Z"};
  write_exr(path("plain.exr"), 5, 2, ch);
  const Frame f = read_frame(path("plain.exr"));
  EXPECT_EQ(f.layer, "");
  EXPECT_EQ(f.get(Role::Colour).channels, (Names{"R", "G", "B"}));
  EXPECT_EQ(f.get(Role::Alpha).channels, (Names{"A"}));
  EXPECT_EQ(f.get(Role::Depth).channels, (Names{"Z"}));
  EXPECT_EQ(f.image(Role::Depth).at(4, 1, 0), written(ch, "Z", 4, 1));
  EXPECT_EQ(f.image(Role::Colour).at(4, 1, 1), written(ch, "G", 4, 1));
}

// A one-part file with every channel half is read as half and converted per pass (the wide
// render's fast path): the same values as the float path gives, the file's own halves, for
// passes and for the channels --keep-passes carries; a file with one float channel among
// halves takes the float path, with the same result.
TEST_F(FrameIoTest, AllHalfFilesReadTheirHalvesExactly) {
  const Names ch = {"R", "G", "B", "A", "N.X", "N.Y", "N.Z", "extra.V"};
  const int w = 7, h = 5;
  auto fn = [](int x, int y, int c) { return value_of(x, y, c) * 1.37f + 0.001f; };  // not exact in half
  for (const bool mixed : {false, true}) {
    OIIO::ImageSpec spec(w, h, int(ch.size()), OIIO::TypeHalf);
    spec.channelnames = ch;
    spec.alpha_channel = 3;
    if (mixed) {
      spec.channelformats.assign(ch.size(), OIIO::TypeHalf);
      spec.channelformats.back() = OIIO::TypeFloat;
    }
    std::vector<float> px(std::size_t(w) * h * ch.size());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < int(ch.size()); ++c) px[(std::size_t(y) * w + x) * ch.size() + std::size_t(c)] = fn(x, y, c);
    const std::string file = path(mixed ? "mixed.exr" : "half.exr");
    auto out = OIIO::ImageOutput::create(file);
    ASSERT_TRUE(out && out->open(file, spec)) << OIIO::geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, px.data())) << out->geterror();
    out->close();
    ReadOptions keep;
    keep.keep_extra = true;
    const Frame f = read_frame(file, keep);
    const std::map<std::string, std::vector<float>> all = read_all(file);  // OIIO's own float conversion
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = std::size_t(y) * w + std::size_t(x);
        EXPECT_EQ(f.image(Role::Colour).at(x, y, 1), all.at("G")[i]) << mixed;
        EXPECT_EQ(f.image(Role::Colour).at(x, y, 1), float(Imath::half(fn(x, y, 1)))) << mixed;
        EXPECT_NE(f.image(Role::Colour).at(x, y, 1), fn(x, y, 1)) << "the test's values must not be exact in half";
        EXPECT_EQ(f.image(Role::Normal).at(x, y, 2), all.at("N.Z")[i]) << mixed;
        ASSERT_EQ(f.extra.size(), 1u) << mixed;
        EXPECT_EQ(f.extra[0].image.at(x, y, 0), all.at("extra.V")[i]) << mixed;
      }
  }
}

TEST_F(FrameIoTest, PlainFileWithShortFeatureNames) {
  const Names ch = {"R", "G", "B", "N.X", "N.Y", "N.Z", "albedo.R", "albedo.G", "albedo.B", "P.X", "P.Y", "P.Z"};
  write_exr(path("short.exr"), 3, 2, ch);
  const Frame f = read_frame(path("short.exr"));
  EXPECT_EQ(f.get(Role::Normal).channels, (Names{"N.X", "N.Y", "N.Z"}));
  EXPECT_EQ(f.get(Role::Albedo).channels, (Names{"albedo.R", "albedo.G", "albedo.B"}));
  EXPECT_EQ(f.get(Role::Position).channels, (Names{"P.X", "P.Y", "P.Z"}));
  EXPECT_EQ(f.image(Role::Position).at(2, 1, 2), written(ch, "P.Z", 2, 1));
}

TEST_F(FrameIoTest, OverrideFromALooseFile) {
  const Names ch = blender_layer("ViewLayer");
  write_exr(path("ml.exr"), 4, 3, ch);
  write_exr(path("normals.exr"), 4, 3, {"R", "G", "B"}, [](int x, int y, int c) { return -value_of(x, y, c); });
  ReadOptions ro;
  ro.overrides.push_back(parse_pass_override("normal=" + path("normals.exr")));
  const Frame f = read_frame(path("ml.exr"), ro);
  const Pass& n = f.get(Role::Normal, Prefer::Feature);
  EXPECT_EQ(n.source, path("normals.exr"));
  EXPECT_EQ(&f.get(Role::Normal, Prefer::Geometry), &n);  // the override replaces every candidate
  EXPECT_EQ(n.image.at(3, 2, 0), -value_of(3, 2, 0));
  EXPECT_EQ(n.image.at(3, 2, 2), -value_of(3, 2, 2));
  EXPECT_EQ(f.get(Role::Colour).source, path("ml.exr"));
}

TEST_F(FrameIoTest, OverrideFromAChannelGroup) {
  const Names ch = blender_layer("ViewLayer");
  write_exr(path("ml.exr"), 4, 3, ch);
  for (const std::string group : {"ViewLayer.Normal", "Normal"}) {
    ReadOptions ro;
    ro.overrides.push_back(parse_pass_override("normal=" + group));
    const Frame f = read_frame(path("ml.exr"), ro);
    EXPECT_EQ(f.get(Role::Normal, Prefer::Feature).name, "ViewLayer.Normal") << group;
    EXPECT_EQ(f.image(Role::Normal).at(1, 1, 0), written(ch, "ViewLayer.Normal.X", 1, 1));
  }
  ReadOptions ro;
  ro.overrides.push_back(parse_pass_override("colour=ViewLayer.Denoising Albedo"));
  const Frame f = read_frame(path("ml.exr"), ro);
  EXPECT_EQ(f.get(Role::Colour).name, "ViewLayer.Denoising Albedo");
}

TEST_F(FrameIoTest, OverrideErrorsNameTheSpec) {
  const Names ch = blender_layer("ViewLayer");
  write_exr(path("ml.exr"), 4, 3, ch);
  write_exr(path("small.exr"), 2, 2, {"R", "G", "B"});

  std::string msg = expect_error(Errc::InvalidArgument, [] { parse_pass_override("nosuchrole=x"); });
  EXPECT_TRUE(contains(msg, "nosuchrole")) << msg;
  expect_error(Errc::InvalidArgument, [] { parse_pass_override("normal"); });
  expect_error(Errc::InvalidArgument, [] { parse_pass_override("normal="); });
  expect_error(Errc::InvalidArgument, [] { parse_pass_override("=x.exr"); });
  EXPECT_EQ(parse_pass_override("Color=a=b.exr").role, Role::Colour);
  EXPECT_EQ(parse_pass_override("Color=a=b.exr").value, "a=b.exr");

  ReadOptions ro;
  ro.overrides.push_back(parse_pass_override("normal=nosuchgroup"));
  msg = expect_error(Errc::MissingPass, [&] { read_frame(path("ml.exr"), ro); });
  EXPECT_TRUE(contains(msg, "nosuchgroup")) << msg;

  ro.overrides = {parse_pass_override("normal=ViewLayer.Depth")};  // one channel for a 3-channel role
  msg = expect_error(Errc::MissingPass, [&] { read_frame(path("ml.exr"), ro); });
  EXPECT_TRUE(contains(msg, "ViewLayer.Depth")) << msg;

  ro.overrides = {parse_pass_override("normal=" + path("small.exr"))};
  msg = expect_error(Errc::SizeMismatch, [&] { read_frame(path("ml.exr"), ro); });
  EXPECT_TRUE(contains(msg, "small.exr")) << msg;
  EXPECT_TRUE(contains(msg, "normal")) << msg;
}

TEST_F(FrameIoTest, ReadErrorsCarryTheirCodeAndTheFile) {
  std::string msg = expect_error(Errc::FileNotFound, [&] { read_frame(path("missing.exr")); });
  EXPECT_TRUE(contains(msg, "missing.exr")) << msg;

  std::ofstream(path("text.exr")) << "not an image\n";
  msg = expect_error(Errc::NotAnImage, [&] { read_frame(path("text.exr")); });
  EXPECT_TRUE(contains(msg, "text.exr")) << msg;

  expect_error(Errc::NotAnImage, [&] { read_frame(dir_.string()); });

  write_exr(path("nocolour.exr"), 4, 4, {"ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z"});
  msg = expect_error(Errc::MissingPass, [&] { read_frame(path("nocolour.exr")); });
  EXPECT_TRUE(contains(msg, "nocolour.exr")) << msg;
  EXPECT_TRUE(contains(msg, "colour")) << msg;
  ReadOptions lenient;
  lenient.require_colour = false;
  EXPECT_TRUE(read_frame(path("nocolour.exr"), lenient).has(Role::Normal));
}

TEST_F(FrameIoTest, TruncatedFilesAreReadErrorsNotCrashes) {
  write_exr(path("full.exr"), 64, 48, blender_layer("ViewLayer"));
  std::ifstream in(path("full.exr"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  for (std::size_t cut : {std::size_t(0), std::size_t(100), bytes.size() / 2, bytes.size() - 1}) {
    std::ofstream(path("cut.exr"), std::ios::binary).write(bytes.data(), std::streamsize(cut));
    try {
      read_frame(path("cut.exr"));
      ADD_FAILURE() << "a file cut to " << cut << " bytes was read";
    } catch (const Error& e) {
      EXPECT_TRUE(e.code() == Errc::ReadFailed || e.code() == Errc::NotAnImage)
          << cut << ": " << errc_name(e.code()) << ": " << e.what();
      EXPECT_TRUE(contains(e.what(), "cut.exr")) << e.what();
    }
  }
}

TEST_F(FrameIoTest, KeepExtraCollectsChannelsWithoutRole) {
  const Names ch = concat({blender_layer("ViewLayer"), {"ViewLayer.AO.R", "ViewLayer.AO.G", "ViewLayer.AO.B",
                                                        "ViewLayer.CryptoObject00.R"}});
  write_exr(path("ml.exr"), 3, 2, ch);
  ReadOptions ro;
  ro.keep_extra = true;
  const Frame f = read_frame(path("ml.exr"), ro);
  Names extra;
  for (const Pass& p : f.extra) extra.push_back(p.name);
  std::sort(extra.begin(), extra.end());
  EXPECT_EQ(extra, (Names{"ViewLayer.AO", "ViewLayer.CryptoObject00"}));
  EXPECT_TRUE(read_frame(path("ml.exr")).extra.empty());

  // Candidates an override replaced are input channels like any other: extra, not dropped.
  ro.overrides.push_back(parse_pass_override("normal=ViewLayer.Normal"));
  const Frame o = read_frame(path("ml.exr"), ro);
  extra.clear();
  for (const Pass& p : o.extra) extra.push_back(p.name);
  std::sort(extra.begin(), extra.end());
  EXPECT_EQ(extra, (Names{"ViewLayer.AO", "ViewLayer.CryptoObject00", "ViewLayer.Denoising Normal"}));
}

// ---------------------------------------------------------------- writing

TEST_F(FrameIoTest, WriteResultThenReadFrameRoundTrips) {
  const Names ch = blender_layer("ViewLayer");
  write_exr(path("in.exr"), 5, 4, ch);
  const Frame in = read_frame(path("in.exr"));
  Image result(5, 4, 3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x)
      for (int c = 0; c < 3; ++c) result.at(x, y, c) = 0.5f + float(x * 7 + y * 3 + c);
  WriteOptions wo;
  wo.attributes.emplace_back("mcreconFilter", "box");
  write_result(path("out.exr"), result, in, wo);
  EXPECT_EQ(listing(), (Names{"in.exr", "out.exr"}));  // no temp file left

  auto all = read_all(path("out.exr"));
  Names names;
  for (const auto& kv : all) names.push_back(kv.first);
  EXPECT_EQ(names, (Names{"A", "B", "G", "R"}));
  const Frame back = read_frame(path("out.exr"));
  EXPECT_EQ(back.image(Role::Colour).storage(), result.storage());
  EXPECT_EQ(back.image(Role::Alpha).storage(), in.image(Role::Alpha).storage());

  auto spec_in = OIIO::ImageInput::open(path("out.exr"));
  ASSERT_TRUE(spec_in);
  EXPECT_EQ(spec_in->spec().format, OIIO::TypeFloat);
  EXPECT_EQ(spec_in->spec().get_string_attribute("mcreconFilter"), "box");
}

// One OpenEXR file with a part per spec; part k's channel c of pixel (x,y) holds
// value_of(x, y, 10 k + c) (distinct across parts).
void write_parts(const std::string& path, const std::vector<OIIO::ImageSpec>& specs) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  ASSERT_TRUE(out->open(path, int(specs.size()), specs.data())) << out->geterror();
  for (std::size_t k = 0; k < specs.size(); ++k) {
    const OIIO::ImageSpec& s = specs[k];
    if (k > 0) ASSERT_TRUE(out->open(path, s, OIIO::ImageOutput::AppendSubimage)) << out->geterror();
    std::vector<float> px(std::size_t(s.width) * s.height * s.nchannels);
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x)
        for (int c = 0; c < s.nchannels; ++c)
          px[(std::size_t(y) * s.width + x) * s.nchannels + c] = value_of(x, y, int(k) * 10 + c);
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, px.data())) << out->geterror();
  }
  out->close();
}

OIIO::ImageSpec part_spec(const std::string& name, int w, int h, const Names& channels) {
  OIIO::ImageSpec s(w, h, int(channels.size()), OIIO::TypeFloat);
  s.channelnames = channels;
  s.alpha_channel = -1;
  s.attribute("name", name);
  return s;
}

TEST_F(FrameIoTest, MultiPartFileJoinsEveryPartPrefixingRepeatedNames) {
  // Beauty, a normal part reusing R,G,B (the usual multi-part layout) and a depth part.
  write_parts(path("parts.exr"), {part_spec("rgba", 4, 3, {"R", "G", "B", "A"}), part_spec("normal", 4, 3, {"R", "G", "B"}),
                                  part_spec("depth", 4, 3, {"Z"})});
  const Frame f = read_frame(path("parts.exr"));
  const Pass& n = f.get(Role::Normal);
  EXPECT_EQ(n.channels, (Names{"normal.R", "normal.G", "normal.B"}));
  const Pass& z = f.get(Role::Depth);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(f.image(Role::Colour).at(x, y, c), value_of(x, y, c));
        EXPECT_EQ(n.image.at(x, y, c), value_of(x, y, 10 + c));
      }
      EXPECT_EQ(z.image.at(x, y, 0), value_of(x, y, 20));
    }
}

TEST_F(FrameIoTest, MultiPartFileWithDifferentDataWindowsIsASizeMismatchNamingThePart) {
  OIIO::ImageSpec shifted = part_spec("normal", 4, 3, {"R", "G", "B"});
  shifted.x = 2;
  write_parts(path("parts.exr"), {part_spec("rgba", 4, 3, {"R", "G", "B", "A"}), shifted});
  try {
    read_frame(path("parts.exr"));
    FAIL() << "expected a SizeMismatch";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::SizeMismatch);
    EXPECT_NE(std::string(e.what()).find("part 1 'normal'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("parts.exr"), std::string::npos) << e.what();
  }
}

TEST_F(FrameIoTest, DataWindowAndDisplayWindowSurviveARoundTrip) {
  // A 5x4 crop at (7, 3) of a 32x24 frame (Blender's "crop to render region", overscan).
  OIIO::ImageSpec spec = part_spec("", 5, 4, {"R", "G", "B", "A"});
  spec.x = 7;
  spec.y = 3;
  spec.full_x = 0;
  spec.full_y = 0;
  spec.full_width = 32;
  spec.full_height = 24;
  write_parts(path("crop.exr"), {spec});
  const Frame in = read_frame(path("crop.exr"));
  EXPECT_EQ(in.width, 5);
  EXPECT_EQ(in.window.x, 7);
  EXPECT_EQ(in.window.y, 3);
  EXPECT_EQ(in.image(Role::Colour).at(0, 0, 0), value_of(0, 0, 0));  // pixels start at the data window
  write_result(path("out.exr"), in.image(Role::Colour), in);
  auto back = OIIO::ImageInput::open(path("out.exr"));
  ASSERT_TRUE(back);
  const OIIO::ImageSpec& s = back->spec();
  EXPECT_EQ((std::vector<int>{s.x, s.y, s.width, s.height}), (std::vector<int>{7, 3, 5, 4}));
  EXPECT_EQ((std::vector<int>{s.full_x, s.full_y, s.full_width, s.full_height}), (std::vector<int>{0, 0, 32, 24}));
  EXPECT_EQ(read_frame(path("out.exr")).image(Role::Colour).storage(), in.image(Role::Colour).storage());
}

TEST_F(FrameIoTest, WriteResultWithoutAlphaWritesOne) {
  write_exr(path("rgb.exr"), 3, 3, {"R", "G", "B"});
  const Frame in = read_frame(path("rgb.exr"));
  write_result(path("out.exr"), in.image(Role::Colour), in);
  auto all = read_all(path("out.exr"));
  ASSERT_EQ(all["A"].size(), 9u);
  for (float a : all["A"]) EXPECT_EQ(a, 1.0f);
}

TEST_F(FrameIoTest, KeptPassesSurviveARoundTrip) {
  const Names ch = concat({blender_layer("ViewLayer"), {"ViewLayer.Emit.R", "ViewLayer.Emit.G", "ViewLayer.Emit.B"}});
  write_exr(path("in.exr"), 4, 3, ch);
  write_exr(path("loose_albedo.exr"), 4, 3, {"R", "G", "B"}, [](int x, int y, int c) { return 0.25f * (x + y + c); });
  ReadOptions ro;
  ro.keep_extra = true;
  ro.overrides.push_back(parse_pass_override("albedo=" + path("loose_albedo.exr")));
  const Frame in = read_frame(path("in.exr"), ro);
  WriteOptions wo;
  wo.keep_passes = true;
  write_result(path("out.exr"), in.image(Role::Colour), in, wo);

  auto all = read_all(path("out.exr"));
  for (const std::string& n : ch) {
    if (n.rfind("ViewLayer.Combined.", 0) == 0) {
      EXPECT_EQ(all.count(n), 0u) << n << " is written as R,G,B,A";
      continue;
    }
    // Every other channel, the Denoising Albedo the loose file replaced included.
    ASSERT_EQ(all.count(n), 1u) << n << " not carried";
    EXPECT_EQ(all[n][std::size_t(2 * 4 + 3)], written(ch, n, 3, 2)) << n;
  }
  ASSERT_EQ(all.count("albedo.X"), 1u);  // a loose pass is named after its role
  EXPECT_EQ(all["albedo.X"][std::size_t(1 * 4 + 2)], 0.25f * 3);

  // Read back, the output gives the same roles from the same channel names.
  const Frame back = read_frame(path("out.exr"));
  EXPECT_EQ(back.get(Role::Colour).channels, (Names{"R", "G", "B"}));
  EXPECT_EQ(back.get(Role::Normal, Prefer::Geometry).name, "ViewLayer.Normal");
  EXPECT_EQ(back.get(Role::Normal, Prefer::Feature).name, "ViewLayer.Denoising Normal");
  EXPECT_EQ(back.get(Role::Depth).name, "ViewLayer.Depth");
  EXPECT_EQ(back.get(Role::Position).name, "ViewLayer.Position");
  EXPECT_EQ(back.get(Role::Motion).name, "ViewLayer.Vector");
  EXPECT_EQ(back.image(Role::Motion).storage(), in.image(Role::Motion).storage());
  EXPECT_EQ(back.image(Role::Colour).storage(), in.image(Role::Colour).storage());
}

TEST_F(FrameIoTest, WriteFailureLeavesNoFile) {
  write_exr(path("in.exr"), 3, 3, {"R", "G", "B"});
  const Frame in = read_frame(path("in.exr"));
  expect_error(Errc::WriteFailed, [&] { write_result(path("nodir/out.exr"), in.image(Role::Colour), in); });
  expect_error(Errc::WriteFailed, [&] { write_result(path("in.exr/out.exr"), in.image(Role::Colour), in); });
  EXPECT_EQ(listing(), (Names{"in.exr"}));
}

TEST_F(FrameIoTest, StaleTempFilesOfKilledRunsAreRemoved) {
  write_exr(path("in.exr"), 3, 3, {"R", "G", "B"});
  std::ofstream(path(".out.exr.mcrecon-tmp.999999")) << "partial";
  std::ofstream(path(".other.exr.mcrecon-tmp.1")) << "someone else's";
  const Frame in = read_frame(path("in.exr"));
  write_result(path("out.exr"), in.image(Role::Colour), in);
  EXPECT_EQ(listing(), (Names{".other.exr.mcrecon-tmp.1", "in.exr", "out.exr"}));
  EXPECT_EQ(temp_prefix_for(path("out.exr")), ".out.exr.mcrecon-tmp.");
}

TEST_F(FrameIoTest, OutputPathChecks) {
  write_exr(path("in.exr"), 2, 2, {"R", "G", "B"});
  fs::create_directories(dir_ / "sub");
  const std::vector<std::string> inputs = {path("in.exr")};
  check_output_path(path("out.exr"), inputs);  // fine

  std::string msg = expect_error(Errc::InvalidArgument, [&] { check_output_path(path("in.exr"), inputs); });
  EXPECT_TRUE(contains(msg, "in.exr")) << msg;
  expect_error(Errc::InvalidArgument, [&] { check_output_path(path("sub/../in.exr"), inputs); });
  expect_error(Errc::InvalidArgument, [&] { check_output_path(path("./in.exr"), inputs); });
  fs::create_symlink(path("in.exr"), path("link.exr"));
  expect_error(Errc::InvalidArgument, [&] { check_output_path(path("link.exr"), inputs); });
  expect_error(Errc::InvalidArgument, [&] { check_output_path(path("in.exr"), {path("link.exr")}); });
  fs::create_hard_link(path("in.exr"), path("hard.exr"));
  expect_error(Errc::InvalidArgument, [&] { check_output_path(path("hard.exr"), inputs); });

  msg = expect_error(Errc::WriteFailed, [&] { check_output_path(path("nodir/out.exr"), inputs); });
  EXPECT_TRUE(contains(msg, "nodir")) << msg;
  expect_error(Errc::WriteFailed, [&] { check_output_path(path("in.exr/out.exr"), inputs); });
  expect_error(Errc::WriteFailed, [&] { check_output_path(path("sub"), inputs); });
  expect_error(Errc::InvalidArgument, [&] { check_output_path("", inputs); });

  // The batch form a sequence uses: every output against every input.
  const std::vector<std::string> frames = {path("f1.exr"), path("in.exr"), path("f3.exr")};
  check_output_paths({path("o1.exr"), path("o2.exr"), path("o3.exr")}, frames);
  msg = expect_error(Errc::InvalidArgument,
                     [&] { check_output_paths({path("o1.exr"), path("sub/../hard.exr")}, frames); });
  EXPECT_TRUE(contains(msg, "hard.exr")) << msg;
  expect_error(Errc::InvalidArgument, [&] { check_output_paths({path("o1.exr"), path("link.exr")}, frames); });
  expect_error(Errc::WriteFailed, [&] { check_output_paths({path("o1.exr"), path("nodir/o2.exr")}, frames); });
}

// ---------------------------------------------------------------- deep

TEST_F(FrameIoTest, DeepFileKeepsEverySampleAndFlattensTheColour) {
  const int w = 4, h = 3;
  OIIO::ImageSpec spec(w, h, 7, OIIO::TypeFloat);
  spec.channelnames = {"R", "G", "B", "A", "Z", "dx", "dy"};
  spec.alpha_channel = 3;
  spec.z_channel = 4;
  spec.deep = true;
  spec.attribute("compression", "zips");
  OIIO::DeepData dd(spec);
  // Pixel p has p % 4 samples (0 to 3), sorted front to back, premultiplied colour.
  auto sample_value = [](int p, int s, int c) {
    switch (c) {
      case 3: return 0.2f + 0.1f * float(s);                           // A
      case 4: return 1.0f + float(s) + 0.01f * float(p);               // Z, increasing
      case 5: return float(p) - 0.5f * float(s);                       // dx
      case 6: return -float(p);                                        // dy
      default: return (0.2f + 0.1f * float(s)) * (0.1f * float(c + 1) + 0.01f * float(p));  // premultiplied RGB
    }
  };
  for (int p = 0; p < w * h; ++p) dd.set_samples(p, p % 4);
  for (int p = 0; p < w * h; ++p)
    for (int s = 0; s < p % 4; ++s)
      for (int c = 0; c < 7; ++c) dd.set_deep_value(p, c, s, sample_value(p, s, c));
  {
    auto out = OIIO::ImageOutput::create(path("deep.exr"));
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path("deep.exr"), spec)) << out->geterror();
    ASSERT_TRUE(out->write_deep_image(dd)) << out->geterror();
    out->close();
  }

  const Frame f = read_frame(path("deep.exr"));
  ASSERT_TRUE(f.deep);
  const DeepSamples& d = *f.deep;
  EXPECT_EQ(d.width, w);
  EXPECT_EQ(d.height, h);
  std::uint64_t total = 0;
  for (int p = 0; p < w * h; ++p) total += std::uint64_t(p % 4);
  EXPECT_EQ(d.total_samples(), total);
  const Names names = {"R", "G", "B", "A", "Z", "dx", "dy"};
  for (int c = 0; c < 7; ++c) ASSERT_GE(d.channel(names[std::size_t(c)]), 0) << names[std::size_t(c)];
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int p = y * w + x;
      ASSERT_EQ(d.samples(x, y), std::uint32_t(p % 4)) << x << "," << y;
      for (int s = 0; s < p % 4; ++s)
        for (int c = 0; c < 7; ++c)  // channels matched by name: a reader may reorder them
          EXPECT_EQ(d.values[std::size_t(d.channel(names[std::size_t(c)]))][d.first(x, y) + std::uint64_t(s)],
                    sample_value(p, s, c))
              << names[std::size_t(c)] << " pixel " << x << "," << y << " sample " << s;
    }

  // The flat colour is the front-to-back "over" composite of the samples.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int p = y * w + x;
      double rgb[3] = {0, 0, 0}, alpha = 0, through = 1;
      for (int s = 0; s < p % 4; ++s) {
        for (int c = 0; c < 3; ++c) rgb[c] += through * sample_value(p, s, c);
        alpha += through * sample_value(p, s, 3);
        through *= 1.0 - sample_value(p, s, 3);
      }
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(f.image(Role::Colour).at(x, y, c), rgb[c], 1e-6) << x << "," << y;
      EXPECT_NEAR(f.image(Role::Alpha).at(x, y, 0), alpha, 1e-6) << x << "," << y;
    }
}

// A file rewritten at the same path in one process (a re-rendered frame read again
// by the Python module, add-on or plugin) is read afresh: deep samples and flat
// passes both come from the new file, not from a cache of the first.
TEST_F(FrameIoTest, DeepFileRewrittenAtTheSamePathIsReadAfresh) {
  write_deep_file(path("deep.exr"), 3, 2, 1, 0.25f);
  const Frame first = read_frame(path("deep.exr"));
  ASSERT_TRUE(first.deep);
  EXPECT_EQ(first.deep->total_samples(), 6u);

  write_deep_file(path("deep.exr"), 5, 4, 2, 0.125f);
  const Frame second = read_frame(path("deep.exr"));
  ASSERT_TRUE(second.deep);
  EXPECT_EQ(second.width, 5);
  EXPECT_EQ(second.deep->width, 5);
  EXPECT_EQ(second.deep->height, 4);
  ASSERT_EQ(second.deep->total_samples(), 40u);
  const int r = second.deep->channel("R");
  ASSERT_GE(r, 0);
  for (float v : second.deep->values[std::size_t(r)]) EXPECT_EQ(v, 0.125f);
  // Two samples of colour 0.125 (premultiplied) and alpha 0.5: 0.125 + 0.5 * 0.125.
  EXPECT_NEAR(second.image(Role::Colour).at(4, 3, 0), 0.1875f, 1e-6f);
}

// ---------------------------------------------------------------- sequences

TEST(SequenceTest, PatternsAndPaths) {
  EXPECT_TRUE(is_sequence_pattern("shot_####.exr"));
  EXPECT_TRUE(is_sequence_pattern("shot_%04d.exr"));
  EXPECT_TRUE(is_sequence_pattern("shot_%d.exr"));
  EXPECT_FALSE(is_sequence_pattern("shot_0001.exr"));
  EXPECT_EQ(sequence_path("shot_####.exr", 7), "shot_0007.exr");
  EXPECT_EQ(sequence_path("shot_#.exr", 12), "shot_12.exr");
  EXPECT_EQ(sequence_path("shot_##.exr", 123), "shot_123.exr");
  EXPECT_EQ(sequence_path("dir/shot_%04d.exr", 42), "dir/shot_0042.exr");
  EXPECT_EQ(sequence_path("shot_%d.exr", 5), "shot_5.exr");
  EXPECT_EQ(sequence_path("a_####_b_####.exr", 3), "a_0003_b_####.exr");  // first run only
  EXPECT_EQ(sequence_path("still.exr", 3), "still.exr");
  EXPECT_EQ(sequence_path("s_%016d.exr", 3), "s_0000000000000003.exr");
  expect_error(Errc::InvalidArgument, [] { sequence_path("s_%099d.exr", 3); });           // would be cut short
  expect_error(Errc::InvalidArgument, [] { sequence_path("s_%099999999999d.exr", 3); });  // not an int
}

TEST(SequenceTest, FrameRanges) {
  using V = std::vector<int>;
  FrameList r = parse_frame_list("1-16");
  EXPECT_EQ(r.first(), 1);
  EXPECT_EQ(r.last(), 16);
  EXPECT_EQ(r.size(), 16u);
  EXPECT_TRUE(r.consecutive());
  EXPECT_EQ(parse_frame_list("7").frames(), V{7});
  EXPECT_EQ(parse_frame_list(" 3 - 5 ").frames(), (V{3, 4, 5}));
  EXPECT_EQ(parse_frame_list("-2-1").frames(), (V{-2, -1, 0, 1}));
  EXPECT_EQ(parse_frame_list("-8--5").frames(), (V{-8, -7, -6, -5}));
  for (const char* bad : {"", "a", "1-", "-", "1-2-3", "5-1", "1..4", "99999999999-1", "1-99999999999", "1-4x0",
                          "1,", ",1", "1,,2", "3,1", "2,2", "1-4,3", "1-4x", "1-4z2", "1-1y1", "1-2000000000"}) {
    const std::string msg = expect_error(Errc::InvalidArgument, [&] { parse_frame_list(bad); });
    EXPECT_TRUE(contains(msg, "--frames")) << bad << ": " << msg;
  }
}

// The lists oiiotool's --frames gives for the same text (oiiotool --frames T --echo "{FRAME_NUMBER}").
TEST(SequenceTest, FrameListsAsOiiotoolWritesThem) {
  using V = std::vector<int>;
  EXPECT_EQ(parse_frame_list("1-10x3").frames(), (V{1, 4, 7, 10}));
  EXPECT_EQ(parse_frame_list("1-10y3").frames(), (V{2, 3, 5, 6, 8, 9}));
  EXPECT_EQ(parse_frame_list("1,5,9").frames(), (V{1, 5, 9}));
  EXPECT_EQ(parse_frame_list("1-3,7").frames(), (V{1, 2, 3, 7}));
  EXPECT_EQ(parse_frame_list("1-16x2").frames(), (V{1, 3, 5, 7, 9, 11, 13, 15}));
  EXPECT_EQ(parse_frame_list("1-4,9-13x2").frames(), (V{1, 2, 3, 4, 9, 11, 13}));
  EXPECT_FALSE(parse_frame_list("1-10x3").consecutive());
  // A span near the top of int ends; a huge step is one frame, not a long loop.
  EXPECT_EQ(parse_frame_list("2147483646-2147483647").frames(), (V{2147483646, 2147483647}));
  EXPECT_EQ(parse_frame_list("1-2147483647x2147483647").frames(), V{1});
  EXPECT_EQ(parse_frame_list("-2147483648--2147483647").size(), 2u);
  // text() reads back as the same list, in its shortest form.
  for (const char* t : {"7", "1-16", "1-10x3", "1-10y3", "1,5,9", "-3-4"}) {
    const FrameList l = parse_frame_list(t);
    EXPECT_EQ(parse_frame_list(l.text()).frames(), l.frames()) << t << " -> " << l.text();
  }
  EXPECT_EQ(parse_frame_list("1,2,3").text(), "1-3");
  EXPECT_EQ(parse_frame_list("1,3,5").text(), "1-5x2");
  EXPECT_EQ(FrameList::span(3, 5).frames(), (V{3, 4, 5}));
  expect_error(Errc::InvalidArgument, [] { FrameList::span(5, 3); });
  expect_error(Errc::InvalidArgument, [] { FrameList::span(0, 2000000000); });
}

}  // namespace
}  // namespace mcr
