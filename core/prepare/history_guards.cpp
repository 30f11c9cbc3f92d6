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
  if (classes.mirror && s.mirror_alpha > 0) {
    class_values(classes, SurfaceClasses::kMirror, float(s.mirror_alpha), alpha_floor_);
    g.alpha_floor = alpha_floor_.data();
    neighbourhood_caps(signal, classes.flags, SurfaceClasses::kMirror, nthreads, cap_);
    g.history_cap = cap_.data();
  }
  return g;
}

}  // namespace mcr
