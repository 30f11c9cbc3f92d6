#pragma once
// Foveated subsampling with an expanded grid (Immonen 2017, 5.2): a uniform grid
// that covers only part of the image is pushed outward by a radial mapping so it
// covers all of it. Inside the fovea the mapping is the identity (every pixel
// sampled); outside, the spacing grows with the distance from the gaze.
#include <cstdint>
#include <vector>

#include "image/pass.h"

namespace mcr {

struct ExpandedGridParams {
  double gaze_x = 0.5, gaze_y = 0.5;  // fraction of width / height
  double fovea_radius = 0.1;          // fraction of the image diagonal, sampled fully
  double density = 0.25;              // target fraction of pixels sampled, (0, 1]
};

class ExpandedGrid {
 public:
  ExpandedGrid(int width, int height, const ExpandedGridParams& params);

  // Radial map from the unexpanded grid to the image: E(d) = d for d <= r0,
  // r0 + (d - r0)(1 + k (d - r0)) beyond. Monotone, so contract() inverts it.
  double expand(double d) const;
  double contract(double e) const;
  double k() const { return k_; }
  double unexpanded_radius() const { return ru_; }

  // 1 where a sample lands, 0 elsewhere (row-major, width*height).
  std::vector<std::uint8_t> mask() const;

 private:
  void set_radius(double ru, double rmax);
  std::size_t count() const;
  int width_, height_;
  double cx_, cy_, r0_, ru_, k_ = 0;
};

// A copy of the frame as a sparse render would give it: every pass zeroed at the
// unsampled pixels and a sample_count pass (1 sampled, 0 hole) added.
Frame sparsify(const Frame& frame, const std::vector<std::uint8_t>& mask);

}  // namespace mcr
