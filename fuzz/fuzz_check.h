#pragma once
// Shared by the fuzz targets: what counts as a finding besides a sanitizer report.
#include <cstdio>

#include "util/error.h"

namespace mcr::fuzz {

// A property the code promises was broken: say which, then crash so libFuzzer keeps the input.
[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "mcrecon fuzz: %s\n", what);
  std::fflush(stderr);
  __builtin_trap();
}

// mcr::Error is the documented answer to bad input, except Errc::Internal (a bug).
inline void expect_user_error(const Error& e) {
  if (!is_user_error(e.code())) {
    std::fprintf(stderr, "mcrecon fuzz: internal error: %s\n", e.what());
    fail("Errc::Internal on fuzzed input");
  }
}

}  // namespace mcr::fuzz
