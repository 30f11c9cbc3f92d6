#pragma once
// The thread count a user gives a front end (CLI --threads, Python threads=):
// 0 = all cores, a positive count (more than the cores is clamped by
// arena_threads, util/parallel.h), a negative one refused here.
#include <string>

#include "util/error.h"

namespace mcr {

inline const char* thread_count_range() { return "expected 0 (all cores) or a positive count"; }

// Returns n, or throws InvalidArgument "<shown>: expected 0 (all cores) or a
// positive count"; `shown` repeats what the user typed ("threads=-1").
inline int checked_thread_count(long long n, const std::string& shown) {
  if (n < 0) throw Error(Errc::InvalidArgument, shown + ": " + thread_count_range());
  return int(n);
}

}  // namespace mcr
