#include "report/report_scenes.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "io/sample_manifest.h"
#include "io/sequence.h"
#include "util/error.h"

namespace mcr {

namespace fs = std::filesystem;

namespace {

ReportScene from_manifest(const SampleScene& s, int spp) {
  ReportScene r;
  r.scene = s.name;
  r.kind = s.kind;
  r.split = s.split.empty() ? "report" : s.split;
  r.spp = spp;
  r.reference_spp = s.reference_spp;
  r.id = s.name + "_" + std::to_string(spp) + "spp";
  for (int f = s.is_sequence() ? s.first_frame : 0; f <= (s.is_sequence() ? s.last_frame : 0); ++f) {
    r.frames.push_back(f);
    r.noisy.push_back(s.is_sequence() ? sequence_path(s.noisy.at(spp), f) : s.noisy.at(spp));
    r.reference.push_back(s.is_sequence() ? sequence_path(s.reference, f) : s.reference);
    r.deep.emplace_back();
  }
  if (s.is_sequence()) {
    r.noisy_pattern = s.noisy.at(spp);
    r.frames_text = FrameList::span(s.first_frame, s.last_frame).text();
  }
  for (const auto& [n, path] : s.noisy) {
    ReportLevel level{n, {}, {}};
    for (int f : r.frames) level.paths.push_back(s.is_sequence() ? sequence_path(path, f) : path);
    r.levels.push_back(level);
  }
  return r;
}

// per_sample/scenes.json (samples/scenes/per_sample.py): the sweep's deep scenes. Its
// "choice" scenes chose the sweep's settings, the "held-out" ones did not.
std::vector<ReportScene> per_sample_scenes(const fs::path& dir) {
  std::vector<ReportScene> out;
  const fs::path file = dir / "scenes.json";
  if (!fs::is_regular_file(file)) return out;
  std::ifstream in(file);
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    throw Error(Errc::InvalidArgument, file.string() + ": not JSON (" + e.what() + ")");
  }
  for (const auto& s : j.at("scenes")) {
    ReportScene r;
    r.scene = s.at("scene").get<std::string>();
    r.kind = "deep";
    r.split = s.value("role", "") == "choice" ? "tune" : "report";
    r.spp = s.value("spp", 0);
    r.reference_spp = s.value("ref_spp", 0);
    r.id = r.scene + "_deep_" + std::to_string(r.spp) + "spp";
    const std::string deep = (dir / s.at("deep").get<std::string>()).string();
    r.frames = {0};
    r.noisy = {deep};  // the image-space filters get its flattened passes
    r.deep = {deep};
    r.reference = {(dir / s.at("reference").get<std::string>()).string()};
    if (r.spp > 0) r.levels = {{r.spp, {deep}, {deep}}};
    out.push_back(r);
  }
  return out;
}

// lightfield/<scene>_lf_<n>spp.exr with its _flat twin and <scene>_lf_ref.exr
// (samples/scenes/lightfield_dof.py): the sheared filters read the first, the image-space
// filters the second (the same samples, aperture-weighted, with averaged features).
std::vector<ReportScene> light_field_scenes(const fs::path& dir, const std::vector<int>& spp) {
  std::vector<ReportScene> out;
  if (!fs::is_directory(dir)) return out;
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string f = e.path().filename().string();
    const std::size_t at = f.rfind("_lf_ref.exr");
    if (at != std::string::npos && at + 11 == f.size()) names.insert(f.substr(0, at));
  }
  for (const std::string& name : names) {
    std::vector<ReportLevel> levels;
    for (int n = 1; n <= 64; ++n) {
      const fs::path flat = dir / (name + "_lf_" + std::to_string(n) + "spp_flat.exr");
      const fs::path lf = dir / (name + "_lf_" + std::to_string(n) + "spp.exr");
      if (fs::is_regular_file(flat) && fs::is_regular_file(lf)) levels.push_back({n, {flat.string()}, {lf.string()}});
    }
    if (levels.empty()) continue;
    // The highest level asked for that the light field has, else its highest.
    int pick = levels.back().spp;
    for (const ReportLevel& l : levels)
      if (std::find(spp.begin(), spp.end(), l.spp) != spp.end()) pick = l.spp;
    ReportScene r;
    r.scene = name + "_lf";
    r.kind = "lightfield";
    r.split = "report";  // the light-field filters' defaults were chosen on the generator's scenes
    r.spp = pick;
    r.reference_spp = 576 * 16;  // every view of the 24 x 24 aperture grid, 16 samples each
    r.id = r.scene + "_" + std::to_string(pick) + "spp";
    r.frames = {0};
    r.noisy = {(dir / (name + "_lf_" + std::to_string(pick) + "spp_flat.exr")).string()};
    r.deep = {(dir / (name + "_lf_" + std::to_string(pick) + "spp.exr")).string()};
    r.reference = {(dir / (name + "_lf_ref.exr")).string()};
    r.levels = levels;
    out.push_back(r);
  }
  return out;
}

}  // namespace

std::vector<ReportScene> sample_report_scenes(const std::string& dir, const std::vector<int>& spp,
                                              const std::vector<std::string>& only) {
  std::vector<ReportScene> all;
  for (const SampleScene& s : load_sample_manifest(dir)) {
    if (s.noisy.empty()) continue;
    if (s.is_sequence()) {
      all.push_back(from_manifest(s, s.noisy.begin()->first));  // real-time filters get 1 spp
      continue;
    }
    for (int n : spp)
      if (s.noisy.count(n)) all.push_back(from_manifest(s, n));
  }
  for (ReportScene& r : per_sample_scenes(fs::path(dir) / "per_sample")) all.push_back(std::move(r));
  for (ReportScene& r : light_field_scenes(fs::path(dir) / "lightfield", spp)) all.push_back(std::move(r));
  if (only.empty()) return all;
  std::vector<ReportScene> picked;
  std::string names;
  std::set<std::string> seen;
  for (const ReportScene& r : all)
    if (seen.insert(r.scene).second) names += (names.empty() ? "" : ", ") + r.scene;
  for (const std::string& name : only)
    if (!seen.count(name))
      throw Error(Errc::InvalidArgument, "--scenes: no sample scene '" + name + "' in '" + dir + "'; there are " + names);
  for (ReportScene& r : all)
    if (std::find(only.begin(), only.end(), r.scene) != only.end()) picked.push_back(std::move(r));
  return picked;
}

ReportScene user_report_scene(const std::string& name, const std::string& noisy, const std::string& reference,
                              const std::string& frames, int spp) {
  ReportScene r;
  r.scene = name.empty() ? fs::path(noisy).stem().string() : name;
  for (char& c : r.scene)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  r.kind = "";  // found when read
  r.split = "user";
  r.spp = spp;
  r.id = r.scene;
  const bool sequence = !frames.empty();
  if (sequence && !is_sequence_pattern(noisy))
    throw Error(Errc::InvalidArgument, "--input '" + noisy + "': --frames needs a #### pattern");
  if (sequence && !is_sequence_pattern(reference))
    throw Error(Errc::InvalidArgument, "--reference '" + reference + "': --frames needs a #### pattern");
  r.frames = sequence ? parse_frame_list(frames).frames() : std::vector<int>{0};
  if (sequence) {
    r.noisy_pattern = r.deep_pattern = noisy;
    r.frames_text = frames;
  }
  for (int f : r.frames) {
    r.noisy.push_back(sequence ? sequence_path(noisy, f) : noisy);
    r.reference.push_back(sequence ? sequence_path(reference, f) : reference);
    r.deep.push_back(r.noisy.back());  // a deep file serves the deep filters too
  }
  if (spp > 0) r.levels.push_back({spp, r.noisy, r.deep});
  return r;
}

}  // namespace mcr
