#pragma once
// Display-referred previews: linear RGB images side by side, through an
// OpenColorIO display transform (Blender's config by default), written as PNG.
#include <string>
#include <vector>

#include "image/image.h"
#include "io/display_transform.h"

namespace mcr {

struct DisplayOptions : DisplayTransform {
  int gap = 4;  // pixels between tiles
};

// Writes tiles left to right (all the same height) as an 8-bit PNG via temp + rename.
void write_side_by_side_png(const std::string& path, const std::vector<const Image*>& tiles,
                            const DisplayOptions& options = {});

// One image's region (the whole image when `region` is empty), enlarged `zoom` times by
// repeating pixels (so that single pixels stay visible), as an 8-bit PNG via temp + rename.
void write_display_png(const std::string& path, const Image& image, const Roi& region = {}, int zoom = 1,
                       const DisplayTransform& transform = {});

}  // namespace mcr
