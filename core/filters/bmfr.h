#pragma once
#include <array>
#include <cstdint>

#include "filters/filter.h"
#include "temporal/accumulation.h"

namespace mcr {

// Blockwise Multi-Order Feature Regression (Koskela et al., ACM TOG 2019), whole pipeline
// on the CPU:
//   demodulation by albedo -> I: temporal accumulation of the noisy illumination
//   -> II: per-block least-squares fit of the illumination to multi-order features
//      [1, n, w, w^2] (augmented Householder QR, stochastic regularisation, displaced grid)
//   -> III: second accumulation of the fit, remodulation, TAA (Karis 2014).
// Temporal: history lives in the object; reset() drops it. A size change or a camera
// cut (more than cut_fraction of the pixels lose every reprojection tap) restarts it.
// The whole frame is always processed (history needs it); only the roi is written.
class BmfrFilter : public Filter {
 public:
  BmfrFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  void reset() override;

  // Milliseconds of the stages of the last execute(): demodulation + phase I, phase II
  // (fit), phase III (second accumulation + remodulation), TAA.
  enum Stage { kAccumulate, kFit, kPost, kTaa, kStages };
  const std::array<double, kStages>& stage_ms() const { return stage_ms_; }
  // Whether the last execute() detected a camera cut, and frames processed since reset().
  bool last_cut() const { return last_cut_; }
  std::int64_t frame_index() const { return frame_index_; }

  // The 16 fixed grid displacements, as fractions of the block size.
  static const std::array<std::array<float, 2>, 16>& grid_offsets();

 protected:
  void check_params() override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  void fit_blocks(const Frame& frame, const Image& illum, const std::vector<float>& valid, Image& fitted, int nthreads);

  TemporalAccumulator phase1_;
  AccumulationBuffer phase3_;
  Image taa_history_;
  std::int64_t frame_index_ = 0;
  bool last_cut_ = false;
  std::array<double, kStages> stage_ms_{};
};

}  // namespace mcr
