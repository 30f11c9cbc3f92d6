// mcrecon: re-denoise saved renders and sequences, inspect passes, compare, demo.
#include <csignal>
#include <cstdio>
#include <iostream>
#include <map>
#include <string>

#include "commands.h"
#include "io/atomic_write.h"
#include "util/error.h"

namespace {

// Ctrl-C or kill mid-write: remove the temp files so no partial output remains.
extern "C" void on_signal(int sig) {
  mcr::remove_pending_temp();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

// CLI11 says "A subcommand is required" for a misspelt command too: name what was typed and
// list the commands. Errors inside a command (unknown option, missing or bad value) are
// CLI11's own, which name the option and the value.
std::string parse_error_text(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  if (!app.get_subcommands().empty()) return e.what();
  std::string names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    names += (names.empty() ? "" : ", ") + sub->get_name();
  if (argc < 2) return "no command given; commands: " + names;
  const std::string first = argv[1];
  if (!first.empty() && first[0] != '-') return "unknown command '" + first + "'; commands: " + names;
  return "expected a command before '" + first + "'; commands: " + names;
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGHUP, on_signal);
  // Over `ulimit -f`: a write fails with EFBIG (message, temp removed) instead of a kill.
  std::signal(SIGXFSZ, SIG_IGN);

  CLI::App app{"mcrecon: reconstruct clean images from noisy Monte Carlo renders"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "mcrecon 0.1.0");
  std::map<CLI::App*, mcr::cli::Run> runs;
  auto add = [&](const char* name, const char* help, mcr::cli::Run (*fn)(CLI::App&)) {
    CLI::App* sub = app.add_subcommand(name, help);
    runs[sub] = fn(*sub);
  };
  add("info", "show the passes found in a render and which filters can run on it", mcr::cli::add_info);
  add("filters", "list every filter with its parameter table", mcr::cli::add_filters);
  add("denoise", "run a filter on a render or a sequence", mcr::cli::add_denoise);
  add("compare", "error metrics of an image against a reference", mcr::cli::add_compare);
  add("plan", "split a sequence's denoise into farm chunks: one command per chunk with warm-up and resume",
      mcr::cli::add_plan);
  add("sparsify", "subsample a render with the thesis' foveated expanded grid (holes for pull-push)",
      mcr::cli::add_sparsify);
  add("lightfield", "render light-field samples (soft shadows, depth of field, indirect light) for the sheared filters",
      mcr::cli::add_lightfield);
  add("report", "run time against error: every filter, auto, parameter sweeps and peers on the sample scenes or "
      "your renders, as report.html + results.json/csv", mcr::cli::add_report);
  add("demo", "run every filter on the sample scenes: table + side-by-side PNGs", mcr::cli::add_demo);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "mcrecon: error: " << parse_error_text(app, e, argc, argv) << "\n";
    return 2;
  }
  try {
    for (CLI::App* sub : app.get_subcommands()) return runs.at(sub)();
  } catch (const mcr::Error& e) {
    std::cerr << "mcrecon: error: " << e.what() << "\n";
    return mcr::is_user_error(e.code()) ? 2 : 1;
  } catch (const std::exception& e) {
    std::cerr << "mcrecon: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
