// evaluate(): metrics averaged over the frames, the temporal error over consecutive
// results and the middle frame's preview, against numbers computed here from a
// brute-force box filter and the metrics' definitions (README "Metrics").
#include "pipeline/evaluate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "metrics_oracle.h"

namespace mcr {
namespace {

using namespace testutil;


ImageMetrics metrics_oracle(const Image& ref, const Image& img) {
  double se = 0, rel = 0, se_clamped = 0;
  const double n = 3.0 * ref.width() * ref.height();
  for (int y = 0; y < ref.height(); ++y)
    for (int x = 0; x < ref.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const double r = ref.at(x, y, c), v = img.at(x, y, c);
        se += (v - r) * (v - r);
        rel += (v - r) * (v - r) / (r * r + 0.01);
        se_clamped += std::pow(clamped(img.at(x, y, c)) - clamped(ref.at(x, y, c)), 2);
      }
  return {std::sqrt(se / n), rel / n, 10.0 * std::log10(n / se_clamped), brute_force_ssim(ref, img)};
}

// Mean over pixels of |Y(b) - Y(a)|, Rec. 709 luminance.
double temporal_oracle(const Image& a, const Image& b) {
  auto lum = [](const Image& im, int x, int y) {
    return 0.2126 * im.at(x, y, 0) + 0.7152 * im.at(x, y, 1) + 0.0722 * im.at(x, y, 2);
  };
  double s = 0;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) s += std::fabs(lum(b, x, y) - lum(a, x, y));
  return s / (double(a.width()) * a.height());
}

// Smooth references, noisy frames around them; each frame a little brighter than the last.
LoadedScene synthetic_scene(int frames, int w = 13, int h = 9) {
  LoadedScene s;
  s.name = "synthetic";
  s.spp = 4;
  for (int f = 0; f < frames; ++f) {
    Image ref(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) ref.at(x, y, c) = 0.2f + 0.04f * float(x) + 0.03f * float(y * c) + 0.05f * float(f);
    Image noisy = random_image(w, h, 3, 100u + unsigned(f), -0.3f, 0.3f);
    for (std::size_t i = 0; i < noisy.storage().size(); ++i) noisy.storage()[i] += ref.storage()[i];
    Frame fr = colour_frame(noisy);
    add_pass(fr, Role::Normal, random_image(w, h, 3, 200u + unsigned(f), -1.0f, 1.0f));
    add_pass(fr, Role::Position, random_image(w, h, 3, 300u, 0.0f, 2.0f));
    fr.frame_number = f + 1;
    s.frames.push_back(fr);
    s.references.push_back(ref);
  }
  return s;
}

std::unique_ptr<Filter> box(int radius) {
  auto f = make_filter("box");
  testutil::without_step_back(*f);
  f->set("radius", std::int64_t(radius));
  f->commit();
  return f;
}

void expect_images_near(const Image& got, const Image& want, double tol) {
  ASSERT_EQ(got.width(), want.width());
  ASSERT_EQ(got.height(), want.height());
  for (int y = 0; y < want.height(); ++y)
    for (int x = 0; x < want.width(); ++x)
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(got.at(x, y, c), want.at(x, y, c), tol) << x << "," << y << "," << c;
}

void expect_metrics_near(const ImageMetrics& got, const ImageMetrics& want, double rel) {
  EXPECT_NEAR(got.rmse, want.rmse, rel * want.rmse);
  EXPECT_NEAR(got.relmse, want.relmse, rel * want.relmse);
  EXPECT_NEAR(got.psnr, want.psnr, rel * want.psnr);
  EXPECT_NEAR(got.ssim, want.ssim, rel);
}

// The mean of the oracles over the frames of `results` against the scene's references.
ImageMetrics mean_oracle(const LoadedScene& s, const std::vector<Image>& results) {
  ImageMetrics m;
  const double n = double(results.size());
  for (std::size_t i = 0; i < results.size(); ++i) {
    const ImageMetrics k = metrics_oracle(s.references[i], results[i]);
    m.rmse += k.rmse / n;
    m.relmse += k.relmse / n;
    m.psnr += k.psnr / n;
    m.ssim += k.ssim / n;
  }
  return m;
}

TEST(Evaluate, StillBoxFilterMetricsAreTheOracles) {
  const LoadedScene s = synthetic_scene(1);
  auto f = box(1);
  const Evaluation ev = evaluate(s, f.get(), 1);
  const Image want = box_oracle(s.frames[0].image(Role::Colour), 1);
  expect_images_near(ev.preview, want, 1e-6);
  expect_metrics_near(ev.metrics, metrics_oracle(s.references[0], want), 1e-5);
  EXPECT_EQ(ev.temporal_error, -1.0);  // a still has none
  // The box filter helps here: the metrics do see the filter.
  EXPECT_LT(ev.metrics.rmse, metrics_oracle(s.references[0], s.frames[0].image(Role::Colour)).rmse);
}

TEST(Evaluate, ThreeFrameSequenceMeansAndTemporalError) {
  const LoadedScene s = synthetic_scene(3);
  std::vector<Image> boxed, noisy;
  for (const Frame& fr : s.frames) {
    boxed.push_back(box_oracle(fr.image(Role::Colour), 2));
    noisy.push_back(fr.image(Role::Colour));
  }
  auto f = box(2);
  const Evaluation ev = evaluate(s, f.get(), 2);
  expect_metrics_near(ev.metrics, mean_oracle(s, boxed), 1e-5);
  EXPECT_NEAR(ev.temporal_error, (temporal_oracle(boxed[0], boxed[1]) + temporal_oracle(boxed[1], boxed[2])) / 2, 1e-6);
  expect_images_near(ev.preview, boxed[1], 1e-6);  // the middle frame
  // No filter: the noisy input itself is judged.
  const Evaluation in = evaluate(s, nullptr, 2);
  expect_metrics_near(in.metrics, mean_oracle(s, noisy), 1e-9);
  EXPECT_NEAR(in.temporal_error, (temporal_oracle(noisy[0], noisy[1]) + temporal_oracle(noisy[1], noisy[2])) / 2, 1e-9);
  EXPECT_EQ(in.preview.storage(), noisy[1].storage());
}

TEST(Evaluate, TemporalFilterStartsFromAFreshHistory) {
  // bmfr keeps history between frames: a second evaluation with the same object must not
  // continue the first one's, so both equal an evaluation by a fresh filter.
  const LoadedScene s = synthetic_scene(3);
  auto used = make_filter("bmfr");
  used->commit();
  const Evaluation first = evaluate(s, used.get(), 1);
  const Evaluation second = evaluate(s, used.get(), 1);
  auto fresh = make_filter("bmfr");
  fresh->commit();
  EXPECT_EQ(evaluate(s, fresh.get(), 1).preview.storage(), second.preview.storage());
  EXPECT_EQ(first.preview.storage(), second.preview.storage());
  EXPECT_EQ(first.metrics.rmse, second.metrics.rmse);
  EXPECT_EQ(first.temporal_error, second.temporal_error);
}

}  // namespace
}  // namespace mcr
