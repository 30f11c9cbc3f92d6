#include "commands.h"
namespace mcr::cli {
Run add_demo(CLI::App& app) { (void)app; return [] { return 0; }; }
}  // namespace mcr::cli
