#pragma once
#include <array>
#include <cstdint>

#include "filters/filter.h"
#include "prepare/history_guards.h"
#include "prepare/surface_classes.h"
#include "temporal/accumulation.h"

namespace mcr {

// Blockwise Multi-Order Feature Regression (Koskela et al., ACM TOG 2019), whole pipeline
// on the CPU:
//   demodulation by albedo -> I: temporal accumulation of the noisy illumination
//   -> II: per-block least-squares fit of the illumination to multi-order features
//      [1, n, w, w^2] (augmented Householder QR, stochastic regularisation, displaced grid)
//   -> III: second accumulation of the fit, remodulation, TAA (Karis 2014: Catmull-Rom
//      history, clipped towards the centre of a YCoCg box = 3x3 min/max intersected with
//      mean +- taa_gamma sigma, Salvi 2016).
// block_size = 0 (default) picks the block side from the frame: the paper's 32 when the
// shorter side has >= 360 pixels (720p and up), 16 below (e.g. the 160x90 samples, where
// a 32-pixel block spans a third of the image height).
// Speed: every per-frame buffer is kept between frames; the reprojection and the albedo
// demodulation run in the same row pass as phase I, phase III and the remodulation in one
// pass (into a planar result), the TAA in one pass that writes the output too; the fit
// works on planar float features per block (double only in the QR and the synthesis
// sums), one task per block. The filter runs in place (no output copy in the base class).
// On x86-64 CPUs with AVX2 (checked at run time) the hot row loops of every stage run 8
// pixels at a time (temporal/*_avx2, bmfr_taa, bmfr_fit, bmfr_fit_features); they do the
// float operations of the scalar loops in the same order without FMA, so both builds give
// the same bits.
// Texture edges (issue 15): colour = albedo x light + specular on a surface with a specular
// layer, so the demodulated illumination keeps the texture (specular / albedo); the fit
// also regresses on the albedo's luminance (albedo_luminance, one column), which follows
// it where the smooth features would blur it across the edge (bmfr_fit.cpp).
// Highlights and mirrors (issue 15; prepare/surface_classes.h, temporal/accumulation.h):
//   - phase I's new sample is cut to its neighbours' mean + sample_limit_k deviations
//     unless its own history backs it (a firefly does not enter the history);
//   - a pixel whose albedo holds light (> 1) is divided by it but left out of the fit
//     (which would spread its light over the block) and keeps its accumulated value;
//   - a mirror-like pixel (Glossy Color >> Diffuse Color) is not divided by its albedo
//     (the albedo of what it reflects, sample by sample), is left out of the fit, and
//     keeps a short history (weight >= mirror_alpha, no brighter than its 3x3 neighbourhood): what it
//     shows does not move with its surface.
// Temporal: history lives in the object; reset() drops it. A size change or a camera
// cut (more than cut_fraction of the pixels lose every reprojection tap) restarts it.
// The whole frame is always processed (history needs it); only the roi is written.
class BmfrFilter : public Filter {
 public:
  BmfrFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  void reset_history() override;
  // Its TAA runs after the remodulation: with light passes it must clip and blend the
  // component as shown (the colour pass's 1-spp edges included), as it does the beauty.
  bool demodulates_itself() const override { return params().get_bool("albedo_demodulation"); }

  // Milliseconds of the stages of the last execute(): demodulation + phase I, phase II
  // (fit), phase III (second accumulation + remodulation), the detail added back
  // (kernels/residual_shrink.h), TAA.
  enum Stage { kAccumulate, kFit, kPost, kDetail, kTaa, kStages };
  const std::array<double, kStages>& stage_ms() const { return stage_ms_; }
  // The same stages in process CPU time (all threads), ms: robust on a loaded machine.
  const std::array<double, kStages>& stage_cpu_ms() const { return stage_cpu_ms_; }
  // Whether the last execute() detected a camera cut, and frames processed since reset().
  bool last_cut() const { return last_cut_; }
  std::int64_t frame_index() const { return frame_index_; }

  // The 16 fixed grid displacements, as fractions of the block size.
  static const std::array<std::array<float, 2>, 16>& grid_offsets();
  // The block side used for a w x h frame with block_size = `param` (0 = auto: 32, the
  // paper's size, when the shorter side has 360 pixels or more; 16 below, where 32-pixel
  // blocks would span a large part of the image).
  static int block_side(std::int64_t param, int w, int h);

 protected:
  void check_params() override;
  PassNeeds own_needs() const override;
  std::vector<std::string> own_unused() const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;
  // run() reads the colour in phase I only and writes the whole roi at the end.
  bool run_in_place() const override { return true; }
  // A frame with a usable history is a temporal estimate: only a still (or a sequence's
  // first frame, or the one after a cut) steps back toward its input.
  bool step_back_applies() const override { return !had_history_; }

 private:
  // Phase II (bmfr_fit.cpp).
  void fit_blocks(const Frame& frame, const Image& illum, const std::vector<float>& valid, Image& fitted, int nthreads);
  // TAA of res_ into the roi of `out` and the next history (bmfr_taa.cpp).
  void taa(const Reprojection& rep, bool history, const Roi& roi, Image& out, int nthreads);
  static void write_planar_roi(const float* planar, std::size_t n, int w, const Roi& roi, Image& out, int nthreads);

  TemporalAccumulator phase1_;
  AccumulationBuffer phase3_;
  // Per-frame work buffers, kept between frames so that a steady sequence allocates nothing.
  Image illum_, albedo_, fitted_;
  std::vector<float> fit_valid_;           // phase I's counts, 0 where a pixel is left out of the fit
  std::vector<float> taa_alpha_;           // per pixel: mirror_taa_alpha on mirrors, else 0
  HistoryGuards history_guards_;           // phase I's (prepare/history_guards.h)
  SurfaceClasses classes_;                 // prepare/surface_classes.h, this frame's
  std::vector<float> res_;                 // phase III result (remodulated), planar RGB
  std::vector<float> taa_hist_, taa_next_;  // TAA history (the previous output), planar RGB
  int taa_w_ = 0, taa_h_ = 0;              // size of taa_hist_ (0: none)
  std::int64_t frame_index_ = 0;
  bool last_cut_ = false;
  bool had_history_ = false;  // the last run() blended a usable history
  std::vector<float> residual_scratch_;  // the detail stage's window sums (kernels/residual_shrink.h)
  std::array<double, kStages> stage_ms_{};
  std::array<double, kStages> stage_cpu_ms_{};
};

}  // namespace mcr
