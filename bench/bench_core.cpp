// Core costs at 1280x720 on a synthetic Blender-like frame: the box filter (the
// floor any filter adds to), metrics, and EXR read/write (the I/O floor).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <random>

#include "filters/registry.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "metrics/metrics.h"

namespace {

constexpr int kW = 1280, kH = 720;

mcr::Image noise_image(int channels, unsigned seed) {
  mcr::Image img(kW, kH, channels);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float& v : img.storage()) v = u(rng);
  return img;
}

mcr::Frame synthetic_frame() {
  mcr::Frame f;
  f.width = kW;
  f.height = kH;
  f.path = "synthetic";
  mcr::Pass colour;
  colour.role = mcr::Role::Colour;
  colour.name = "ViewLayer.Combined";
  colour.channels = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B"};
  colour.image = noise_image(3, 1);
  f.passes.push_back(colour);
  return f;
}

void BM_box(benchmark::State& state) {
  const mcr::Frame frame = synthetic_frame();
  auto filter = mcr::make_filter("box");
  filter->set("radius", std::int64_t(state.range(0)));
  filter->commit();
  mcr::ExecOptions opt;
  opt.nthreads = int(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(filter->execute(frame, opt));
  state.SetItemsProcessed(state.iterations() * kW * kH);
}
BENCHMARK(BM_box)->ArgsProduct({{1, 2, 4, 8}, {1, 2}})->ArgNames({"radius", "threads"})->Unit(benchmark::kMillisecond);

void BM_compare_images(benchmark::State& state) {
  const mcr::Image a = noise_image(3, 2), b = noise_image(3, 3);
  for (auto _ : state) benchmark::DoNotOptimize(mcr::compare_images(a, b, int(state.range(0))));
}
BENCHMARK(BM_compare_images)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond);

// Write then read an RGBA float EXR of the result size: what any filter's
// end-to-end time is bounded below by.
void BM_exr_write(benchmark::State& state) {
  const mcr::Frame frame = synthetic_frame();
  const mcr::Image rgb = frame.image(mcr::Role::Colour);
  const std::string path = (std::filesystem::temp_directory_path() / "mcrecon_bench_io.exr").string();
  for (auto _ : state) mcr::write_result(path, rgb, frame);
  std::filesystem::remove(path);
}
BENCHMARK(BM_exr_write)->Unit(benchmark::kMillisecond);

void BM_exr_read(benchmark::State& state) {
  const mcr::Frame frame = synthetic_frame();
  const std::string path = (std::filesystem::temp_directory_path() / "mcrecon_bench_read.exr").string();
  mcr::write_result(path, frame.image(mcr::Role::Colour), frame);
  for (auto _ : state) benchmark::DoNotOptimize(mcr::read_frame(path));
  std::filesystem::remove(path);
}
BENCHMARK(BM_exr_read)->Unit(benchmark::kMillisecond);

}  // namespace
