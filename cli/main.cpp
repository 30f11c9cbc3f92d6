// mcrecon: re-denoise saved renders and sequences, inspect passes, compare, demo.
#include <csignal>
#include <cstdio>
#include <iostream>
#include <map>

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
  add("sparsify", "subsample a render with the thesis' foveated expanded grid (holes for pull-push)",
      mcr::cli::add_sparsify);
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
    std::cerr << "mcrecon: error: " << e.what() << "\n";
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
