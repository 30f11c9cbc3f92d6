#pragma once
// Temporal accumulation (BMFR phase I and III, Koskela et al. 2019, 4.1 and 4.3):
// the previous accumulated value is reprojected (bilinear, discarded taps left out,
// normalised by the kept weights only), and blended with the new value by a
// cumulative moving average (weight 1/n for the n-th sample, n = reprojected sample
// count rounded to the nearest integer, plus one) until that weight would fall below
// alpha, then by an exponential moving average of weight alpha.
//
// Guards (optional, per pixel, AccumulationGuards below) act on the new value before the
// blend: its luminance is cut to max(limit, history_factor x the history's luminance, 0)
// (limit_fresh instead of limit where the pixel has no history, when given),
// RGB scaled alike (a firefly that neither its neighbours nor its own history back is cut
// to what they do back; a highlight that persists is not), and its weight is at least
// alpha_floor (a pixel whose history cannot be trusted, such as a mirror whose reflection
// does not move with the surface, keeps a short one). Before both, the history's luminance
// is cut to max(history_cap, 0) the same way (a reflection that has slid away fades at
// once, as TAA clips its history to the current neighbourhood).
//
// Non-finite input: a pixel whose new value has a NaN/Inf channel keeps its history
// (count unchanged); with no history it is marked invalid (count 0, value 0), and
// invalid history taps are never read.
#include <functional>
#include <vector>

#include "image/pass.h"
#include "temporal/reprojection.h"

namespace mcr {

struct AccumulationGuards {
  const float* limit = nullptr;        // w x h luminance bounds (prepare/sample_limits.h), or none
  const float* limit_fresh = nullptr;  // w x h, for pixels without history (else `limit`), or none
  const float* alpha_floor = nullptr;  // w x h, or none
  const float* history_cap = nullptr;  // w x h luminance bounds of the history (+inf: none), or none
  float history_factor = 4.0f;
  bool any() const { return limit || alpha_floor || history_cap; }
};

// One accumulated quantity (any channel count <= 8) with its per-pixel sample count.
class AccumulationBuffer {
 public:
  // Blends `current` with the history reprojected by `r` (same size) and keeps the
  // result (and the counts) as the new history; returns it (valid until the next call).
  const Image& accumulate(const Reprojection& r, const Image& current, double alpha, int nthreads,
                          const AccumulationGuards& guards = {});
  void reset();
  const Image& value() const { return value_; }
  const std::vector<float>& count() const { return count_; }  // 0 = invalid pixel

  // The same split up, for callers fusing it with other per-row work: begin() sizes the
  // target (double-buffered, reused between frames) and says whether the history is
  // usable with `r`; row(y) blends row y (r's row y must be final); finish() makes the
  // target the new history. begin() may be called again before finish() to redo a frame.
  void begin(const Reprojection& r, const Image& current);
  void row(int y, const Reprojection& r, const Image& current, double alpha, const AccumulationGuards& guards = {});
  void finish();
  // The target of the pending begin()/row() calls (the history-to-be).
  const Image& pending() const { return next_; }

 private:
  Image value_, next_;
  std::vector<float> count_, next_count_;
  bool usable_ = false;
};

struct AccumulationParams {
  double alpha = 0.2;  // BMFR alpha1
  ReprojectionParams reprojection;
};

// Phase I on its own: geometry history + one colour buffer. Needs world position and
// world normal (Prefer::Geometry); uses the motion pass when present (zero motion
// otherwise: a moving camera then relies on the discard tests alone).
class TemporalAccumulator {
 public:
  explicit TemporalAccumulator(AccumulationParams p = {}) : params_(p) {}
  void set_params(const AccumulationParams& p) { params_ = p; }
  const AccumulationParams& params() const { return params_; }

  // Accumulates `colour` (RGB) of `frame`; throws MissingPass without position/normal.
  // The result stays valid until the next call.
  const Image& accumulate(const Frame& frame, const Image& colour, int nthreads = 0);
  const Image& accumulate(const Image& colour, const Image& position, const Image& normal, const Image* motion,
                          int nthreads = 0);
  // Same, calling before_row(y) (when set) right before row y of `colour` is read, in
  // the same parallel pass: lets a caller produce `colour` row by row (fused passes).
  const Image& accumulate(const Frame& frame, const Image& colour, const std::function<void(int)>& before_row,
                          int nthreads);

  // Guards for the following accumulate() calls (the arrays must stay valid and sized to
  // the frames); clear_guards() drops them.
  void set_guards(const AccumulationGuards& g) { guards_ = g; }
  void clear_guards() { guards_ = {}; }

  const Reprojection& last_reprojection() const { return reprojection_; }
  const std::vector<float>& sample_count() const { return buffer_.count(); }
  void reset();

 private:
  AccumulationParams params_;
  AccumulationGuards guards_;
  GeometryHistory geometry_;
  AccumulationBuffer buffer_;
  Reprojection reprojection_;
  std::vector<std::size_t> row_lost_;
  const std::function<void(int)>* before_row_ = nullptr;
};

}  // namespace mcr
