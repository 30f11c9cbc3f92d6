// The sample manifest: a manifest written here is read back field by field, load_scene reads
// the renders it names, and a missing file, bad JSON or an spp the manifest lacks give the
// errors the headers name (io/sample_manifest.h, pipeline/evaluate.h).
#include "io/sample_manifest.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "io/sequence.h"
#include "pipeline/evaluate.h"
#include "expect_error.h"
#include "scratch_dir.h"

namespace mcr {
namespace {

using namespace testutil;
namespace fs = std::filesystem;

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

// A w x h R,G,B EXR whose every value is v.
void write_flat_exr(const std::string& path, int w, int h, float v) {
  fs::create_directories(fs::path(path).parent_path());
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  const OIIO::ImageSpec spec(w, h, 3, OIIO::TypeFloat);
  const std::vector<float> px(std::size_t(w) * h * 3, v);
  ASSERT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeFloat, px.data()) && out->close()) << out->geterror();
}

const char* const kManifest = R"({
 "scenes": [
  {"name": "wall", "kind": "still", "description": "a flat wall", "width": 6, "height": 4,
   "noisy": {"1": "wall/wall_1spp.exr", "16": "wall/wall_16spp.exr"},
   "reference": "wall/wall_ref.exr", "reference_spp": 256},
  {"name": "pan", "kind": "sequence", "width": 5, "height": 3,
   "noisy": {"2": "pan/pan_2spp_####.exr"},
   "reference": "pan/pan_ref_####.exr", "reference_spp": 64, "frames": [3, 5]},
  {"name": "bare", "noisy": {}, "reference": "bare.exr"}
 ]
})";

TEST(SampleManifest, WrittenManifestReadsBack) {
  const ScratchDir dir("mcrecon_manifest");
  write_text(dir.path("manifest.json"), kManifest);
  const std::vector<SampleScene> scenes = load_sample_manifest(dir.str());
  ASSERT_EQ(scenes.size(), 3u);
  const SampleScene& wall = scenes[0];
  EXPECT_EQ(wall.name, "wall");
  EXPECT_EQ(wall.kind, "still");
  EXPECT_FALSE(wall.is_sequence());
  EXPECT_EQ(wall.description, "a flat wall");
  EXPECT_EQ(wall.width, 6);
  EXPECT_EQ(wall.height, 4);
  EXPECT_EQ(wall.noisy, (std::map<int, std::string>{{1, dir.path("wall/wall_1spp.exr")},
                                                    {16, dir.path("wall/wall_16spp.exr")}}));
  EXPECT_EQ(wall.reference, dir.path("wall/wall_ref.exr"));
  EXPECT_EQ(wall.reference_spp, 256);
  const SampleScene& pan = scenes[1];
  EXPECT_TRUE(pan.is_sequence());
  EXPECT_EQ(pan.noisy, (std::map<int, std::string>{{2, dir.path("pan/pan_2spp_####.exr")}}));
  EXPECT_EQ(pan.reference, dir.path("pan/pan_ref_####.exr"));
  EXPECT_EQ(pan.first_frame, 3);
  EXPECT_EQ(pan.last_frame, 5);
  // Optional fields take their defaults.
  const SampleScene& bare = scenes[2];
  EXPECT_EQ(bare.kind, "still");
  EXPECT_EQ(bare.description, "");
  EXPECT_EQ(bare.width, 0);
  EXPECT_EQ(bare.reference_spp, 0);
  EXPECT_TRUE(bare.noisy.empty());
  EXPECT_EQ(bare.first_frame, 1);
  EXPECT_EQ(bare.last_frame, 1);
}

TEST(SampleManifest, LoadSceneReadsTheNamedRendersInFrameOrder) {
  const ScratchDir dir("mcrecon_manifest");
  write_text(dir.path("manifest.json"), kManifest);
  const std::vector<SampleScene> scenes = load_sample_manifest(dir.str());
  write_flat_exr(dir.path("wall/wall_16spp.exr"), 6, 4, 0.5f);
  write_flat_exr(dir.path("wall/wall_ref.exr"), 6, 4, 0.25f);
  for (int f = 3; f <= 5; ++f) {
    write_flat_exr(sequence_path(dir.path("pan/pan_2spp_####.exr"), f), 5, 3, float(f));
    write_flat_exr(sequence_path(dir.path("pan/pan_ref_####.exr"), f), 5, 3, float(10 * f));
  }
  const LoadedScene wall = load_scene(scenes[0], 16);
  EXPECT_EQ(wall.name, "wall");
  EXPECT_EQ(wall.spp, 16);
  ASSERT_EQ(wall.frames.size(), 1u);
  ASSERT_EQ(wall.references.size(), 1u);
  EXPECT_EQ(wall.frames[0].width, 6);
  EXPECT_EQ(wall.frames[0].image(Role::Colour).at(5, 3, 2), 0.5f);
  EXPECT_EQ(wall.references[0].at(0, 0, 0), 0.25f);
  std::vector<int> progress;
  const LoadedScene pan = load_scene(scenes[1], 2, [&](int done, int total) { progress.push_back(done * 10 + total); });
  ASSERT_EQ(pan.frames.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(pan.frames[std::size_t(i)].frame_number, 3 + i);
    EXPECT_EQ(pan.frames[std::size_t(i)].image(Role::Colour).at(1, 1, 0), float(3 + i));
    EXPECT_EQ(pan.references[std::size_t(i)].at(4, 2, 1), float(10 * (3 + i)));
  }
  EXPECT_EQ(progress, (std::vector<int>{13, 23, 33}));
}

TEST(SampleManifest, MissingManifestIsFileNotFoundNamingIt) {
  const ScratchDir dir("mcrecon_manifest");
  expect_error(Errc::FileNotFound, {dir.path("manifest.json")}, [&] { load_sample_manifest(dir.str()); });
}

TEST(SampleManifest, BadJsonIsInvalidArgumentNamingTheFile) {
  const ScratchDir dir("mcrecon_manifest");
  const std::string file = dir.path("manifest.json");
  for (const char* text : {R"({"scenes": [ {"name": "x", )",                       // truncated
                           R"({"scenes": [{"noisy": {}, "reference": "r.exr"}]})",  // no name
                           R"({"scenes": [{"name": "x", "noisy": {}}]})",           // no reference
                           R"({"scenes": [{"name": 3, "noisy": {}, "reference": "r.exr"}]})",
                           R"({"stills": []})"}) {
    SCOPED_TRACE(text);
    write_text(file, text);
    expect_error(Errc::InvalidArgument, {"malformed sample manifest", file}, [&] { load_sample_manifest(dir.str()); });
  }
}

TEST(SampleManifest, SppTheManifestLacksIsMissingPassNamingSceneAndSpp) {
  const ScratchDir dir("mcrecon_manifest");
  write_text(dir.path("manifest.json"), kManifest);
  const std::vector<SampleScene> scenes = load_sample_manifest(dir.str());
  expect_error(Errc::MissingPass, {"'wall'", "4 spp"}, [&] { load_scene(scenes[0], 4); });
  // A render the manifest names but the directory lacks: the reader's error, naming the file.
  expect_error(Errc::FileNotFound, {dir.path("wall/wall_1spp.exr")}, [&] { load_scene(scenes[0], 1); });
}

TEST(SampleManifest, DefaultDirectoryHonoursTheEnvironment) {
  const char* old = std::getenv("MCRECON_SAMPLES");
  const std::string saved = old ? old : "";
  ::setenv("MCRECON_SAMPLES", "/some/where", 1);
  EXPECT_EQ(default_samples_dir(), "/some/where");
  ::unsetenv("MCRECON_SAMPLES");
  EXPECT_EQ(default_samples_dir(), std::string(MCRECON_SOURCE_DIR) + "/samples/data");
  if (old) ::setenv("MCRECON_SAMPLES", saved.c_str(), 1);
}

TEST(SampleManifest, ShippedManifestNamesFilesThatExist) {
  const std::string dir = std::string(MCRECON_SOURCE_DIR) + "/samples/data";
  const std::vector<SampleScene> scenes = load_sample_manifest(dir);
  ASSERT_FALSE(scenes.empty());
  for (const SampleScene& s : scenes) {
    SCOPED_TRACE(s.name);
    EXPECT_FALSE(s.noisy.empty());
    std::vector<std::string> files;
    for (int f : {s.first_frame, s.last_frame}) {
      for (const auto& [spp, path] : s.noisy) files.push_back(s.is_sequence() ? sequence_path(path, f) : path);
      files.push_back(s.is_sequence() ? sequence_path(s.reference, f) : s.reference);
    }
    for (const std::string& p : files) EXPECT_TRUE(fs::exists(p)) << p;
  }
}

// A noisy key that is not a sample count is a typed error naming the file and the key,
// not a std::invalid_argument from a string conversion.
TEST(SampleManifest, NonNumericSppIsInvalidArgumentNamingTheFile) {
  const ScratchDir dir("mcrecon_manifest");
  const std::string file = dir.path("manifest.json");
  write_text(file, R"({"scenes": [{"name": "x", "noisy": {"many": "x.exr"}, "reference": "r.exr"}]})");
  expect_error(Errc::InvalidArgument, {file, "many"}, [&] { load_sample_manifest(dir.str()); });
}

}  // namespace
}  // namespace mcr
