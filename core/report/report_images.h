#pragma once
// The report's pictures: where the filters fail (crops of the highest error) and how much
// (per-pixel error maps).
#include <string>
#include <vector>

#include "image/image.h"

namespace mcr {

struct CropRegion {
  Roi crop;  // shown at 1:1
  Roi zoom;  // inside `crop`, shown at 4:1
};

// Per pixel, the mean over R, G, B of (x - r)^2 / (r^2 + 0.01) (the relMSE's terms); non-finite
// values count as 0, as in the metrics. One channel.
Image relative_error_map(const Image& reference, const Image& image);

// Up to `count` non-overlapping size x size windows with the highest summed error of `maps`
// (the filters' error maps added), highest first; each with the zoom x zoom window of highest
// error inside it. Windows are clipped to the image (a frame smaller than `size` gives one).
std::vector<CropRegion> highest_error_regions(const std::vector<const Image*>& maps, int count = 2, int size = 64,
                                              int zoom = 16);

// A one-channel float OpenEXR ("Y"), temp file then rename.
void write_error_map(const std::string& path, const Image& map);

}  // namespace mcr
