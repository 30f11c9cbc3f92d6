#include "io/sample_manifest.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/input_limits.h"
#include "util/error.h"

namespace mcr {

namespace fs = std::filesystem;

std::string default_samples_dir() {
  if (const char* env = std::getenv("MCRECON_SAMPLES")) return env;
#ifdef MCRECON_SOURCE_DIR
  return std::string(MCRECON_SOURCE_DIR) + "/samples/data";
#else
  return "samples/data";
#endif
}

std::vector<SampleScene> load_sample_manifest(const std::string& dir) {
  const fs::path file = fs::path(dir) / "manifest.json";
  require_regular_file(file.string());  // a FIFO would block the open below
  std::ifstream in(file);
  if (!in) throw Error(Errc::FileNotFound, "cannot read sample manifest '" + file.string() + "'");
  std::vector<SampleScene> scenes;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    for (const auto& s : j.at("scenes")) {
      SampleScene sc;
      sc.name = s.at("name").get<std::string>();
      sc.kind = s.value("kind", std::string("still"));
      sc.description = s.value("description", std::string());
      sc.split = s.value("split", std::string());
      sc.width = s.value("width", 0);
      sc.height = s.value("height", 0);
      for (const auto& [spp, path] : s.at("noisy").items()) {
        // The keys are sample counts: "16", never "many" or "16x".
        char* end = nullptr;
        const long n = std::strtol(spp.c_str(), &end, 10);
        if (spp.empty() || *end != '\0' || n <= 0 || n > 1 << 24)
          throw Error(Errc::InvalidArgument, "sample manifest '" + file.string() + "': scene '" + sc.name +
                                                 "' has a noisy entry '" + spp + "' that is not a sample count");
        sc.noisy[int(n)] = (fs::path(dir) / path.get<std::string>()).string();
      }
      if (s.contains("halves"))
        for (const auto& [spp, pair] : s.at("halves").items()) {
          const int n = std::atoi(spp.c_str());
          if (n <= 0 || !pair.is_array() || pair.size() != 2)
            throw Error(Errc::InvalidArgument, "sample manifest '" + file.string() + "': scene '" + sc.name +
                                                   "' has a halves entry '" + spp + "' that is not two files of a sample count");
          sc.halves[n] = {(fs::path(dir) / pair.at(0).get<std::string>()).string(),
                          (fs::path(dir) / pair.at(1).get<std::string>()).string()};
        }
      sc.reference = (fs::path(dir) / s.at("reference").get<std::string>()).string();
      sc.reference_spp = s.value("reference_spp", 0);
      if (s.contains("frames")) {
        sc.first_frame = s.at("frames").at(0).get<int>();
        sc.last_frame = s.at("frames").at(1).get<int>();
      }
      scenes.push_back(std::move(sc));
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(Errc::InvalidArgument, "malformed sample manifest '" + file.string() + "': " + e.what());
  }
  return scenes;
}

}  // namespace mcr
