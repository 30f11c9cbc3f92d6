#pragma once
#include "filters/filter.h"

namespace mcr {

// Shirley et al. 2011: each pixel from the individual samples around it, swept front to back
// (filters/samples/sweep_kernel.h), for defocus, motion blur and transparency. Reads the
// frame's deep (per-sample) buffer: R, G, B and Z per sample (required); A (coverage, default
// 1), dx, dy (position in the pixel, default spread over it), blur (denoising diameter in
// pixels), mx, my (motion in pixels over the shutter); the camera for the circle of confusion
// from the parameters or the header attributes mcrecon:lens_mm, mcrecon:fstop,
// mcrecon:focus_distance, mcrecon:sensor_width_mm.
class SweepFilter : public Filter {
 public:
  SweepFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();

  // How many pixels of the last execute() the sweep had to sort (the rest had one scale).
  std::size_t sorted_pixels() const { return sorted_; }
  bool used_layered() const { return layered_; }

 protected:
  void check_params() override;
  std::vector<std::string> own_unused() const override;
  bool step_back_applies() const override { return false; }
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  std::size_t sorted_ = 0;
  bool layered_ = false;
};

}  // namespace mcr
