#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>

#include "commands.h"
#include "io/atomic_write.h"
#include "io/preview.h"
#include "io/sample_manifest.h"
#include "json_views.h"
#include "pipeline/evaluate.h"
#include "pipeline/filter_catalog.h"
#include "progress.h"
#include "util/error.h"
#include "validators.h"

namespace mcr::cli {

namespace {

struct DemoArgs {
  std::string samples, out = "demo_out";
  std::vector<int> spp = {16};
  std::vector<std::string> filters;
  int threads = 0;
  bool json = false;
  bool spp_given = false;
};

struct Row {
  std::string scene, input, filter;
  Evaluation ev;
};

void print_row(const Row& r, bool timed) {
  char secs[32] = "-";
  if (timed) std::snprintf(secs, sizeof secs, "%.4f", r.ev.seconds);
  char temporal[32] = "-";
  if (r.ev.temporal_error >= 0) std::snprintf(temporal, sizeof temporal, "%.5f", r.ev.temporal_error);
  std::printf("%-8s %-9s %-14s %9s %10.5f %8.3f %7.4f %9s\n", r.scene.c_str(), r.input.c_str(), r.filter.c_str(), secs,
              r.ev.metrics.relmse, r.ev.metrics.psnr, r.ev.metrics.ssim, temporal);
  std::fflush(stdout);
}

// Every --spp level must be one some scene has: a level none has would run nothing.
void check_spp(const std::vector<int>& spp, const std::vector<SampleScene>& scenes, const std::string& dir) {
  std::set<int> levels;
  for (const SampleScene& s : scenes)
    for (const auto& [n, path] : s.noisy) levels.insert(n);
  for (int n : spp) {
    if (levels.count(n)) continue;
    std::string have;
    for (int l : levels) have += (have.empty() ? "" : ", ") + std::to_string(l);
    throw Error(Errc::InvalidArgument, "--spp " + std::to_string(n) + ": no sample scene in '" + dir + "' has " +
                                           std::to_string(n) + " spp; the levels there are " + have);
  }
}

int run_demo(const DemoArgs& a) {
  const std::string dir = a.samples.empty() ? default_samples_dir() : a.samples;
  const std::vector<SampleScene> scenes = load_sample_manifest(dir);
  std::vector<std::string> filters = a.filters.empty() ? catalog_names() : a.filters;
  for (const auto& f : filters) catalog_info(f);  // unknown names fail before any work
  if (a.spp_given) check_spp(a.spp, scenes, dir);
  std::filesystem::create_directories(a.out);

  std::printf("%-8s %-9s %-14s %9s %10s %8s %7s %9s\n", "scene", "input", "filter", "seconds", "relMSE", "PSNR", "SSIM",
              "temporal");
  nlohmann::json report = nlohmann::json::array();
  for (const SampleScene& scene : scenes) {
    // Sequences are denoised at their lowest spp (1 spp, as real-time filters get).
    std::vector<int> spps = a.spp;
    if (scene.is_sequence() && !a.spp_given && !scene.noisy.empty()) spps = {scene.noisy.begin()->first};
    for (int spp : spps) {
      if (!scene.noisy.count(spp)) continue;
      Progress load_progress("load " + scene.name, scene.is_sequence() ? scene.last_frame - scene.first_frame + 1 : 1);
      const LoadedScene loaded = load_scene(scene, spp, [&](int d, int) { load_progress.step(d, ""); });
      load_progress.finish();
      const std::string input = std::to_string(spp) + "spp";
      std::vector<Row> rows;
      rows.push_back({scene.name, input, "(noisy)", evaluate(loaded, nullptr, a.threads)});
      print_row(rows.back(), false);
      // The same scene at 4x the samples: what a filter must beat to be "worth 4x".
      if (scene.noisy.count(spp * 4)) {
        const LoadedScene more = load_scene(scene, spp * 4);
        rows.push_back({scene.name, std::to_string(spp * 4) + "spp", "(noisy)", evaluate(more, nullptr, a.threads)});
        print_row(rows.back(), false);
      }
      for (const auto& name : filters) {
        auto filter = make_catalog_filter(name);
        filter->commit();
        if (!filter->missing_passes(loaded.frames.front()).empty()) continue;
        if (filter->info().deep_input && !loaded.frames.front().deep) continue;  // per-sample scenes only
        Progress progress(scene.name + " " + name, int(loaded.frames.size()));
        Row row{scene.name, input, name, evaluate(loaded, filter.get(), a.threads, [&](int d, int) { progress.step(d, ""); })};
        progress.finish();
        rows.push_back(std::move(row));
        print_row(rows.back(), true);
      }
      // Pointers into `rows` only now that it has stopped growing.
      std::vector<const Image*> tiles = {&rows.front().ev.preview};
      std::string legend = "noisy " + input;
      for (const Row& r : rows)
        if (r.filter != "(noisy)") {
          tiles.push_back(&r.ev.preview);
          legend += " | " + r.filter;
        }
      const std::size_t mid = loaded.references.size() / 2;
      tiles.push_back(&loaded.references[mid]);
      legend += " | reference " + std::to_string(scene.reference_spp) + "spp";
      const std::string png = (std::filesystem::path(a.out) / (scene.name + "_" + input + ".png")).string();
      write_side_by_side_png(png, tiles);
      std::fprintf(stderr, "wrote %s (%s)\n", png.c_str(), legend.c_str());
      for (const Row& r : rows)
        report.push_back({{"scene", r.scene},
                          {"input", r.input},
                          {"filter", r.filter},
                          {"seconds", r.filter == "(noisy)" ? nlohmann::json(nullptr) : nlohmann::json(r.ev.seconds)},
                          {"relmse", number(r.ev.metrics.relmse)},
                          {"rmse", number(r.ev.metrics.rmse)},
                          {"psnr", number(r.ev.metrics.psnr)},
                          {"ssim", number(r.ev.metrics.ssim)},
                          {"temporal_error", r.ev.temporal_error >= 0 ? nlohmann::json(r.ev.temporal_error) : nlohmann::json(nullptr)}});
    }
  }
  const std::string json_path = (std::filesystem::path(a.out) / "results.json").string();
  write_text_atomic(report.dump(2) + "\n", json_path);
  std::fprintf(stderr, "wrote %s\n", json_path.c_str());
  if (a.json) std::cout << report.dump(2) << "\n";
  return 0;
}

}  // namespace

Run add_demo(CLI::App& app) {
  auto a = std::make_shared<DemoArgs>();
  app.add_option("--samples", a->samples, "sample data directory with manifest.json (default: the repo's samples/data)");
  app.add_option("-o,--out", a->out, "directory for side-by-side PNGs and results.json");
  app.add_option_function<std::vector<int>>(
      "--spp", [a](const std::vector<int>& v) { a->spp = v; a->spp_given = true; },
      "input sample counts to denoise (default: 16 for stills, the lowest for sequences)")
      ->check(whole_number(1));
  app.add_option("--filters", a->filters, "filters to run (default: all, auto included)");
  add_threads_option(app, a->threads);
  app.add_flag("--json", a->json, "also print the table as JSON");
  return [a] { return run_demo(*a); };
}

}  // namespace mcr::cli
