// The sweep filter on deep frames: closed forms (in-focus = the pixel mean, all blurred = the
// wide box of the pixel means), the camera from parameters and from a deep EXR's header, the
// layered path against the sorted one, the sort skipped where nothing is blurred, the edge
// cases of deep input, and the errors a user meets.
#include "filters/samples/sweep.h"

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <vector>

#include "expect_error.h"
#include "filters/samples/sweep_samples.h"
#include "io/frame_reader.h"
#include "util/error.h"

namespace mcr {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// A camera with a strong defocus on small test images: 50 mm f/0.1 on a 36 mm sensor, focus 4
// (on 24 pixels: 7 px at depth 1.5, 3.7 px at 40).
constexpr double kLens = 50, kFstop = 0.1, kFocus = 4, kSensor = 36;

struct DeepBuilder {
  int w, h;
  std::vector<std::vector<std::vector<float>>> px;  // per pixel: samples of {R,G,B,Z,dx,dy}
  DeepBuilder(int w_, int h_) : w(w_), h(h_), px(std::size_t(w_ * h_)) {}
  void add(int x, int y, float r, float g, float b, float z, float dx, float dy) {
    px[std::size_t(y * w + x)].push_back({r, g, b, z, dx, dy});
  }
  std::shared_ptr<DeepSamples> deep() const {
    auto d = std::make_shared<DeepSamples>();
    d->width = w;
    d->height = h;
    d->channel_names = {"R", "G", "B", "Z", "dx", "dy"};
    d->offsets.assign(px.size() + 1, 0);
    for (std::size_t p = 0; p < px.size(); ++p) d->offsets[p + 1] = d->offsets[p] + px[p].size();
    d->values.assign(6, std::vector<float>(d->total_samples()));
    for (std::size_t p = 0; p < px.size(); ++p)
      for (std::size_t s = 0; s < px[p].size(); ++s)
        for (int c = 0; c < 6; ++c) d->values[std::size_t(c)][d->offsets[p] + s] = px[p][s][std::size_t(c)];
    return d;
  }
  Frame frame() const {
    Frame f;
    f.width = w;
    f.height = h;
    f.path = "deep.exr";
    Pass p;
    p.role = Role::Colour;
    p.name = "RGB";
    p.image = Image(w, h, 3);
    f.passes.push_back(p);
    f.deep = deep();
    return f;
  }
  // Per-pixel sample mean (Alg. 1), channel 0.
  double mean(int x, int y) const {
    const auto& v = px[std::size_t(y * w + x)];
    double s = 0;
    for (const auto& a : v) s += a[0];
    return v.empty() ? 0.0 : s / double(v.size());
  }
};

// A depth whose circle of confusion is `d` pixels on a `width`-pixel image (before the focus).
float depth_for_coc(double d, int width) {
  sweep::Camera cam{kLens, kFstop, kFocus, kSensor};
  double lo = 1e-4, hi = kFocus;  // the circle shrinks from lo to hi
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cam.coc(mid, width) > d ? lo : hi) = mid;
  }
  return float(0.5 * (lo + hi));
}

DeepBuilder random_scene(int w, int h, int spp, float z_of_pixel(int, int, float), unsigned seed) {
  DeepBuilder b(w, h);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < spp; ++k) b.add(x, y, u(rng) * 2, u(rng), u(rng), z_of_pixel(x, y, u(rng)), u(rng), u(rng));
  return b;
}

Image run(SweepFilter& f, const Frame& frame) {
  f.commit();
  return f.execute(frame);
}

void set_camera(SweepFilter& f) {
  f.set("lens_mm", kLens);
  f.set("fstop", kFstop);
  f.set("focus_distance", kFocus);
  f.set("sensor_width_mm", kSensor);
}

TEST(Sweep, InFocusIsThePixelMeanAndNeedsNoSort) {
  DeepBuilder b = random_scene(12, 9, 16, [](int, int, float u) { return float(kFocus) + 0.01f * u; }, 3);
  SweepFilter f;
  set_camera(f);
  Image out = run(f, b.frame());
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 12; ++x) EXPECT_NEAR(out.pixel(x, y)[0], b.mean(x, y), 1e-5) << x << "," << y;
  EXPECT_EQ(f.sorted_pixels(), 0u);
}

TEST(Sweep, AllBlurredIsTheWideBoxOfThePixelMeans) {
  const float z = depth_for_coc(9.0, 16);
  DeepBuilder b = random_scene(16, 12, 16, [](int, int, float) { return 0.0f; }, 5);
  for (auto& p : b.px)
    for (auto& s : p) s[3] = z;
  SweepFilter f;
  set_camera(f);
  f.set("width", 5.0);    // the paper's two scales, 1 and 5
  f.set("step_back", 0.0);  // the sweep alone
  Image out = run(f, b.frame());
  for (int y = 2; y < 10; ++y)
    for (int x = 2; x < 14; ++x) {
      double want = 0;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) want += b.mean(x + dx, y + dy);
      EXPECT_NEAR(out.pixel(x, y)[0], want / 25, 1e-5) << x << "," << y;
    }
  EXPECT_EQ(f.sorted_pixels(), 0u);
}

float defocus_scene(int x, int y, float u) {
  if (x + y < 10) return 1.0f + 0.3f * u;  // near, blurred (8.6 to 12.5 px)
  if (y > 12) return 40.0f + u;            // far, blurred
  return float(kFocus) - 0.1f + 0.2f * u;  // in focus
}

TEST(Sweep, LayeredEqualsSortedOnDefocus) {
  DeepBuilder b = random_scene(24, 18, 16, defocus_scene, 7);
  for (int scales : {2, 4}) {
    SweepFilter sorted, layered;
    for (SweepFilter* f : {&sorted, &layered}) {
      set_camera(*f);
      f->set("blend", false);
      f->set("scales", std::int64_t(scales));
      f->set("width", 7.0);
    }
    sorted.set_text("layered", "off");
    layered.set_text("layered", "on");
    Image a = run(sorted, b.frame()), c = run(layered, b.frame());
    EXPECT_FALSE(sorted.used_layered());
    EXPECT_TRUE(layered.used_layered());
    EXPECT_GT(sorted.sorted_pixels(), 0u);
    for (int y = 0; y < 18; ++y)
      for (int x = 0; x < 24; ++x)
        for (int ch = 0; ch < 3; ++ch)
          EXPECT_NEAR(a.pixel(x, y)[ch], c.pixel(x, y)[ch], 1e-5f * std::max(1.0f, std::fabs(a.pixel(x, y)[ch])));
  }
}

TEST(Sweep, CameraFromTheDeepFileHeader) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("mcrecon_sweep_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "defocus.exr").string();
  DeepBuilder b = random_scene(10, 8, 4, defocus_scene, 9);
  {
    OIIO::ImageSpec spec(10, 8, 6, OIIO::TypeFloat);
    spec.channelnames = {"R", "G", "B", "Z", "dx", "dy"};
    spec.z_channel = 3;
    spec.deep = true;
    spec.attribute("compression", "zips");
    spec.attribute("mcrecon:lens_mm", float(kLens));
    spec.attribute("mcrecon:fstop", float(kFstop));
    spec.attribute("mcrecon:focus_distance", float(kFocus));
    spec.attribute("mcrecon:sensor_width_mm", float(kSensor));
    OIIO::DeepData dd(spec);
    for (int p = 0; p < 80; ++p) {
      dd.set_samples(p, int(b.px[std::size_t(p)].size()));
      for (std::size_t s = 0; s < b.px[std::size_t(p)].size(); ++s)
        for (int c = 0; c < 6; ++c) dd.set_deep_value(p, c, int(s), b.px[std::size_t(p)][s][std::size_t(c)]);
    }
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec) && out->write_deep_image(dd)) << OIIO::geterror();
    out->close();
  }
  const Frame read = read_frame(path);
  ASSERT_TRUE(read.deep);
  SweepFilter from_file, from_params;
  set_camera(from_params);
  Image a = run(from_file, read), c = run(from_params, b.frame());
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 10; ++x) EXPECT_NEAR(a.pixel(x, y)[0], c.pixel(x, y)[0], 1e-5f);
  // A parameter overrides the header: another focus gives another image.
  SweepFilter refocused;
  set_camera(refocused);
  refocused.set("focus_distance", 1.6);
  Image d = run(refocused, read);
  double diff = 0;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 10; ++x) diff += std::fabs(d.pixel(x, y)[0] - a.pixel(x, y)[0]);
  EXPECT_GT(diff, 0.1);
  fs::remove_all(dir);
}

TEST(Sweep, BlurChannelAndAlgorithms) {
  // The blur channel is the diameter; splat (Alg. 1B) and box (Alg. 1) read the same samples.
  DeepBuilder b = random_scene(10, 10, 8, [](int, int, float u) { return 2.0f + u; }, 11);
  Frame f = b.frame();
  auto deep = std::make_shared<DeepSamples>(*f.deep);
  deep->channel_names.push_back("blur");
  deep->values.emplace_back(deep->total_samples(), 1.0f);
  f.deep = deep;
  SweepFilter box, sweep1;
  box.set_text("algorithm", "box");
  Image a = run(box, f), c = run(sweep1, f);  // blur 1 everywhere: the sweep is the box
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 10; ++x) {
      EXPECT_NEAR(a.pixel(x, y)[0], b.mean(x, y), 1e-5);
      EXPECT_NEAR(c.pixel(x, y)[0], b.mean(x, y), 1e-5);
    }
}

TEST(Sweep, DeepEdgeCases) {
  // 0, 1 and 1000 samples, NaN depth and colour, all background, and a 1x1 image.
  DeepBuilder b(6, 5);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 6; ++x) {
      const int n = x == 0 ? 0 : x == 1 ? 1 : x == 2 ? 1000 : 4;
      for (int k = 0; k < n; ++k) {
        float z = 1 + 10 * u(rng);
        if (x == 3) z = kNaN;
        if (x == 4) z = k % 2 ? kInf : 0.0f;  // background both ways
        float r = u(rng);
        if (x == 5 && k == 0) r = kNaN;
        b.add(x, y, r, u(rng), u(rng), z, u(rng), u(rng));
      }
    }
  for (const char* alg : {"sweep", "splat", "box"}) {
    SweepFilter f;
    set_camera(f);
    f.set_text("algorithm", alg);
    Image out = run(f, b.frame());
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 6; ++x)
        for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(out.pixel(x, y)[c])) << alg << " " << x << "," << y;
    EXPECT_EQ(f.nonfinite_repaired(), 0u);
  }
  // Alg. 1: a pixel with no sample gives 0; the NaN sample is left out of its pixel's mean.
  SweepFilter box;
  box.set_text("algorithm", "box");
  Image out = run(box, b.frame());
  EXPECT_EQ(out.pixel(0, 2)[0], 0.0f);
  const auto& v = b.px[std::size_t(2 * 6 + 5)];
  EXPECT_NEAR(out.pixel(5, 2)[0], (v[1][0] + v[2][0] + v[3][0]) / 3.0, 1e-6);
  // 1x1.
  DeepBuilder one(1, 1);
  one.add(0, 0, 0.5f, 0.25f, 1.0f, 3.0f, 0.5f, 0.5f);
  SweepFilter f1;
  set_camera(f1);
  Image o1 = run(f1, one.frame());
  EXPECT_FLOAT_EQ(o1.pixel(0, 0)[0], 0.5f);
  EXPECT_FLOAT_EQ(o1.pixel(0, 0)[2], 1.0f);
}

TEST(Sweep, StepBackKeepsCleanPixelsAndLetsNoisyOnesBlur) {
  // Everything blurred (diameter 9). Left half: every sample of a pixel the same colour (a
  // clean pixel: no spread), a checker of pixel colours; right half: samples spread widely.
  const float z = depth_for_coc(9.0, 16);
  DeepBuilder b(16, 8);
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x)
      for (int k = 0; k < 16; ++k) {
        const float v = x < 8 ? ((x + y) % 2 ? 1.0f : 0.2f) : 4.0f * u(rng);
        b.add(x, y, v, v, v, z, u(rng), u(rng));
      }
  SweepFilter off, on;
  for (SweepFilter* f : {&off, &on}) set_camera(*f);
  off.set("step_back", 0.0);
  on.set("step_back", 1.0);
  Image a = run(off, b.frame()), c = run(on, b.frame());
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 6; ++x) EXPECT_FLOAT_EQ(c.pixel(x, y)[0], float(b.mean(x, y))) << x << "," << y;
  // Noisy pixels: within one standard error of their own mean, and mostly the sweep's result.
  int kept = 0;
  for (int y = 0; y < 8; ++y)
    for (int x = 10; x < 16; ++x) {
      const auto& v = b.px[std::size_t(y * 16 + x)];
      double m = 0, s2 = 0;
      for (const auto& s : v) m += s[0] / 16.0;
      for (const auto& s : v) s2 += (s[0] - m) * (s[0] - m) / 15.0;
      EXPECT_LE(std::fabs(c.pixel(x, y)[0] - m), std::sqrt(s2 / 16.0) * (1 + 1e-4) + 1e-6);
      kept += c.pixel(x, y)[0] == a.pixel(x, y)[0];
    }
  EXPECT_GT(kept, 24);  // of 48
}

TEST(Sweep, ErrorsNameWhatIsMissing) {
  DeepBuilder b = random_scene(4, 4, 2, [](int, int, float) { return 2.0f; }, 1);
  Frame flat = b.frame();
  flat.deep.reset();
  SweepFilter f;
  set_camera(f);
  f.commit();
  testutil::expect_error(Errc::MissingPass, {"deep", "deep.exr"}, [&] { f.execute(flat); });
  // No camera, no blur, no motion: nothing gives a diameter.
  SweepFilter nocam;
  nocam.commit();
  testutil::expect_error(Errc::MissingPass, {"blur", "deep.exr"}, [&] { nocam.execute(b.frame()); });
  SweepFilter coc;
  coc.set_text("diameter", "coc");
  coc.commit();
  testutil::expect_error(Errc::MissingPass, {"lens_mm", "deep.exr"}, [&] { coc.execute(b.frame()); });
  // No Z channel.
  Frame noz = b.frame();
  auto d = std::make_shared<DeepSamples>(*noz.deep);
  d->channel_names[3] = "depth";
  noz.deep = d;
  testutil::expect_error(Errc::MissingPass, {"'Z'", "deep.exr"}, [&] { f.execute(noz); });
  // A header attribute that is not a number.
  Frame bad = b.frame();
  auto d2 = std::make_shared<DeepSamples>(*bad.deep);
  d2->attributes["mcrecon:fstop"] = "f/2";
  bad.deep = d2;
  SweepFilter fromfile;
  fromfile.commit();
  testutil::expect_error(Errc::BadParameterValue, {"mcrecon:fstop", "f/2"}, [&] { fromfile.execute(bad); });
  // layered=on with blend on, and with a diameter that is not the circle of confusion.
  SweepFilter lay;
  lay.set_text("layered", "on");
  testutil::expect_error(Errc::BadParameterValue, {"layered=on", "blend=off"}, [&] { lay.commit(); });
  SweepFilter lay2;
  set_camera(lay2);
  lay2.set_text("layered", "on");
  lay2.set("blend", false);
  lay2.set_text("diameter", "blur");
  lay2.commit();
  testutil::expect_error(Errc::MissingPass, {"'blur'"}, [&] { lay2.execute(b.frame()); });
}

}  // namespace
}  // namespace mcr
