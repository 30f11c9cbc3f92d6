#pragma once
// Subcommands of the mcrecon CLI. Each registers its options on the app and
// returns the exit status; mcr::Error is translated to a message + status in main.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <functional>
#include <string>

#include "validators.h"

namespace mcr::cli {

using Run = std::function<int()>;

// -j/--threads of every command: 0 = all cores, more than the cores is clamped, anything
// else refused as "--threads: expects a whole number in [0, 2147483647], got '-1'".
inline CLI::Option* add_threads_option(CLI::App& app, int& threads) {
  return app.add_option("-j,--threads", threads, "threads (0 = all cores; more than the cores: all cores)")
      ->check(whole_number(0));
}

Run add_info(CLI::App& app);
Run add_filters(CLI::App& app);
Run add_denoise(CLI::App& app);
Run add_compare(CLI::App& app);
Run add_demo(CLI::App& app);
Run add_sparsify(CLI::App& app);
Run add_plan(CLI::App& app);
Run add_lightfield(CLI::App& app);
Run add_report(CLI::App& app);

}  // namespace mcr::cli
