#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "commands.h"
#include "report/report.h"
#include "util/error.h"

namespace mcr::cli {

namespace {

struct ReportArgs {
  ReportOptions options;
  std::vector<std::string> inputs, references;
  std::string frames, name;
  int input_spp = 0;
  bool with_samples = false, no_peers = false, no_sweeps = false, no_page = false;
};

// The running executable: every filter timed as a command runs this same build.
std::string self_path() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : p.string();
}

int run_report_command(ReportArgs& a) {
  ReportOptions& o = a.options;
  if (a.inputs.size() != a.references.size())
    throw Error(Errc::InvalidArgument, "--input and --reference come in pairs: " + std::to_string(a.inputs.size()) +
                                           " --input, " + std::to_string(a.references.size()) + " --reference");
  if (!a.name.empty() && a.inputs.size() > 1)
    throw Error(Errc::InvalidArgument, "--name '" + a.name + "': one name for " + std::to_string(a.inputs.size()) + " inputs");
  for (std::size_t i = 0; i < a.inputs.size(); ++i)
    o.inputs.push_back({a.name, a.inputs[i], a.references[i], a.frames, a.input_spp});
  o.with_samples = a.inputs.empty() || a.with_samples;
  o.builtin_peers = !a.no_peers;
  o.sweeps = !a.no_sweeps;
  o.cli = self_path();
  o.log = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const ReportSummary s = run_report(o);
  std::fprintf(stderr, "wrote %s and %s (%d scenes, %d runs%s)\n", s.results_json.c_str(), s.results_csv.c_str(),
               s.scenes, s.runs, s.failed_runs ? (", " + std::to_string(s.failed_runs) + " failed").c_str() : "");
  if (!a.no_page) std::fprintf(stderr, "wrote %s\n", render_report_page(o).c_str());
  return s.failed_runs ? 1 : 0;
}

}  // namespace

Run add_report(CLI::App& app) {
  auto a = std::make_shared<ReportArgs>();
  ReportOptions& o = a->options;
  app.add_option("-o,--out", o.out, "folder for report.html, results.json, results.csv and the pictures")
      ->capture_default_str();
  app.add_option("--samples", o.samples, "sample data directory with manifest.json (default: the repo's samples/data)");
  app.add_option("--spp", o.spp, "stills' input sample counts (default 16; sequences at their lowest)")
      ->check(whole_number(1));
  app.add_option("--scenes", o.scenes, "only these sample scenes (names as in the manifest)");
  app.add_option("--filters", o.filters, "filters to run (default: every filter, auto included)");
  app.add_option("--input", a->inputs, "your render (a #### pattern with --frames); pairs with --reference")
      ->type_size(1)->expected(0, -1);
  app.add_option("--reference", a->references, "the high-spp reference of the --input before it");
  app.add_option("--frames", a->frames, "frames of the --input / --reference patterns (1-16, 1-16x2, 1,5,9)");
  app.add_option("--name", a->name, "name of the --input in the report (default: its file name)");
  app.add_option("--input-spp", a->input_spp, "the --input's samples per pixel (for 'worth N x samples')")
      ->check(whole_number(1));
  app.add_flag("--with-samples", a->with_samples, "with --input: report on the sample scenes too");
  app.add_option("--peer", o.peers,
                 "an external denoiser, NAME='COMMAND {colour} {albedo} {normal} ... {output}' (repeatable; "
                 "README: peers)");
  app.add_flag("--no-builtin-peers", a->no_peers, "leave out OpenCV's non-local means");
  app.add_option("--timing", o.timing,
                 "in-process (filter time, no I/O), command (every run a process, wall clock) or auto (command "
                 "where peers run)")
      ->capture_default_str();
  app.add_flag("--no-sweeps", a->no_sweeps, "each filter with its defaults only (no sweep of its main parameter)");
  app.add_option("--scaling-max", o.scaling_max, "largest side of the scaling section (0: none)")
      ->check(whole_number(0))->capture_default_str();
  app.add_option("--scaling-min", o.scaling_min, "smallest side of the scaling section")
      ->check(whole_number(16))->capture_default_str();
  app.add_option("--repeat", o.repeat, "scaling: best of N runs")->check(whole_number(1))->capture_default_str();
  app.add_option("--python", o.python, "Python with matplotlib for the page")->capture_default_str();
  app.add_flag("--no-page", a->no_page, "results.json, results.csv and pictures only (no report.html)");
  add_threads_option(app, o.threads);
  return [a] { return run_report_command(*a); };
}

}  // namespace mcr::cli
