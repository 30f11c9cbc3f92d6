#pragma once
// The per-pixel guards of a temporal accumulation (temporal/accumulation.h) built from a
// frame: one rule for bmfr's phase I and the pipeline's `--accumulate` (issue 15).
//   - limit: a new sample's luminance may not exceed its neighbours' mean + limit_k
//     deviations (limit_k_fresh without history; prepare/sample_limits.h) unless its own history backs it
//     (history_factor x the history's luminance): a firefly does not enter the history;
//   - on mirror-like pixels (prepare/surface_classes.h) the new sample's weight is at
//     least mirror_alpha and the history is no brighter than the current 3x3
//     neighbourhood's brightest: what a mirror shows does not move with its surface;
//   - on background pixels (no geometry: Blender writes no motion for the world) the
//     history is no brighter than the current 3x3 neighbourhood's brightest either: an
//     environment's bright spot does not stay where the camera left it.
// The buffers are kept between frames (a sequence allocates once).
#include <vector>

#include "image/image.h"
#include "prepare/surface_classes.h"
#include "temporal/accumulation.h"

namespace mcr {

struct HistoryGuardSettings {
  double limit_k = 3.0;        // 0: no sample limit
  // A pixel without history: only a clear firefly is cut (the firefly step's k): at k 3 a
  // sequence's first frame lost 2.2-2.4% of its mean luminance (room 16 spp, anim frame 9).
  double limit_k_fresh = 8.0;
  int limit_radius = 2;
  double history_factor = 4.0;
  double mirror_alpha = 1.0;   // 0: mirrors as any pixel
  bool background_cap = true;  // false: background pixels as any pixel
};

class HistoryGuards {
 public:
  // signal: the RGB that is about to be accumulated (the frame's size). The result points
  // into this object: valid until the next build().
  AccumulationGuards build(const Image& signal, const SurfaceClasses& classes, const HistoryGuardSettings& s,
                           int nthreads);

 private:
  std::vector<float> limit_, fresh_, alpha_floor_, cap_;
};

}  // namespace mcr
