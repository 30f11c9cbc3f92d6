// sweep (Shirley et al. 2011) run time per megapixel at 16 samples per pixel: the sorted sweep
// and the layered depth-of-field path for 1, 2 and 4 scales (widest 7 px), the blended two-scale
// default, and Alg. 1B. Synthetic defocus on 512x512: a near blurred band, a plane in focus
// with a sharp texture, a far background; per sample a random position in the pixel.
// Issue 17 points 2 and 5 (speed only: the error figures need the DOF sample scene).
// The machine may be shared: run with --benchmark_repetitions=3 and read the minimum.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>

#include "filters/registry.h"

namespace {

constexpr int kSize = 512, kSpp = 16;

const mcr::Frame& frame() {
  static const mcr::Frame f = [] {
    mcr::Frame fr;
    fr.width = fr.height = kSize;
    fr.path = "synthetic_dof";
    mcr::Pass p;
    p.role = mcr::Role::Colour;
    p.name = "RGB";
    p.image = mcr::Image(kSize, kSize, 3);
    fr.passes.push_back(p);
    auto d = std::make_shared<mcr::DeepSamples>();
    d->width = d->height = kSize;
    d->channel_names = {"R", "G", "B", "Z", "dx", "dy"};
    const std::size_t n = std::size_t(kSize) * kSize * kSpp;
    d->offsets.resize(std::size_t(kSize) * kSize + 1);
    for (std::size_t i = 0; i < d->offsets.size(); ++i) d->offsets[i] = i * kSpp;
    d->values.assign(6, std::vector<float>(n));
    d->attributes = {{"mcrecon:lens_mm", "50"}, {"mcrecon:fstop", "1.4"}, {"mcrecon:focus_distance", "4"},
                     {"mcrecon:sensor_width_mm", "36"}};
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x)
        for (int k = 0; k < kSpp; ++k) {
          const std::size_t i = (std::size_t(y) * kSize + x) * kSpp + k;
          const float dx = u(rng), dy = u(rng);
          float z, c;
          if (y < kSize / 4 && u(rng) < 0.7f) {
            z = 1.5f + 0.3f * u(rng), c = 2.0f;  // near, blurred
          } else if (y < 3 * kSize / 4) {
            z = 4.0f, c = ((x / 8 + y / 8) % 2) ? 0.8f : 0.1f;  // in focus, a checker
          } else {
            z = 30.0f + u(rng), c = 0.5f;  // far, blurred
          }
          const float v[6] = {c * u(rng) * 2, c, c * 0.5f, z, dx, dy};
          for (int ch = 0; ch < 6; ++ch) d->values[std::size_t(ch)][i] = v[ch];
        }
    fr.deep = d;
    return fr;
  }();
  return f;
}

void run(benchmark::State& state, const char* algorithm, int scales, bool blend, const char* layered) {
  auto f = mcr::make_filter("sweep");
  f->set_text("algorithm", algorithm);
  f->set("scales", std::int64_t(scales));
  f->set("width", 7.0);
  f->set("blend", blend);
  f->set_text("layered", layered);
  f->commit();
  const mcr::Frame& fr = frame();
  for (auto _ : state) benchmark::DoNotOptimize(f->execute(fr));
  state.counters["MP/s"] = benchmark::Counter(double(kSize) * kSize * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["s/MP"] = benchmark::Counter(double(kSize) * kSize * 1e-6,
                                              benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK_CAPTURE(run, sorted_1_scale, "sweep", 1, false, "off")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(run, sorted_2_scales, "sweep", 2, false, "off")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(run, layered_2_scales, "sweep", 2, false, "on")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(run, sorted_4_scales, "sweep", 4, false, "off")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(run, layered_4_scales, "sweep", 4, false, "on")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(run, sorted_2_blended_default, "sweep", 2, true, "auto")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(run, splat_alg1b, "splat", 2, true, "auto")->Unit(benchmark::kMillisecond)->UseRealTime();
