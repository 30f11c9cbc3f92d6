#pragma once
// Subcommands of the mcrecon CLI. Each registers its options on the app and
// returns the exit status; mcr::Error is translated to a message + status in main.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <functional>
#include <string>

#include "util/thread_count.h"

namespace mcr::cli {

using Run = std::function<int()>;

// -j/--threads of every command: 0 = all cores, more than the cores is clamped, a
// negative count refused as "--threads: expected 0 (all cores) or a positive count, got '-1'".
inline CLI::Option* add_threads_option(CLI::App& app, int& threads) {
  const CLI::Validator non_negative(
      [](std::string& text) {
        char* end = nullptr;
        const long long n = std::strtoll(text.c_str(), &end, 10);
        // Not a number: CLI11's own conversion error names it.
        return end != text.c_str() && *end == '\0' && n < 0 ? std::string(thread_count_range()) + ", got '" + text + "'"
                                                            : std::string();
      },
      "INT >= 0");
  return app.add_option("-j,--threads", threads, "threads (0 = all cores; more than the cores: all cores)")
      ->check(non_negative);
}

Run add_info(CLI::App& app);
Run add_filters(CLI::App& app);
Run add_denoise(CLI::App& app);
Run add_compare(CLI::App& app);
Run add_demo(CLI::App& app);
Run add_sparsify(CLI::App& app);

}  // namespace mcr::cli
