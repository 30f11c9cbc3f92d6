#pragma once
// `mcrecon report`: every filter with its defaults, auto, a sweep of each filter's main
// parameter and any peers, on the sample scenes or a user's renders, scored against references;
// writes OUT/results.json, OUT/results.csv, OUT/images (display PNGs: frames and crops of the
// highest error), OUT/errors (per-pixel error maps) and the scaling measurements. The page
// (OUT/report.html) is drawn from results.json by report/render_report.py.
#include <functional>
#include <string>
#include <vector>

namespace mcr {

struct ReportInput {
  std::string name, noisy, reference, frames;  // frames: "" for a still, else a #### pattern's list
  int spp = 0;                                 // 0: not known
};

struct ReportOptions {
  std::string out = "report_out";
  std::string samples;                 // sample data directory ("" = the default one)
  bool with_samples = true;            // the sample scenes (off when only user inputs are wanted)
  std::vector<int> spp = {16};         // stills' input sample counts
  std::vector<std::string> scenes;     // sample scene names (empty: all)
  std::vector<std::string> filters;    // empty: every filter of the catalog, auto included
  std::vector<ReportInput> inputs;     // a user's renders with references
  std::vector<std::string> peers;      // "NAME=COMMAND TEMPLATE"
  bool builtin_peers = true;           // OpenCV's non-local means when python3-opencv is present
  std::string timing = "auto";         // "in-process", "command", "auto" (command where peers run)
  bool sweeps = true;
  int scaling_min = 256, scaling_max = 2048;  // scaling_max 0: no scaling section
  int threads = 0, repeat = 1;
  std::string cli;                     // the mcrecon CLI (command timing)
  std::string python = "/usr/bin/python3";
  std::string report_dir;              // report/ (render_report.py, peers/); "" = $MCRECON_REPORT_DIR or the source tree's
  double command_timeout = 1800;       // seconds per command (a peer that hangs is killed)
  std::function<void(const std::string&)> log;  // progress and table lines
};

struct ReportSummary {
  std::string results_json, results_csv;
  int scenes = 0, runs = 0, failed_runs = 0;
};

// Throws InvalidArgument / FileNotFound naming the option and what was typed; a failing peer
// or command does not stop the report (its row names the failure, failed_runs counts it).
ReportSummary run_report(const ReportOptions& options);

// The folder of render_report.py and the built-in peers.
std::string report_scripts_dir(const ReportOptions& options);

// Runs `python report/render_report.py OUT` (its progress on stderr); throws Internal naming
// the command when it fails. Returns OUT/report.html.
std::string render_report_page(const ReportOptions& options);

}  // namespace mcr
