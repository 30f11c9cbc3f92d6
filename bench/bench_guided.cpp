// Guided filter run time against radius at 1024x1024 with a 4-channel guide
// (normal xyz + depth, the Bauszat et al. setting): the box sums make it O(N), so
// the times should be flat in the radius. The machine is shared: take the best of
// several runs (--benchmark_repetitions=5 --benchmark_report_aggregates_only=false).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "filters/registry.h"

namespace {

constexpr int kSize = 1024;

// A plausible render: a sphere in front of a tilted floor; normals, depth, and a
// noisy colour that follows the shading.
mcr::Frame synthetic_frame() {
  mcr::Frame f;
  f.width = kSize;
  f.height = kSize;
  f.path = "synthetic";
  mcr::Image colour(kSize, kSize, 3), normal(kSize, kSize, 3), depth(kSize, kSize, 1);
  std::mt19937 rng(7);
  std::exponential_distribution<float> noise(1.0f);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const float u = (x + 0.5f) / kSize * 2 - 1, v = (y + 0.5f) / kSize * 2 - 1;
      float n[3] = {0.0f, 0.8f, 0.6f}, z = 5.0f + 3.0f * v;
      const float rr = u * u + v * v;
      if (rr < 0.36f) {
        n[0] = u / 0.6f;
        n[1] = -v / 0.6f;
        n[2] = std::sqrt(std::max(0.0f, 1 - n[0] * n[0] - n[1] * n[1]));
        z = 3.0f - 0.6f * n[2];
      }
      const float shade = std::max(0.05f, 0.3f * n[0] + 0.8f * n[1] + 0.5f * n[2]);
      for (int c = 0; c < 3; ++c) {
        normal.at(x, y, c) = n[c];
        colour.at(x, y, c) = shade * (0.4f + 0.2f * c) * noise(rng);
      }
      depth.at(x, y, 0) = z;
    }
  auto add = [&](mcr::Role role, const char* name, mcr::Image img) {
    mcr::Pass p;
    p.role = role;
    p.name = name;
    p.image = std::move(img);
    f.passes.push_back(std::move(p));
  };
  add(mcr::Role::Colour, "Combined", std::move(colour));
  add(mcr::Role::Normal, "Normal", std::move(normal));
  add(mcr::Role::Depth, "Depth", std::move(depth));
  return f;
}

const mcr::Frame& frame() {
  static const mcr::Frame f = synthetic_frame();
  return f;
}

void BM_guided(benchmark::State& state) {
  auto filter = mcr::make_filter("guided");
  filter->set("radius", std::int64_t(state.range(0)));
  filter->set("guide", std::string("normal_depth"));
  filter->commit();
  mcr::ExecOptions opt;
  opt.nthreads = int(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(filter->execute(frame(), opt));
  state.SetItemsProcessed(state.iterations() * kSize * kSize);
}
BENCHMARK(BM_guided)
    ->ArgsProduct({{1, 2, 4, 8, 16, 32, 64}, {2, 1}})
    ->ArgNames({"radius", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The floor under it: the base class (copies, safety net) via the box filter.
void BM_box_floor(benchmark::State& state) {
  auto filter = mcr::make_filter("box");
  filter->set("radius", std::int64_t(0));
  filter->commit();
  mcr::ExecOptions opt;
  opt.nthreads = 2;
  for (auto _ : state) benchmark::DoNotOptimize(filter->execute(frame(), opt));
}
BENCHMARK(BM_box_floor)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
