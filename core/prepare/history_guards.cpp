#include "prepare/history_guards.h"

#include "prepare/sample_limits.h"

namespace mcr {

AccumulationGuards HistoryGuards::build(const Image& signal, const SurfaceClasses& classes, const HistoryGuardSettings& s,
                                        int nthreads) {
  AccumulationGuards g;
  g.history_factor = float(s.history_factor);
  if (s.limit_k > 0) {
    firefly_limits(signal, s.limit_radius, s.limit_k, nthreads, limit_, s.limit_k_fresh, &fresh_);
    g.limit = limit_.data();
    g.limit_fresh = fresh_.data();
  }
  alpha_floor_.clear();
  const bool mirrors = classes.mirror && s.mirror_alpha > 0, background = classes.background && s.background_cap;
  if (mirrors) {
    class_values(classes, SurfaceClasses::kMirror, float(s.mirror_alpha), alpha_floor_);
    g.alpha_floor = alpha_floor_.data();
  }
  if (mirrors || background) {
    const std::uint8_t mask = std::uint8_t((mirrors ? SurfaceClasses::kMirror : 0) |
                                           (background ? SurfaceClasses::kBackground : 0));
    neighbourhood_caps(signal, classes.flags, mask, nthreads, cap_);
    g.history_cap = cap_.data();
  }
  return g;
}

}  // namespace mcr
