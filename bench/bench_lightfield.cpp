// The light-field filters' run time per pixel (issue 18): the factored sheared filter against
// the brute-force 4D one and axis-aligned filtering, on synthetic depth-of-field light fields of
// 128x128 and 256x256, l = 2, 3, 4 (4 to 16 samples per pixel), max_width 8, 16, 32. The slopes
// (6 .. 8, sigma_y 0.5: sigma_x 12 pixels) put every sheared support at the max_width cap, and
// aaf's mu = 0.1 gives it the same radius (sigma_x 15 pixels), so the three compare at one
// width. One thread (ns per pixel per core); the core functions, not the Filter wrappers (no
// deep EXR decode in the timing). The machine may be shared: run with
// --benchmark_repetitions=3 and read the minimum; sheared4d at 256x256, width 32 takes seconds
// per iteration.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "filters/lightfield/aaf.h"
#include "filters/lightfield/sheared.h"
#include "filters/lightfield/sheared4d.h"

namespace {

const mcr::LightField& field(int size, int l) {
  static std::map<std::pair<int, int>, mcr::LightField> cache;
  auto it = cache.find({size, l});
  if (it != cache.end()) return it->second;
  mcr::LightField lf;
  lf.effect = mcr::LightFieldEffect::Dof;
  lf.width = lf.height = size;
  lf.l = l;
  lf.y_range = 1;
  lf.sigma_y = 0.5f;
  const std::size_t n = std::size_t(size) * std::size_t(size), s = n * std::size_t(l * l);
  for (auto* v : {&lf.r, &lf.g, &lf.b, &lf.y1, &lf.y2}) v->assign(s, 0.0f);
  for (auto* v : {&lf.smin, &lf.smax, &lf.depth, &lf.e1y, &lf.e2x}) v->assign(n, 0.0f);
  lf.e1x.assign(n, 1.0f);
  lf.e2y.assign(n, 1.0f);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float cell = 2.0f / float(l);
  for (std::size_t p = 0; p < n; ++p) {
    const int x = int(p % std::size_t(size)), y = int(p / std::size_t(size));
    lf.smin[p] = 6.0f + 0.5f * std::sin(0.05f * float(x));
    lf.smax[p] = 8.0f + 0.5f * std::cos(0.04f * float(y));
    const float o1 = u(rng), o2 = u(rng);  // uniform jittered: one offset per pixel
    for (int k = 0; k < l * l; ++k) {
      const std::size_t i = p * std::size_t(l * l) + std::size_t(k);
      lf.y1[i] = -1.0f + (float(k % l) + o1) * cell;
      lf.y2[i] = -1.0f + (float(k / l) + o2) * cell;
      const float v = (lf.y1[i] + 0.1f * float(x % 37) - 1.5f > 0) ? 1.0f : 0.1f;
      lf.r[i] = v;
      lf.g[i] = 0.5f * v;
      lf.b[i] = 0.25f + 0.1f * lf.y2[i];
    }
  }
  return cache.emplace(std::make_pair(size, l), std::move(lf)).first->second;
}

using Core = void (*)(const mcr::LightField&, const mcr::lf::Options&, const mcr::Roi&, int, mcr::Image&,
                      mcr::lf::Counts*);

void run(benchmark::State& state, Core core) {
  const int size = int(state.range(0)), l = int(state.range(1));
  mcr::lf::Options o;
  o.max_width = int(state.range(2));
  o.mu = 0.1f;  // aaf only: the sheared filters' own rule takes every pixel here
  const mcr::LightField& lf = field(size, l);
  mcr::Image out(size, size, 3);
  for (auto _ : state) {
    core(lf, o, mcr::Roi::all(size, size), 1, out, nullptr);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["ns/pixel"] = benchmark::Counter(double(size) * double(size) * 1e-9,
                                                  benchmark::Counter::kIsIterationInvariantRate |
                                                      benchmark::Counter::kInvert);
}

void grid(benchmark::internal::Benchmark* b) {
  for (int size : {128, 256})
    for (int l : {2, 3, 4})
      for (int width : {8, 16, 32}) b->Args({size, l, width});
  b->ArgNames({"size", "l", "max_width"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK_CAPTURE(run, sheared, &mcr::sheared_lightfield)->Apply(grid);
BENCHMARK_CAPTURE(run, sheared4d, &mcr::sheared4d_lightfield)->Apply(grid);
BENCHMARK_CAPTURE(run, aaf, &mcr::aaf_lightfield)->Apply(grid);
