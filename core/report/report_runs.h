#pragma once
// One entry of the report: a filter setting or a peer run over every frame of a scene,
// timed, its peak memory taken, its outputs scored against the references.
#include <string>
#include <vector>

#include "filters/filter.h"
#include "metrics/metrics.h"
#include "report/peer_command.h"
#include "report/report_scenes.h"

namespace mcr {

struct LoadedReportScene {
  ReportScene scene;
  std::vector<Frame> flat;      // per frame: what the image-space filters read
  std::vector<Frame> deep;      // per frame: the per-sample / light-field frames (empty when none)
  std::vector<Image> references;
};

// Reads every frame, the deep twins and the references; a user render's kind is set here.
LoadedReportScene load_report_scene(const ReportScene& scene);

struct Scores {
  ImageMetrics mean;                    // over frames
  double temporal_error = -1;           // mean over consecutive frames; -1 for stills
  std::vector<double> frame_relmse;     // per frame
  std::vector<double> frame_temporal;   // per frame, -1 for the first
};
Scores score_outputs(const std::vector<Image>& outputs, const std::vector<Image>& references, int nthreads);

struct RunResult {
  std::string id, filter, kind = "filter", parameters;  // kind: filter, auto, peer
  bool is_default = true;
  std::string sweep_param;  // "" when not a sweep point
  double sweep_value = 0;
  double seconds = -1, filter_seconds = -1, peak_memory_mb = -1;
  Scores scores;
  std::string chosen;               // auto: the filter it ran ("input" when it kept the input), choices_summary()
  std::vector<std::string> notes;
  std::string error;                // a peer or command that failed: why
  std::vector<Image> outputs;       // per frame
  double worth_x_samples = -1;
  bool pareto_relmse = false, pareto_ssim = false;
  bool ok() const { return error.empty(); }
};

// auto's choices over the frames of a run: "pwaf" when every frame ran the same, else each with
// its frame count, most first (ties in the order they came): "pwaf x8, bilateral x4, atrous x1".
std::string choices_summary(const std::vector<std::string>& per_frame);

// The frames a filter takes in this scene (flat or deep), or null with `why` set.
const std::vector<Frame>* frames_for(const LoadedReportScene& s, Filter& filter, std::string& why);

// In the process: the filter's execute() time summed over frames, the resident memory the
// run added at its peak.
RunResult run_in_process(const LoadedReportScene& s, Filter& filter, const std::vector<Frame>& frames, int nthreads);

struct CommandTiming {
  std::string cli;        // the mcrecon CLI
  std::string work_dir;   // outputs of the commands, removed by the caller
  int nthreads = 0;
  double timeout_seconds = 600;
};

// As a command (`mcrecon denoise`): wall time from spawn to exit, reading and writing
// included, the process's peak memory; filter_seconds from its --timings line.
RunResult run_as_command(const LoadedReportScene& s, const std::string& filter, const std::string& set,
                         bool deep_input, const CommandTiming& timing);

// A peer, frame by frame (its exported passes written before the clock starts).
RunResult run_peer(const LoadedReportScene& s, const PeerCommand& peer, const CommandTiming& timing);

}  // namespace mcr
