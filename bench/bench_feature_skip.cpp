// Skipping what a scene doesn't need (kernels/feature_activity.h): each feature-aware
// filter at 1024x1024 on a textured flat wall facing the camera (one normal, one
// depth everywhere; positions spread over the wall; noisy colour), against the same
// frame whose normal and depth carry a faint ripple (0.01 in the normal, 0.001 in the
// depth: over the tolerance, so the passes are used, yet too small to change the
// result). Arg 0: wall (constant passes, dropped), 1: ripple (the same passes, used).
// Counter relmse: against the noise-free colour, equal on both rows (the time saved
// costs no error). Threads = 2. Wall clock (UseRealTime); on a shared machine run with
// --benchmark_repetitions=N and read the _min rows.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "filters/registry.h"
#include "metrics/metrics.h"

namespace {

constexpr int kSize = 1024;
constexpr int kThreads = 2;

struct Wall {
  mcr::Frame frame;
  mcr::Image clean;
};

Wall make_wall(bool ripple) {
  Wall w;
  mcr::Frame& f = w.frame;
  f.width = f.height = kSize;
  f.path = ripple ? "ripple" : "wall";
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0f, 0.15f);
  mcr::Image colour(kSize, kSize, 3), normal(kSize, kSize, 3), position(kSize, kSize, 3), albedo(kSize, kSize, 3),
      depth(kSize, kSize, 1);
  w.clean = mcr::Image(kSize, kSize, 3);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const float r = ripple ? std::sin(0.05f * float(x)) * std::cos(0.07f * float(y)) : 0.0f;
      normal.at(x, y, 0) = 0.01f * r;
      normal.at(x, y, 1) = 0.0f;
      normal.at(x, y, 2) = 1.0f;
      depth.at(x, y, 0) = 5.0f + 0.001f * r;
      position.at(x, y, 0) = 0.004f * float(x);
      position.at(x, y, 1) = 0.004f * float(y);
      position.at(x, y, 2) = 5.0f;
      // A plaster texture lit by a soft gradient.
      const float tex = 0.55f + 0.25f * std::sin(0.02f * float(x) + 0.3f * std::sin(0.015f * float(y)));
      const float light = 0.6f + 0.4f * float(x + y) / float(2 * kSize);
      for (int c = 0; c < 3; ++c) {
        albedo.at(x, y, c) = tex * (0.9f + 0.05f * float(c));
        const float v = albedo.at(x, y, c) * light;
        w.clean.at(x, y, c) = v;
        colour.at(x, y, c) = std::max(0.0f, v * (1.0f + noise(rng)));
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
  return w;
}

// The colour is the same noisy image in both (same seed, same texture).
const Wall& wall(bool ripple) {
  static const Wall walls[2] = {make_wall(false), make_wall(true)};
  return walls[ripple ? 1 : 0];
}

double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

void common(benchmark::internal::Benchmark* b) {
  b->Arg(0)->Arg(1)->ArgName("ripple");
  b->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->ComputeStatistics("min", min_of);
}

void run(benchmark::State& state, const char* name, std::vector<std::pair<const char*, mcr::ParamValue>> params) {
  auto filter = mcr::make_filter(name);
  for (auto& [k, v] : params) filter->set(k, v);
  filter->commit();
  const Wall& w = wall(state.range(0) != 0);
  mcr::ExecOptions opt;
  opt.nthreads = kThreads;
  mcr::Image out = filter->execute(w.frame, opt);  // warm-up: scratch allocated once, as for a video
  for (auto _ : state) {
    out = filter->execute(w.frame, opt);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["relmse"] = mcr::relmse(w.clean, out, kThreads);
  state.counters["skipped"] = double(std::count_if(filter->notes().begin(), filter->notes().end(), [](const std::string& n) {
    return n.find("pass is constant") != std::string::npos;
  }));
  state.SetItemsProcessed(state.iterations() * std::int64_t(kSize) * kSize);
}

// Normal, position and depth weights (depth on): the wall drops normal and depth.
void BM_skip_bilateral(benchmark::State& state) {
  run(state, "bilateral", {{"use_depth", std::string("on")}, {"colour_sigma", 0.3}, {"spatial_sigma", 2.0}});
}
BENCHMARK(BM_skip_bilateral)->Apply(common);

void BM_skip_atrous(benchmark::State& state) {
  run(state, "atrous", {{"use_depth", std::string("on")}, {"colour_sigma", 0.3}});
}
BENCHMARK(BM_skip_atrous)->Apply(common);

// Guide normal + position (6 channels): the wall drops the normal (3 channels).
void BM_skip_guided(benchmark::State& state) {
  run(state, "guided", {{"guide", std::string("normal_position")}});
}
BENCHMARK(BM_skip_guided)->Apply(common);

// Gn and Gsp (first-hit position): the wall drops Gn.
void BM_skip_pwaf(benchmark::State& state) { run(state, "pwaf", {}); }
BENCHMARK(BM_skip_pwaf)->Apply(common);

// Default features [1, n, w, w^2] (10 columns): the wall drops the 3 normal columns.
// Every execute is the next frame of a still sequence (the history is kept).
void BM_skip_bmfr(benchmark::State& state) { run(state, "bmfr", {}); }
BENCHMARK(BM_skip_bmfr)->Apply(common);

}  // namespace

BENCHMARK_MAIN();
