// Hashes of every filter's output on every sample scene, for its defaults and every
// benchmark sweep setting (bench/sweeps.cpp): one line "scene filter setting hash" each.
// A refactoring that promises the same results must print the same lines: compare with
// bench/check_output_hashes.sh. The hash is FNV-1a over the float bits of the RGB result
// (every frame of a sequence, in order).
//   mcrecon_output_hashes [--scenes a,b] [--filters a,b] [--threads N]
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "filters/registry.h"
#include "io/sample_manifest.h"
#include "pipeline/evaluate.h"
#include "sweeps.h"
#include "pipeline/reconstruction.h"
#include "util/error.h"
#include "util/isa.h"

namespace {


struct Fnv {
  std::uint64_t h = 1469598103934665603ull;
  void add(const mcr::Image& im) {
    for (float f : im.storage()) {
      std::uint32_t u;
      std::memcpy(&u, &f, 4);
      for (int b = 0; b < 4; ++b) {
        h ^= (u >> (8 * b)) & 0xffu;
        h *= 1099511628211ull;
      }
    }
  }
};

// The filter alone, or after the pipeline's accumulation stage (as --accumulate runs it).
std::string hash_of(const mcr::LoadedScene& scene, std::unique_ptr<mcr::Filter> filter, bool accumulate, int threads) {
  mcr::Reconstruction rec(std::move(filter), accumulate);
  rec.reset();
  Fnv fnv;
  mcr::ExecOptions eo;
  eo.nthreads = threads;
  for (const mcr::Frame& frame : scene.frames) fnv.add(rec.run(frame, eo));
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv.h));
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 0;
  std::vector<std::string> scenes_wanted, filters_wanted;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) { std::fprintf(stderr, "%s needs a value\n", a.c_str()); return 2; }
    const std::string v = argv[++i];
    if (a == "--threads") threads = std::stoi(v);
    else if (a == "--scenes") scenes_wanted = mcr::bench::split_list(v);
    else if (a == "--filters") filters_wanted = mcr::bench::split_list(v);
    else { std::fprintf(stderr, "unknown option %s\n", a.c_str()); return 2; }
  }
  try {
    std::printf("isa %s\n", mcr::isa_name(mcr::isa()));
    for (const mcr::SampleScene& scene : mcr::load_sample_manifest(mcr::default_samples_dir())) {
      if (!mcr::bench::wanted(scenes_wanted, scene.name)) continue;
      const int spp = scene.is_sequence() ? scene.noisy.begin()->first : 16;
      const mcr::LoadedScene loaded = mcr::load_scene(scene, spp);
      for (const std::string& name : mcr::image_filter_names()) {
        if (!mcr::bench::wanted(filters_wanted, name)) continue;
        const mcr::FilterInfo& info = mcr::filter_info(name);
        // Temporal filters run on sequences; image filters on stills with their whole sweep,
        // on sequences with their defaults, alone and after accumulation.
        if (info.temporal != scene.is_sequence() && info.temporal) continue;
        const mcr::bench::Sweep& sweep = mcr::bench::sweep_for(name);
        const bool full = info.temporal || !scene.is_sequence();
        std::vector<double> values = sweep.values;
        if (!full || values.empty() || sweep.param.empty()) values = {std::nan("")};
        std::vector<std::string> variants = full ? mcr::bench::sweep_variants(name) : std::vector<std::string>{""};
        for (const std::string& variant : variants)
          for (bool demod : {false, true}) {
            if (demod && !loaded.frames.front().has(mcr::Role::Albedo)) continue;
            for (double v : values) {
              auto filter = mcr::make_filter(name);
              std::string setting = demod ? "demod" : "";
              const std::string given = mcr::bench::apply_variant(*filter, variant);
              if (!given.empty()) setting += (setting.empty() ? "" : " ") + given;
              if (!std::isnan(v)) {
                filter->set(sweep.param, v);
                setting += (setting.empty() ? "" : " ") + sweep.param + "=" +
                           mcr::param_value_text(filter->params().values().at(sweep.param));
              }
              if (demod && !filter->params().has("demodulate")) break;  // bmfr demodulates itself
              if (demod) filter->set("demodulate", true);
              filter->commit();
              if (!filter->missing_passes(loaded.frames.front()).empty()) break;
              if (setting.empty()) setting = "defaults";
              auto twin = mcr::make_filter(name);  // the same settings, for the accumulated run
              for (const auto& kv : filter->params().values()) twin->set(kv.first, kv.second);
              twin->commit();
              std::printf("%s %s [%s] %s\n", scene.name.c_str(), name.c_str(), setting.c_str(),
                          hash_of(loaded, std::move(filter), false, threads).c_str());
              if (scene.is_sequence() && !info.temporal)
                std::printf("%s %s [accumulate %s] %s\n", scene.name.c_str(), name.c_str(), setting.c_str(),
                            hash_of(loaded, std::move(twin), true, threads).c_str());
              std::fflush(stdout);
            }
          }
      }
    }
  } catch (const mcr::Error& e) {
    std::fprintf(stderr, "mcrecon_output_hashes: %s\n", e.what());
    return 2;
  }
  return 0;
}
