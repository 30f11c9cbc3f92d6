// Run time against kernel size at 1024x1024 for the image-space filters, the
// shape of Immonen 2017 tables 5.1 and 5.2: gaussian (Simple Blur), bilateral
// with 1, 2, 3 features (colour; + normal; + position) and atrous per pass count
// (cumulative; the per-pass cost is the difference of consecutive rows) for
// k_g = 3, 5, 9. Kernel size k = 2r + 1; sigma = r / 3 so that r = ceil(3 sigma).
// "Time" is wall clock (UseRealTime), "CPU" the whole process' CPU time over all
// threads (MeasureProcessCPUTime): on a shared machine CPU / threads is what the
// run would take on that many free cores. Threads are the last argument.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <vector>
#include <random>

#include "filters/registry.h"
#include "util/isa.h"

namespace {

constexpr int kSize = 1024;

// A frame with smooth shading plus noise, and geometry with edges: four planes
// (normals differ by quadrant), a sphere-ish bump in the middle.
const mcr::Frame& synthetic_frame() {
  static const mcr::Frame frame = [] {
    mcr::Frame f;
    f.width = f.height = kSize;
    f.path = "synthetic";
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    mcr::Image colour(kSize, kSize, 3), normal(kSize, kSize, 3), position(kSize, kSize, 3), albedo(kSize, kSize, 3),
        depth(kSize, kSize, 1);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const int q = (x < kSize / 2 ? 0 : 1) + (y < kSize / 2 ? 0 : 2);
        const float nx[4] = {0.0f, 0.6f, -0.6f, 0.0f}, nz[4] = {1.0f, 0.8f, 0.8f, 1.0f};
        const float ny[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        normal.at(x, y, 0) = nx[q];
        normal.at(x, y, 1) = ny[q];
        normal.at(x, y, 2) = nz[q];
        position.at(x, y, 0) = x * 0.01f;
        position.at(x, y, 1) = y * 0.01f;
        position.at(x, y, 2) = q * 0.5f;
        depth.at(x, y, 0) = 2.0f + q * 0.5f;
        for (int c = 0; c < 3; ++c) {
          albedo.at(x, y, c) = 0.2f + 0.2f * float(q) + 0.1f * float(c);
          colour.at(x, y, c) = albedo.at(x, y, c) * (0.5f + u(rng));
        }
      }
    auto add = [&f](mcr::Role r, const char* name, mcr::Image im) {
      mcr::Pass p;
      p.role = r;
      p.name = name;
      p.image = std::move(im);
      f.passes.push_back(std::move(p));
    };
    add(mcr::Role::Colour, "Combined", std::move(colour));
    add(mcr::Role::Normal, "Denoising Normal", std::move(normal));
    add(mcr::Role::Position, "Position", std::move(position));
    add(mcr::Role::Albedo, "Denoising Albedo", std::move(albedo));
    add(mcr::Role::Depth, "Depth", std::move(depth));
    return f;
  }();
  return frame;
}

// On a machine shared with others the fastest repetition is the one least
// disturbed: run with --benchmark_repetitions=N and read the _min rows.
double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

void common(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->ComputeStatistics("min", min_of);
}

void run(benchmark::State& state, mcr::Filter& filter, int threads) {
  filter.commit();
  mcr::ExecOptions opt;
  opt.nthreads = threads;
  const mcr::Frame& frame = synthetic_frame();
  filter.execute(frame, opt);  // warm-up: scratch planes allocated once, as for a video
  for (auto _ : state) benchmark::DoNotOptimize(filter.execute(frame, opt));
  state.SetItemsProcessed(state.iterations() * std::int64_t(kSize) * kSize);
  state.SetLabel(mcr::isa_name(mcr::isa()));
}

void use_features(mcr::Filter& f, int count) {
  const char* names[5] = {"colour", "normal", "position", "albedo", "depth"};
  for (int i = 0; i < 5; ++i) f.set(std::string("use_") + names[i], std::string(i < count ? "on" : "off"));
}

// Args: kernel size, threads.
void BM_gaussian(benchmark::State& state) {
  const int r = int(state.range(0) - 1) / 2;
  auto f = mcr::make_filter("gaussian");
  f->set("sigma", std::min(21.0, r / 3.0));
  run(state, *f, int(state.range(1)));
}
BENCHMARK(BM_gaussian)
    ->ArgsProduct({{1, 3, 5, 9, 17, 33, 65, 127}, {1, 2}})
    ->ArgNames({"k", "threads"})
    ->Apply(common);

// Foveated Simple Blur: sigma 0 at the gaze growing to r/3 beyond the outer radius
// (the non-separable per-pixel path). Args: outer kernel size, threads.
void BM_gaussian_foveated(benchmark::State& state) {
  const int r = int(state.range(0) - 1) / 2;
  auto f = mcr::make_filter("gaussian");
  f->set("foveated", true);
  f->set("sigma", 0.0);
  f->set("sigma_outer", std::min(21.0, r / 3.0));
  f->set("inner_radius", 0.1);
  f->set("outer_radius", 0.4);
  run(state, *f, int(state.range(1)));
}
BENCHMARK(BM_gaussian_foveated)
    ->ArgsProduct({{5, 9, 17}, {2}})
    ->ArgNames({"k", "threads"})
    ->Apply(common);

// Args: kernel size, features (1 colour, 2 + normal, 3 + position), threads.
void BM_bilateral(benchmark::State& state) {
  const int r = int(state.range(0) - 1) / 2;
  auto f = mcr::make_filter("bilateral");
  f->set("radius", std::int64_t(r));
  f->set("spatial_sigma", std::max(0.01, r / 3.0));
  use_features(*f, int(state.range(1)));
  run(state, *f, int(state.range(2)));
}
BENCHMARK(BM_bilateral)
    ->ArgsProduct({{1, 3, 5, 9, 17, 33}, {1, 2, 3}, {2}})
    ->ArgNames({"k", "features", "threads"})
    ->Apply(common);
BENCHMARK(BM_bilateral)
    ->ArgsProduct({{17}, {3}, {1}})
    ->ArgNames({"k", "features", "threads"})
    ->Apply(common);
BENCHMARK(BM_bilateral)
    ->ArgsProduct({{65}, {1, 3}, {2}})
    ->ArgNames({"k", "features", "threads"})
    ->Apply(common)
    ->Iterations(1);

// order=1 (first-order regression on the features): kernel size, features, threads.
// Quadratic in the radius like order 0, with an (n+1)^2 update per tap.
void BM_bilateral_order1(benchmark::State& state) {
  const int r = int(state.range(0) - 1) / 2;
  auto f = mcr::make_filter("bilateral");
  f->set("radius", std::int64_t(r));
  f->set("spatial_sigma", std::max(0.01, r / 3.0));
  f->set("order", std::int64_t(1));
  use_features(*f, int(state.range(1)));
  run(state, *f, int(state.range(2)));
}
BENCHMARK(BM_bilateral_order1)
    ->ArgsProduct({{5, 9, 13}, {3}, {2}})
    ->ArgNames({"k", "features", "threads"})
    ->Apply(common)
    ->Iterations(1);

// Args: k_g, iterations (cumulative time), threads. Colour + normal + position.
void BM_atrous(benchmark::State& state) {
  auto f = mcr::make_filter("atrous");
  f->set("kernel_size", state.range(0));
  f->set("iterations", state.range(1));
  use_features(*f, 3);
  run(state, *f, int(state.range(2)));
}
BENCHMARK(BM_atrous)
    ->ArgsProduct({{3, 5, 9}, {1, 2, 3, 4, 5, 6}, {2}})
    ->ArgNames({"kg", "iterations", "threads"})
    ->Apply(common);
BENCHMARK(BM_atrous)
    ->ArgsProduct({{5}, {5}, {1}})
    ->ArgNames({"kg", "iterations", "threads"})
    ->Apply(common);

// The three builds of the cross kernel on this CPU (0 generic, 1 avx2, 2 avx512)
// for the two targets: atrous 5 passes k_g 5 and bilateral radius 8, 3 features.
void BM_isa(benchmark::State& state) {
  const mcr::Isa level = mcr::Isa(state.range(0));
  if (int(level) > int(mcr::best_isa())) {
    state.SkipWithError("instruction set not available on this CPU");
    return;
  }
  const mcr::ScopedIsa use(level);
  auto f = mcr::make_filter(state.range(1) ? "bilateral" : "atrous");
  if (state.range(1)) {
    f->set("radius", std::int64_t(8));
    f->set("spatial_sigma", 8 / 3.0);
  } else {
    f->set("kernel_size", std::int64_t(5));
    f->set("iterations", std::int64_t(5));
  }
  use_features(*f, 3);
  run(state, *f, int(state.range(2)));
}
BENCHMARK(BM_isa)
    ->ArgsProduct({{0, 1, 2}, {0, 1}, {1}})
    ->ArgNames({"isa", "bilateral", "threads"})
    ->Apply(common);

}  // namespace
