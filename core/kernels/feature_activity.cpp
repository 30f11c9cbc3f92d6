#include "kernels/feature_activity.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

namespace {

// The pixel's channels into v; false when one is not finite.
inline bool read_pixel(const float* p, int nc, int channels, float* v) {
  bool ok = true;
  for (int c = 0; c < channels; ++c) {
    v[c] = p[std::min(c, nc - 1)];
    ok = ok && std::isfinite(v[c]);
  }
  return ok;
}

}  // namespace

FeatureActivity feature_activity(const Image& im, int channels, const Roi& region, const Tolerance& tol,
                                 int nthreads) {
  if (channels < 1 || channels > 4 || im.channels() < 1)
    throw Error(Errc::Internal, "feature_activity: bad channel count " + std::to_string(channels));
  FeatureActivity a;
  a.channels = channels;
  if (region.empty()) return a;
  const int nc = im.channels();
  // The first counted pixel, row-major: the reference.
  int fx = -1, fy = -1;
  for (int y = region.y0; y < region.y1 && fy < 0; ++y)
    for (int x = region.x0; x < region.x1; ++x)
      if (read_pixel(im.pixel(x, y), nc, channels, a.value)) {
        fx = x;
        fy = y;
        break;
      }
  if (fy < 0) return a;  // Absent
  a.kind = Activity::Constant;
  a.some_nonfinite = fx != region.x0 || fy != region.y0;
  float ref[4], t[4];
  std::copy(a.value, a.value + 4, ref);
  for (int c = 0; c < channels; ++c) t[c] = float(tol.abs + tol.rel * std::fabs(double(ref[c])));
  std::atomic<bool> varies{false}, nonfinite{false};
  parallel_rows(fy, region.y1, nthreads, [&](int y) {
    if (varies.load(std::memory_order_relaxed)) return;  // answer known: stop early
    bool bad = false;
    float v[4];
    for (int x = y == fy ? fx : region.x0; x < region.x1; ++x) {
      if (!read_pixel(im.pixel(x, y), nc, channels, v)) {
        bad = true;
        continue;
      }
      for (int c = 0; c < channels; ++c)
        if (!(std::fabs(v[c] - ref[c]) <= t[c])) {
          varies.store(true, std::memory_order_relaxed);
          return;
        }
    }
    if (bad) nonfinite.store(true, std::memory_order_relaxed);
  });
  if (varies.load()) {
    a.kind = Activity::Varies;
    a.some_nonfinite = false;
  } else {
    a.some_nonfinite = a.some_nonfinite || nonfinite.load();
  }
  return a;
}

std::string activity_note(const std::string& pass, const FeatureActivity& a, const Roi& region, int w, int h,
                          const std::string& consequence) {
  const std::string where = region == Roi::all(w, h) ? "the frame" : "the region read";
  if (a.kind == Activity::Absent) return pass + " pass has no finite value over " + where + ": " + consequence;
  std::string values;
  for (int c = 0; c < a.channels; ++c) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%s%.3f", c ? ", " : "", double(a.value[c]));
    values += buf;
  }
  return pass + " pass is constant over " + where + " (" + values + "): " + consequence;
}

}  // namespace mcr
