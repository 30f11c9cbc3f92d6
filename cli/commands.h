#pragma once
// Subcommands of the mcrecon CLI. Each registers its options on the app and
// returns the exit status; mcr::Error is translated to a message + status in main.
#include <CLI/CLI.hpp>
#include <functional>

namespace mcr::cli {

using Run = std::function<int()>;

Run add_info(CLI::App& app);
Run add_filters(CLI::App& app);
Run add_denoise(CLI::App& app);
Run add_compare(CLI::App& app);
Run add_demo(CLI::App& app);
Run add_sparsify(CLI::App& app);

}  // namespace mcr::cli
