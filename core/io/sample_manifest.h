#pragma once
// The sample scenes' manifest (samples/data/manifest.json), read by the demo,
// the benchmarks and the end-to-end tests.
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace mcr {

struct SampleScene {
  std::string name, kind, description;  // kind: "still" or "sequence"
  std::string split;  // "tune": settings are chosen on it; "report": figures are reported on it
  int width = 0, height = 0;
  std::map<int, std::string> noisy;  // spp -> absolute path (a #### pattern for sequences)
  std::map<int, std::pair<std::string, std::string>> halves;  // spp -> its two half buffers
  std::string reference;             // absolute path or pattern
  int reference_spp = 0;
  int first_frame = 1, last_frame = 1;  // sequences
  bool is_sequence() const { return kind == "sequence"; }
};

// Reads DIR/manifest.json; throws FileNotFound / InvalidArgument naming the file.
std::vector<SampleScene> load_sample_manifest(const std::string& dir);

// The samples directory: $MCRECON_SAMPLES, else the source tree's samples/data.
std::string default_samples_dir();

}  // namespace mcr
