#pragma once
// Private helpers shared by metrics.cpp and ssim.cpp; not part of the public API.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "image/image.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr::metrics_detail {

// NaN and +-Inf read as 0 (see metrics.h).
inline double finite_or_zero(float v) { return std::isfinite(v) ? double(v) : 0.0; }
inline double clamp01(double v) { return std::min(std::max(v, 0.0), 1.0); }

// Throws unless both images are non-empty, of equal size and have at least 3 channels.
inline void check_pair(const Image& a, const Image& b, const char* what, const char* name_a,
                       const char* name_b) {
  auto size = [](const Image& im) {
    return std::to_string(im.width()) + "x" + std::to_string(im.height());
  };
  if (a.width() != b.width() || a.height() != b.height())
    throw Error(Errc::SizeMismatch, std::string(what) + ": " + name_a + " is " + size(a) + " but " +
                                        name_b + " is " + size(b));
  if (a.empty() || b.empty() || a.width() == 0 || a.height() == 0)
    throw Error(Errc::InvalidArgument, std::string(what) + ": empty image (" + size(a) + ")");
  for (const Image* im : {&a, &b})
    if (im->channels() < 3)
      throw Error(Errc::InvalidArgument,
                  std::string(what) + ": " + (im == &a ? name_a : name_b) + " has " +
                      std::to_string(im->channels()) + " channel(s), RGB (3 or more) needed");
}

// Runs fn(first, last) over [0, count) split into fixed blocks of `block` items, in parallel on
// `nthreads` threads (<= 0: all cores; more than the hardware has is clamped, arena_threads). The split
// does not depend on the thread count.
template <class Fn>
void parallel_blocks(int count, int block, int nthreads, const Fn& fn) {
  const int nblocks = (count + block - 1) / block;
  tbb::task_arena& arena = shared_arena(nthreads);
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<int>(0, nblocks, 1),
        [&](const tbb::blocked_range<int>& r) {
          for (int b = r.begin(); b != r.end(); ++b) {
            const int first = b * block;
            const int last = first + block < count ? first + block : count;
            fn(first, last);
          }
        },
        tbb::simple_partitioner());
  });
}

// Sum of per-row partial sums, added serially in row order (deterministic).
inline double ordered_sum(const std::vector<double>& parts) {
  double s = 0.0;
  for (double p : parts) s += p;
  return s;
}

// Mean SSIM over R, G, B; inputs already checked with check_pair.
double ssim_checked(const Image& reference, const Image& image, int nthreads);

}  // namespace mcr::metrics_detail
