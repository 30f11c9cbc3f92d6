#pragma once
// Run time against error: a filter on a loaded sample scene (still or sequence)
// judged against its high-spp reference. Used by the demo and the benchmarks.
#include <functional>
#include <string>
#include <vector>

#include "filters/filter.h"
#include "io/sample_manifest.h"
#include "metrics/metrics.h"

namespace mcr {

struct LoadedScene {
  std::string name;
  int spp = 0;
  std::vector<Frame> frames;       // in frame order
  std::vector<Image> references;   // RGB, one per frame
};

using ProgressFn = std::function<void(int done, int total)>;

// Reads the noisy frames at `spp` and the references; throws MissingPass when
// the manifest has no such spp.
LoadedScene load_scene(const SampleScene& scene, int spp, const ProgressFn& progress = {});

struct Evaluation {
  double seconds = 0;            // filter time, summed over frames (no I/O)
  ImageMetrics metrics;          // mean over frames
  double temporal_error = -1;    // mean over consecutive frames; -1 for stills
  Image preview;                 // result of the middle frame
};

// filter == nullptr judges the noisy input itself. Temporal filters are reset first.
Evaluation evaluate(const LoadedScene& scene, Filter* filter, int nthreads = 0, const ProgressFn& progress = {});

}  // namespace mcr
