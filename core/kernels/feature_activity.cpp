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

FeatureActivity activity_over_frame(const WholeFrameRange& r, const Tolerance& tol) {
  FeatureActivity a;
  a.channels = r.channels;
  if (!r.any_counted) return a;
  std::copy(r.first, r.first + 4, a.value);
  a.kind = Activity::Constant;
  // The scan's test |v - ref| <= t in float: rounding is monotonic, so its largest value over
  // the frame is at a channel's least or greatest value.
  for (int c = 0; c < r.channels; ++c) {
    const float t = float(tol.abs + tol.rel * std::fabs(double(r.first[c])));
    if (!(std::fabs(r.hi[c] - r.first[c]) <= t) || !(std::fabs(r.lo[c] - r.first[c]) <= t)) {
      a.kind = Activity::Varies;
      return a;
    }
  }
  a.some_nonfinite = r.some_uncounted;
  return a;
}

void extend_frame_range(const Image& im, int channels, const Roi& rows, WholeFrameRange& r) {
  if (channels < 1 || channels > 4 || im.channels() < 1)
    throw Error(Errc::Internal, "extend_frame_range: bad channel count " + std::to_string(channels));
  r.channels = channels;
  const int nc = im.channels();
  float v[4];
  for (int y = rows.y0; y < rows.y1; ++y)
    for (int x = rows.x0; x < rows.x1; ++x) {
      if (!read_pixel(im.pixel(x, y), nc, channels, v)) {
        r.some_uncounted = true;
        continue;
      }
      if (!r.any_counted) {
        r.any_counted = true;
        std::copy(v, v + channels, r.first);
        std::copy(v, v + channels, r.lo);
        std::copy(v, v + channels, r.hi);
      }
      for (int c = 0; c < channels; ++c) {
        r.lo[c] = std::min(r.lo[c], v[c]);
        r.hi[c] = std::max(r.hi[c], v[c]);
      }
    }
}

FeatureActivity feature_activity(const Image& im, int channels, const Roi& region, const Tolerance& tol,
                                 int nthreads) {
  if (channels < 1 || channels > 4 || im.channels() < 1)
    throw Error(Errc::Internal, "feature_activity: bad channel count " + std::to_string(channels));
  FeatureActivity a;
  a.channels = channels;
  if (region.empty()) return a;
  if (im.whole_frame && im.whole_frame->channels == channels) return activity_over_frame(*im.whole_frame, tol);
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
