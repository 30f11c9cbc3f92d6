#pragma once
// Reprojection of the previous frame into the current one with the motion pass, and
// the per-tap discard tests of BMFR phase I (Koskela et al. 2019, 4.1; Schied 2017):
// each of the four bilinear taps of the previous frame is kept only when its world
// position is close to the current pixel's and its normal agrees.
//
// Motion convention (Blender's Vector pass, verified on samples/data anim frames 2-16:
// median world distance 0.0003 with this sign against 0.04 with the other): X and Y are
// previous minus current in pixels with x to the right and Y UP, so the current pixel
// (x, y) (rows going down, pixel centres at integers) was at (x + V.x, y - V.y).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace mcr {

struct ReprojectionParams {
  // World-position discard test. relative: threshold in pixel footprints, the footprint
  // being the world distance to the nearest horizontal / vertical neighbour (larger of
  // the two) in the current frame; absolute: threshold in world units.
  bool relative_position = true;
  double position_threshold = 3.0;
  // Normal test: cosine between current and previous normal must be >= this.
  // Pixels whose normals are both (near) zero (background) pass it.
  double normal_cos = 0.9;
  // A camera cut is declared when, with a history present, more than this fraction of
  // the pixels keep no tap at all; the history is then dropped (reported as cut).
  double cut_fraction = 0.9;
};

// Where every pixel of the current frame was in the previous one, and which of its
// four bilinear taps passed the discard tests.
struct Reprojection {
  int width = 0, height = 0;
  std::vector<float> prev_x, prev_y;  // position in the previous frame (pixel centres at integers)
  // bit k set: tap k kept; taps are (x0,y0), (x0+1,y0), (x0,y0+1), (x0+1,y0+1),
  // x0 = floor(prev_x), y0 = floor(prev_y).
  std::vector<std::uint8_t> taps;
  std::vector<std::uint8_t> inside;  // bit k set: tap k lies inside the previous frame (no tests)
  bool has_history = false;   // a previous frame of the same size existed
  bool cut = false;           // history dropped by the cut test (taps all 0 then)
  std::size_t discarded = 0;  // pixels with no kept tap

  // Bilinear sample of `history` (interleaved, `channels`) for pixel i over the taps in
  // `mask` (and only those where accept(tap index) is true), normalised by the kept
  // weights only. Returns the kept weight sum (0: nothing usable, out untouched).
  template <class Accept>
  float sample(std::size_t i, const float* history, int channels, std::uint8_t mask, float* out, Accept&& accept) const;
  float sample(std::size_t i, const float* history, int channels, float* out) const {
    return sample(i, history, channels, taps[i], out, [](std::size_t) { return true; });
  }
};

// Keeps the previous frame's geometry; update() compares the current frame with it,
// then stores the current frame for the next call.
class GeometryHistory {
 public:
  // position, normal: world space, 3+ channels; motion: Vector pass (2+ channels) or
  // nullptr for zero motion. All the same size. A size change drops the history.
  Reprojection update(const Image& position, const Image& normal, const Image* motion,
                      const ReprojectionParams& params, int nthreads);
  // Same, into `r` (its buffers are reused from frame to frame: no allocation once sized).
  void update(const Image& position, const Image& normal, const Image* motion, const ReprojectionParams& params,
              int nthreads, Reprojection& r);
  void reset();
  bool empty() const { return geo_.empty(); }

  // The same update split up so that a caller can fuse its own per-row work with it
  // (TemporalAccumulator does the accumulation of row y right after its reprojection):
  // begin() sizes `r`; row(y) fills row y of `r` and stores row y of the current
  // geometry as the next history (returns the pixels of the row with no kept tap);
  // finish() decides the camera cut (then every tap is cleared; returns true) and makes
  // the stored geometry the history. Rows may run in parallel between begin and finish.
  void begin(const Image& position, const Image& normal, const Image*& motion, Reprojection& r);
  std::size_t row(int y, const Image& position, const Image& normal, const Image* motion,
                  const ReprojectionParams& params, Reprojection& r);
  bool finish(const ReprojectionParams& params, Reprojection& r, std::size_t discarded);

 private:
  // Previous frame's geometry, one 32-byte record per pixel: position xyz, normal xyz,
  // squared normal length when position and normal are finite (else NaN), 0. A tap
  // test reads one record (one load) instead of three arrays.
  std::vector<float> geo_, next_geo_;  // next_: the current frame, filled by row()
  int geo_w_ = 0, geo_h_ = 0;
};

// Floats per record of GeometryHistory's packed geometry.
constexpr int kGeoRecord = 8;

// floor() as an int for |v| < 2^31 (reprojected positions are kept within +-1e7): inline
// code instead of a libm call on the baseline x86-64 target.
inline int floor_int(float v) {
  const int i = int(v);
  return i - (float(i) > v ? 1 : 0);
}

// The previous-frame position of pixel (x, y) for a motion pass (or nullptr).
inline void previous_position(const Image* motion, int x, int y, float& px, float& py) {
  px = float(x);
  py = float(y);
  if (!motion) return;
  const float* m = motion->pixel(x, y);
  px += m[0];
  py -= m[1];
}

template <class Accept>
float Reprojection::sample(std::size_t i, const float* history, int channels, std::uint8_t mask, float* out,
                           Accept&& accept) const {
  if (!mask) return 0.0f;
  const float px = prev_x[i], py = prev_y[i];
  const int x0 = floor_int(px), y0 = floor_int(py);
  const float fx0 = float(x0), fy0 = float(y0);
  const float fx = px - fx0, fy = py - fy0;
  const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  const int tx[4] = {x0, x0 + 1, x0, x0 + 1}, ty[4] = {y0, y0, y0 + 1, y0 + 1};
  float sum = 0;
  float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int k = 0; k < 4; ++k) {
    if (!(mask & (1u << k)) || w[k] <= 0.0f) continue;
    const std::size_t t = std::size_t(ty[k]) * std::size_t(width) + std::size_t(tx[k]);
    if (!accept(t)) continue;
    sum += w[k];
    for (int c = 0; c < channels; ++c) acc[c] += w[k] * history[t * std::size_t(channels) + std::size_t(c)];
  }
  if (sum <= 1e-6f) return 0.0f;
  for (int c = 0; c < channels; ++c) out[c] = acc[c] / sum;
  return sum;
}

}  // namespace mcr
