#pragma once
// What `mcrecon report` reports on: the sample scenes (flat stills and sequences from
// samples/data/manifest.json, per-sample deep scenes from per_sample/scenes.json, the Blender
// light field in lightfield/) or a user's own render with its reference.
#include <string>
#include <vector>

namespace mcr {

// The same scene rendered at another sample count: a reference point ("worth N x samples").
struct ReportLevel {
  int spp = 0;
  std::vector<std::string> paths;  // per frame, flat files
  std::vector<std::string> deep;   // per frame, the per-sample / light-field twins (empty: none)
};

struct ReportScene {
  std::string id;      // "room_16spp": folder and anchor names
  std::string scene;   // "room"
  std::string kind;    // "still", "sequence", "deep" (per-sample), "lightfield"; a user render's is
                       // found when it is read
  std::string split;   // "tune" (settings were chosen on it), "report" (held out), "user"
  int spp = 0, reference_spp = 0;  // 0: not known
  std::vector<int> frames;          // frame numbers ({0} for a still)
  std::vector<std::string> noisy;   // per frame: what the image-space filters read
  std::vector<std::string> deep;    // per frame: per-sample / light-field file ("" when none)
  std::vector<std::string> reference;
  std::vector<ReportLevel> levels;  // every render of the scene at a known spp, the input included
  // Sequences: the #### patterns and frame list a command-line run takes ("" for stills).
  std::string noisy_pattern, deep_pattern, frames_text;
};

// The sample scenes under `dir` at each of `spp` that a scene has (sequences at their lowest
// spp; deep scenes and the light field at the sample count they were made with); `only`
// (scene names) narrows them, an unknown name is an InvalidArgument listing the names.
std::vector<ReportScene> sample_report_scenes(const std::string& dir, const std::vector<int>& spp,
                                              const std::vector<std::string>& only = {});

// A user's render: `noisy` and `reference` files, or #### patterns with `frames` ("1-16").
// Throws InvalidArgument for a pattern without frames or frames without a pattern; the files
// themselves are checked by the caller (io/frame_reader.h, check_image_file).
ReportScene user_report_scene(const std::string& name, const std::string& noisy, const std::string& reference,
                              const std::string& frames, int spp);

}  // namespace mcr
