#pragma once
// Row-parallel loops with an explicit thread count (0 = all cores), the way
// ImageBufAlgo takes nthreads: callers that tile or share the machine can limit us.
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace mcr {

// The arena size for a thread count: 0 (or less) = all cores; more threads than
// the hardware has are clamped to it (an arena of 100000 threads crashes TBB, and
// more threads than cores gain nothing). Every arena in the core is sized here.
// Front ends refuse negative counts before they get this far (util/thread_count.h).
inline int arena_threads(int nthreads) {
  const int cores = tbb::info::default_concurrency();
  return nthreads > 0 ? (nthreads < cores ? nthreads : cores) : tbb::task_arena::automatic;
}

// Calls fn(y) for every y in [y0, y1), rows spread over nthreads threads.
template <class Fn>
void parallel_rows(int y0, int y1, int nthreads, Fn&& fn) {
  if (y1 <= y0) return;
  tbb::task_arena arena(arena_threads(nthreads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(y0, y1), [&](const tbb::blocked_range<int>& r) {
      for (int y = r.begin(); y != r.end(); ++y) fn(y);
    });
  });
}

}  // namespace mcr
