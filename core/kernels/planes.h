#pragma once
// Planar (SoA) copies of the passes, made once per execute() by the edge-avoiding
// filters (bilateral, atrous) and the foveated Gaussian: the layout every plane of one
// execute() shares (PlaneBox), the colour's planes (planar_colour) and their way back
// into an image (store_colour), and the row helpers that split interleaved pixels into
// planes. The row loops are written once and built per instruction set
// (MCR_ISA_VERSIONS, util/isa.h: every build gives the same bits). The feature guides
// (kernels/feature_guides.h) are planes of this layout too.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace mcr {

// Layout of every plane of one execute(): the pixels of `box` (absolute image
// coordinates), row-major, each row padded by kPlanePad zero columns on both
// sides so that the kernel's vector loads never need a bounds check.
inline constexpr int kPlanePad = 16;  // >= the widest vector (16 lanes)
struct PlaneBox {
  Roi box;
  int stride = 0;
  PlaneBox() = default;
  explicit PlaneBox(const Roi& b) : box(b), stride((b.empty() ? 0 : b.width()) + 2 * kPlanePad) {}
  std::size_t size() const { return box.empty() ? 0 : std::size_t(stride) * std::size_t(box.height()); }
  std::size_t index(int x, int y) const {
    return std::size_t(y - box.y0) * std::size_t(stride) + std::size_t(x - box.x0 + kPlanePad);
  }
  std::vector<float> plane(float fill = 0.0f) const;  // pads are 0 whatever the fill
  // Makes v a plane of this layout reusing its memory (no page faults from one
  // frame to the next): pads zeroed, interior left as it was unless `fill` is given.
  void prepare(std::vector<float>& v) const;
  void prepare(std::vector<float>& v, float fill) const;
};

// Planar copy of the RGB input over a box.
struct ColourPlanes {
  PlaneBox pb;
  std::vector<float> c[3];  // non-finite pixels hold 0 (all three channels)
  std::vector<float> ok;    // 1 where all three channels are finite, else 0
  float scale = 1.0f;       // power of two the colour was multiplied by (exact; undone on
                            // output). 1 while max |c| is in [2^-20, 2^100]; above, max |c|
                            // is brought below 2^100 so no weighted sum of up to 129^2 taps
                            // can overflow; below, it is raised (by at most 2^64) so tiny
                            // images (1e-30) keep full precision clear of the denormals
};
// clamp > 0: finite channels are clamped to [-clamp, clamp] first (firefly clamp).
// Fills `p`, reusing the memory it holds from an earlier call.
void planar_colour(const Image& colour, const Roi& box, double clamp, int nthreads, ColourPlanes& p);

// out(x, y, c) = planes[c] / scale over roi (rounded from double, clamped to +-FLT_MAX).
void store_colour(const float* const planes[3], const PlaneBox& pb, float scale, const Roi& roi, Image& out,
                  int nthreads);

// The row helpers of planar_colour and gather_guides (kernels/feature_guides.h). One
// row of n pixels of a 3-channel image into three planes: a pixel with a non-finite
// channel becomes 0 with ok 0; finite channels are clamped to [-lim, lim]. Returns the
// largest |value| written, as its bit pattern (a non-negative float's bits order as
// the float). Built per instruction set.
std::uint32_t split_rgb3(const float* __restrict v, int n, float lim, float* __restrict c0, float* __restrict c1,
                         float* __restrict c2, float* __restrict ok);
// The same for any channel count ch: the first `planes` channels into c[0..planes),
// the last one repeated when the image has fewer (not vectorised).
std::uint32_t split_any(const float* v, int ch, int n, int planes, float lim, float* const* c, float* ok);

}  // namespace mcr
