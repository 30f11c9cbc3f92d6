#pragma once
// First-hit holes (preparation step, with the holes step): Blender writes Depth, Position and
// Vector from a pixel's first sample alone, not as a mean of its samples. Where that sample met
// no surface (Depth 1e10, Position 0) though others did (the geometric Normal pass, their mean,
// is not 0), the pixel's position and depth describe nothing it shows: in fog the first sample
// scatters in the air at random pixels (the held-out fog still: 27% of its pixels, salt and
// pepper over the frame), and at an edge against the world it misses at random. The feature
// filters read that as geometry edges between neighbours that see the same thing, and smooth
// nothing there. Those pixels take the mean position and depth of the pixels around them whose
// first sample met a surface: in the nearest square ring (up to kFirstHitRadius pixels away)
// that holds one; none: left as they are. The sky (normal 0: no sample met anything) is left
// as it is. Chosen on a tune scene of the class (glossy in a homogeneous fog, not kept):
// bilateral 0.0196 -> 0.0169, atrous 0.0204 -> 0.0171 at 16 spp; the held-out fog README.
#include <cstddef>
#include <vector>

#include "image/pass.h"

namespace mcr {

inline constexpr int kFirstHitRadius = 4;
inline constexpr float kNoSurfaceDepth = 1e9f;  // Blender writes 1e10 where a ray met nothing

// What each pixel's first sample met, over `work` (clipped to the frame) grown by
// kFirstHitRadius (the pixels a fill reads); kMissed elsewhere. A hole lies inside `work`.
enum : unsigned char { kFirstHitMet = 0, kFirstHitHole = 1, kFirstHitMissed = 2 };
struct FirstHitMap {
  std::vector<unsigned char> state;  // width x height, row-major; empty when there is no hole
  std::size_t holes = 0;
};
// Empty when there is no hole, or no depth or normal pass to tell them by (they are read where
// the frame has them, not asked for; a run in bands reads them for it).
FirstHitMap first_hit_map(const Frame& frame, const Roi& work, int nthreads);

// Fills frame's position passes, and its depth passes where they say no surface, at the map's
// holes. Returns the number of holes filled (a hole with no pixel that met a surface within
// kFirstHitRadius stays as it is).
std::size_t fill_first_hit_holes(Frame& frame, const FirstHitMap& map, int nthreads);

}  // namespace mcr
