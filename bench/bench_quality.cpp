// Run time against error on the sample scenes: every registered filter, a sweep
// of its main parameter (bench/sweeps.cpp), with and without albedo
// demodulation, under the defaults, firefly_k=2, firefly_k=1 and the filter's own variants,
// against the noisy input and the same scene at 4x the samples. Then `auto`.
// The summary never scores a setting on the scene it was chosen on: each filter's best
// setting is chosen on the manifest's "tune" scenes (lowest mean log relMSE over them)
// and reported on the "report" scenes, beside the defaults and `auto`.
//   mcrecon_bench_quality [--spp 16] [--scenes room,glossy] [--filters a,b] [--threads N] [--json FILE]
#include <cstdio>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "filters/registry.h"
#include "pipeline/filter_catalog.h"
#include "io/sample_manifest.h"
#include "pipeline/evaluate.h"
#include "sweeps.h"
#include "util/error.h"

namespace {


struct Best {
  std::string setting;
  mcr::Evaluation ev;
};

}  // namespace

int main(int argc, char** argv) {
  int spp = 16, threads = 0;
  std::vector<std::string> scenes_wanted, filters_wanted;
  std::string json_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) { std::fprintf(stderr, "%s needs a value\n", a.c_str()); std::exit(2); }
      return argv[++i];
    };
    if (a == "--spp") spp = std::stoi(next());
    else if (a == "--threads") threads = std::stoi(next());
    else if (a == "--scenes") scenes_wanted = mcr::bench::split_list(next());
    else if (a == "--filters") filters_wanted = mcr::bench::split_list(next());
    else if (a == "--json") json_path = next();
    else { std::fprintf(stderr, "unknown option %s\n", a.c_str()); return 2; }
  }
  try {
    nlohmann::json rows = nlohmann::json::array();
    std::printf("%-8s %-10s %-50s %10s %10s %8s %7s\n", "scene", "filter", "setting", "ms", "relMSE", "PSNR", "SSIM");
    std::map<std::string, std::vector<std::pair<std::string, Best>>> summary;
    // filter -> setting -> scene -> evaluation; scene -> split.
    std::map<std::string, std::map<std::string, std::map<std::string, mcr::Evaluation>>> all;
    std::map<std::string, std::string> split;
    std::vector<std::string> order;
    std::map<std::string, std::pair<mcr::ImageMetrics, mcr::ImageMetrics>> noisy;
    for (const mcr::SampleScene& scene : mcr::load_sample_manifest(mcr::default_samples_dir())) {
      if (scene.is_sequence() || !scene.noisy.count(spp) || !mcr::bench::wanted(scenes_wanted, scene.name)) continue;
      const mcr::LoadedScene loaded = mcr::load_scene(scene, spp);
      const mcr::Evaluation base = mcr::evaluate(loaded, nullptr, threads);
      mcr::Evaluation more = base;
      if (scene.noisy.count(spp * 4)) more = mcr::evaluate(mcr::load_scene(scene, spp * 4), nullptr, threads);
      noisy[scene.name] = {base.metrics, more.metrics};
      split[scene.name] = scene.split;
      std::printf("%-8s %-10s %-50s %10s %10.5f %8.3f %7.4f\n", scene.name.c_str(), "(noisy)", (std::to_string(spp) + " spp").c_str(), "-",
                  base.metrics.relmse, base.metrics.psnr, base.metrics.ssim);
      std::printf("%-8s %-10s %-50s %10s %10.5f %8.3f %7.4f\n", scene.name.c_str(), "(noisy)", (std::to_string(spp * 4) + " spp").c_str(), "-",
                  more.metrics.relmse, more.metrics.psnr, more.metrics.ssim);
      for (const std::string& name : mcr::image_filter_names()) {
        if (!mcr::bench::wanted(filters_wanted, name)) continue;
        const mcr::FilterInfo& info = mcr::filter_info(name);
        if (info.temporal) continue;  // sequences have their own benchmark
        const mcr::bench::Sweep& sweep = mcr::bench::sweep_for(name);
        std::vector<double> values = sweep.values;
        if (values.empty() || sweep.param.empty()) values = {std::nan("")};
        Best best{"", {}};
        best.ev.metrics.relmse = 1e300;
        // Variants: the defaults, firefly suppression (a common parameter), the filter's own.
        const std::vector<std::string> variants = mcr::bench::sweep_variants(name);
        for (const std::string& variant : variants)
        for (bool demod : {false, true}) {
          if (demod && !loaded.frames.front().has(mcr::Role::Albedo)) continue;
          for (double v : values) {
            auto filter = mcr::make_filter(name);
            std::string setting = demod ? "demod " : "";
            const std::string given = mcr::bench::apply_variant(*filter, variant);
            if (!given.empty()) setting += given + " ";
            if (!std::isnan(v)) {
              filter->set(sweep.param, v);
              setting += sweep.param + "=" + mcr::param_value_text(filter->params().values().at(sweep.param));
            } else {
              setting += "defaults";
            }
            if (demod && !filter->params().has("demodulate")) break;
            if (demod) filter->set("demodulate", true);
            filter->commit();
            if (!filter->missing_passes(loaded.frames.front()).empty()) break;
            // Best of 3 runs for the time; the error is deterministic.
            mcr::Evaluation ev = mcr::evaluate(loaded, filter.get(), threads);
            for (int rep = 0; rep < 2; ++rep) ev.seconds = std::min(ev.seconds, mcr::evaluate(loaded, filter.get(), threads).seconds);
            std::printf("%-8s %-10s %-50s %10.2f %10.5f %8.3f %7.4f\n", scene.name.c_str(), name.c_str(), setting.c_str(),
                        ev.seconds * 1e3, ev.metrics.relmse, ev.metrics.psnr, ev.metrics.ssim);
            std::fflush(stdout);
            rows.push_back({{"scene", scene.name}, {"filter", name}, {"setting", setting}, {"ms", ev.seconds * 1e3},
                            {"relmse", ev.metrics.relmse}, {"psnr", ev.metrics.psnr}, {"ssim", ev.metrics.ssim}});
            if (ev.metrics.relmse < best.ev.metrics.relmse) best = {setting, ev};
            all[name][setting][scene.name] = ev;
            if (std::find(order.begin(), order.end(), name) == order.end()) order.push_back(name);
          }
        }
        if (!best.setting.empty()) summary[scene.name].push_back({name, best});
      }
      if (mcr::bench::wanted(filters_wanted, "auto")) {
        auto a = mcr::make_catalog_filter("auto");
        a->commit();
        mcr::Evaluation ev = mcr::evaluate(loaded, a.get(), threads);
        for (int rep = 0; rep < 2; ++rep) ev.seconds = std::min(ev.seconds, mcr::evaluate(loaded, a.get(), threads).seconds);
        std::printf("%-8s %-10s %-50s %10.2f %10.5f %8.3f %7.4f\n", scene.name.c_str(), "auto", "defaults", ev.seconds * 1e3,
                    ev.metrics.relmse, ev.metrics.psnr, ev.metrics.ssim);
        rows.push_back({{"scene", scene.name}, {"filter", "auto"}, {"setting", "defaults"}, {"ms", ev.seconds * 1e3},
                        {"relmse", ev.metrics.relmse}, {"psnr", ev.metrics.psnr}, {"ssim", ev.metrics.ssim}});
        all["auto"]["defaults"][scene.name] = ev;
        if (std::find(order.begin(), order.end(), "auto") == order.end()) order.push_back("auto");
      }
    }
    // Settings chosen on the tune scenes, reported on the others.
    std::printf("\nChosen on the tune scenes (lowest mean log relMSE there), reported on the report scenes, at %d spp:\n", spp);
    std::printf("%-8s %-10s %-50s %10s %10s %7s %10s %10s\n", "scene", "filter", "setting", "ms", "relMSE", "SSIM", "<=input", "<=4x spp");
    std::map<std::string, std::string> chosen;
    for (const auto& [name, settings] : all) {
      double best_score = 1e300;
      for (const auto& [setting, scenes] : settings) {
        double sum = 0;
        int n = 0;
        for (const auto& [scene, ev] : scenes)
          if (split[scene] == "tune") {
            sum += std::log(std::max(ev.metrics.relmse, 1e-30) / std::max(noisy[scene].first.relmse, 1e-30));
            ++n;
          }
        if (n && sum / n < best_score) best_score = sum / n, chosen[name] = setting;
      }
    }
    for (const auto& [scene, sp] : split) {
      if (sp != "report") continue;
      const auto& [base, more] = noisy[scene];
      std::printf("%-8s %-10s %-50s %10s %10.5f %7.4f\n", scene.c_str(), "(noisy)", "", "-", base.relmse, base.ssim);
      std::printf("%-8s %-10s %-50s %10s %10.5f %7.4f\n", scene.c_str(), "(noisy4x)", "", "-", more.relmse, more.ssim);
      for (const std::string& name : order)
        for (const std::string& setting : {std::string("defaults"), chosen.count(name) ? chosen[name] : std::string()}) {
          if (setting.empty() || !all[name].count(setting) || !all[name][setting].count(scene)) continue;
          const mcr::Evaluation& ev = all[name][setting][scene];
          std::printf("%-8s %-10s %-50s %10.2f %10.5f %7.4f %10s %10s\n", scene.c_str(), name.c_str(),
                      (setting == "defaults" ? "defaults" : "tuned: " + setting).c_str(), ev.seconds * 1e3, ev.metrics.relmse,
                      ev.metrics.ssim, ev.metrics.relmse <= base.relmse ? "yes" : "NO",
                      ev.metrics.relmse <= more.relmse ? "yes" : "no");
          if (chosen.count(name) && chosen[name] == "defaults") break;
        }
    }
    std::printf("\nBest setting per filter per scene, chosen on that scene (optimistic: for comparison only) at %d spp against the noisy %d-spp render:\n", spp, spp * 4);
    std::printf("%-8s %-10s %-50s %10s %10s %7s %12s %10s\n", "scene", "filter", "setting", "ms", "relMSE", "SSIM", "relMSE<=4x", "SSIM>4x");
    for (const auto& [scene, list] : summary) {
      const auto& [base, more] = noisy[scene];
      std::printf("%-8s %-10s %-50s %10s %10.5f %7.4f\n", scene.c_str(), "(noisy4x)", "", "-", more.relmse, more.ssim);
      for (const auto& [name, b] : list)
        std::printf("%-8s %-10s %-50s %10.2f %10.5f %7.4f %12s %10s\n", scene.c_str(), name.c_str(), b.setting.c_str(),
                    b.ev.seconds * 1e3, b.ev.metrics.relmse, b.ev.metrics.ssim, b.ev.metrics.relmse <= more.relmse ? "yes" : "no",
                    b.ev.metrics.ssim > more.ssim ? "yes" : "no");
    }
    if (!json_path.empty()) std::ofstream(json_path) << rows.dump(2) << "\n";
  } catch (const mcr::Error& e) {
    std::fprintf(stderr, "mcrecon_bench_quality: %s\n", e.what());
    return 2;
  }
  return 0;
}
