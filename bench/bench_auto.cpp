// `auto` against the filter it picks: run time and relMSE per still sample scene, each
// frame tiled 4 x 4 (256x192 -> 1024x768, 0.79 megapixel) so that the times are per
// megapixel at a realistic size; best of --repeat runs at --threads threads.
//   mcrecon_bench_auto [--spp 16] [--threads 2] [--repeat 3] [--scenes a,b]
// Then the skip row: `wall` with its constant normal and depth passes as rendered,
// against the same frame with a faint ripple in them (over the skip tolerance, so they
// are used): auto's time at equal error (issue 14, point 4). Last, on the scenes with half
// buffers: auto and every filter at full size on the 16-spp file (noise estimated from the
// image) against the mean of its two halves (noise from their difference).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "filters/registry.h"
#include "io/frame_reader.h"
#include "io/half_buffers.h"
#include "io/sample_manifest.h"
#include "metrics/metrics.h"
#include "pipeline/auto_filter.h"
#include "pipeline/evaluate.h"
#include "pipeline/filter_catalog.h"
#include "sweeps.h"

namespace {

constexpr int kTiles = 4;

mcr::Image tile_image(const mcr::Image& im) {
  mcr::Image out(im.width() * kTiles, im.height() * kTiles, im.channels());
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) {
      // Mirrored copies: no seams for the filters to find.
      const int tx = x / im.width(), ty = y / im.height();
      int sx = x % im.width(), sy = y % im.height();
      if (tx % 2) sx = im.width() - 1 - sx;
      if (ty % 2) sy = im.height() - 1 - sy;
      std::copy(im.pixel(sx, sy), im.pixel(sx, sy) + im.channels(), out.pixel(x, y));
    }
  return out;
}

mcr::Frame tile_frame(const mcr::Frame& f) {
  mcr::Frame t = f;
  t.width = f.width * kTiles;
  t.height = f.height * kTiles;
  for (mcr::Pass& p : t.passes) p.image = tile_image(p.image);
  return t;
}

struct Run {
  double seconds = 1e300;
  double relmse = 0;
  std::string chosen;
};

Run time_filter(const std::string& name, const mcr::Frame& frame, const mcr::Image& ref, int threads, int repeat) {
  Run r;
  for (int k = 0; k < repeat; ++k) {
    auto f = mcr::make_catalog_filter(name);
    f->commit();
    mcr::ExecOptions eo;
    eo.nthreads = threads;
    const auto t0 = std::chrono::steady_clock::now();
    const mcr::Image out = f->execute(frame, eo);
    r.seconds = std::min(r.seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    r.relmse = mcr::relmse(ref, out, threads);
    if (auto* a = dynamic_cast<mcr::AutoFilter*>(f.get())) r.chosen = a->chosen();
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int spp = 16, threads = 2, repeat = 3;
  std::vector<std::string> scenes_wanted;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) { std::fprintf(stderr, "%s needs a value\n", a.c_str()); std::exit(2); }
      return argv[++i];
    };
    if (a == "--spp") spp = std::stoi(next());
    else if (a == "--threads") threads = std::stoi(next());
    else if (a == "--repeat") repeat = std::stoi(next());
    else if (a == "--scenes") scenes_wanted = mcr::bench::split_list(next());
    else { std::fprintf(stderr, "unknown option %s\n", a.c_str()); return 2; }
  }
  std::printf("%-9s %-6s %-10s %9s %9s %10s\n", "scene", "split", "filter", "s", "s/MP", "relMSE");
  for (const mcr::SampleScene& scene : mcr::load_sample_manifest(mcr::default_samples_dir())) {
    if (scene.is_sequence() || !scene.noisy.count(spp) || !mcr::bench::wanted(scenes_wanted, scene.name)) continue;
    const mcr::LoadedScene loaded = mcr::load_scene(scene, spp);
    const mcr::Frame frame = tile_frame(loaded.frames.front());
    const mcr::Image ref = tile_image(loaded.references.front());
    const double mp = double(frame.width) * frame.height / 1e6;
    std::printf("%-9s %-6s %-10s %9s %9s %10.5f\n", scene.name.c_str(), scene.split.c_str(), "(noisy)", "-", "-",
                mcr::relmse(ref, frame.image(mcr::Role::Colour).channel_range(0, 3), threads));
    const Run a = time_filter("auto", frame, ref, threads, repeat);
    // What auto picked: one filter, or two ("a+b", the mean of their results) whose times add.
    const std::vector<std::string> picks = mcr::bench::split_list(a.chosen, '+');
    double picked = 0;
    for (const std::string& name : mcr::image_filter_names()) {
      if (mcr::filter_info(name).temporal || mcr::filter_info(name).deep_input) continue;
      const Run r = time_filter(name, frame, ref, threads, repeat);
      if (std::find(picks.begin(), picks.end(), name) != picks.end()) picked += r.seconds;
      std::printf("%-9s %-6s %-10s %9.4f %9.4f %10.5f\n", scene.name.c_str(), scene.split.c_str(), name.c_str(), r.seconds,
                  r.seconds / mp, r.relmse);
    }
    std::printf("%-9s %-6s %-10s %9.4f %9.4f %10.5f   chose %s: %.2fx its time\n", scene.name.c_str(), scene.split.c_str(),
                "auto", a.seconds, a.seconds / mp, a.relmse, a.chosen.c_str(), picked > 0 ? a.seconds / picked : 0.0);
    if (scene.name == "wall") {
      mcr::Frame ripple = frame;
      for (mcr::Pass& p : ripple.passes) {
        if (p.role != mcr::Role::Normal && p.role != mcr::Role::Depth) continue;
        for (int y = 0; y < ripple.height; ++y)
          for (int x = 0; x < ripple.width; ++x)
            p.image.at(x, y, 0) += (p.role == mcr::Role::Normal ? 0.01f : 0.001f) * std::sin(0.05f * x) * std::cos(0.07f * y);
      }
      const Run b = time_filter("auto", ripple, ref, threads, repeat);
      std::printf("%-9s %-6s %-10s %9.4f %9.4f %10.5f   (normal/depth rippled, so used): chose %s\n", "wall", scene.split.c_str(),
                  "auto", b.seconds, b.seconds / mp, b.relmse, b.chosen.c_str());
    }
  }
  std::printf("\nHalf buffers (%d spp, full size): noise from the image alone | from the halves' difference\n", spp);
  for (const mcr::SampleScene& scene : mcr::load_sample_manifest(mcr::default_samples_dir())) {
    if (!scene.halves.count(spp) || !mcr::bench::wanted(scenes_wanted, scene.name)) continue;
    const mcr::Frame single = mcr::read_frame(scene.noisy.at(spp));
    const mcr::Frame halves = mcr::combine_halves(mcr::read_frame(scene.halves.at(spp).first),
                                                  mcr::read_frame(scene.halves.at(spp).second));
    const mcr::Image ref = mcr::read_frame(scene.reference).image(mcr::Role::Colour).channel_range(0, 3);
    for (const std::string& name : mcr::catalog_names()) {
      if (mcr::catalog_info(name).temporal || mcr::catalog_info(name).deep_input) continue;  // stills, flat
      const Run a = time_filter(name, single, ref, threads, 1), b = time_filter(name, halves, ref, threads, 1);
      std::printf("%-9s %-10s %10.5f %10.5f %s%s\n", scene.name.c_str(), name.c_str(), a.relmse, b.relmse,
                  a.chosen.empty() ? "" : ("chose " + a.chosen + " | " + b.chosen).c_str(), "");
    }
  }
  return 0;
}
