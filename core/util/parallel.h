#pragma once
// Row-parallel loops with an explicit thread count (0 = all cores), the way
// ImageBufAlgo takes nthreads: callers that tile or share the machine can limit us.
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <map>
#include <mutex>

namespace mcr {

// The arena size for a thread count: 0 (or less) = all cores; more threads than
// the hardware has are clamped to it (an arena of 100000 threads crashes TBB, and
// more threads than cores gain nothing). Every arena in the core is sized here.
// Front ends refuse negative counts before they get this far (util/thread_count.h).
inline int arena_threads(int nthreads) {
  const int cores = tbb::info::default_concurrency();
  return nthreads > 0 ? (nthreads < cores ? nthreads : cores) : tbb::task_arena::automatic;
}

// The arena for a thread count, made once and kept for the life of the process: an arena
// built and dropped per call keeps memory TBB does not give back (oneTBB issue 967; 1000
// small runs on 2 threads grew a process by 100 MB and slowed each call 6x). Shared by
// every caller: task_arena::execute may be entered from several threads at once.
inline tbb::task_arena& shared_arena(int nthreads) {
  static std::mutex lock;
  static std::map<int, tbb::task_arena*>* arenas = new std::map<int, tbb::task_arena*>();  // never destroyed
  const int n = arena_threads(nthreads);
  const std::lock_guard<std::mutex> hold(lock);
  tbb::task_arena*& a = (*arenas)[n];
  if (!a) a = new tbb::task_arena(n);
  return *a;
}

// Calls fn(y) for every y in [y0, y1), rows spread over nthreads threads.
template <class Fn>
void parallel_rows(int y0, int y1, int nthreads, Fn&& fn) {
  if (y1 <= y0) return;
  shared_arena(nthreads).execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(y0, y1), [&](const tbb::blocked_range<int>& r) {
      for (int y = r.begin(); y != r.end(); ++y) fn(y);
    });
  });
}

}  // namespace mcr
