#pragma once
// Writing a filter result: an RGBA float EXR, optionally with the input's passes and the
// denoised components, or a display-referred PNG/JPEG/TIFF (io/output_format.h).
#include <string>
#include <utility>
#include <vector>

#include "image/pass.h"
#include "io/display_transform.h"

namespace mcr {

struct WriteOptions {
  bool keep_passes = false;       // carry every non-colour channel of the input
  std::string compression = "zip";
  std::vector<std::pair<std::string, std::string>> attributes;  // extra header strings
  // With components=light_passes: write each denoised component as its own layer
  // (pipeline/denoise_session.h fills `layers`).
  bool keep_components = false;
  // Extra RGB layers, written as float NAME.R, NAME.G, NAME.B after R,G,B,A.
  std::vector<std::pair<std::string, const Image*>> layers;
  // PNG, JPEG, TIFF: the view the scene-linear result goes through, and the bits per channel
  // (0: 8 for PNG and JPEG, 16 for TIFF; 16 only for PNG and TIFF).
  DisplayTransform display;
  int bits = 0;
};

// Throws InvalidArgument (naming the path and the setting) unless `path` names a format
// mcrecon writes and the options fit it: layers, kept passes and components need EXR; the
// EXR compression must be one OpenImageIO writes; the display transform must exist.
void check_write(const std::string& path, const WriteOptions& options);

// R,G,B from rgb and A from the input's alpha pass (1 when absent): the pixels write_result
// writes first, interleaved (4 channels), for a front end that hands them over in memory.
Image rgba_result(const Image& rgb, const Frame& input);

// R,G,B from rgb, A from the input's alpha pass (1 when absent), via temp + rename, in the
// format the extension names (check_write first). JPEG has no alpha: R,G,B only.
void write_result(const std::string& path, const Image& rgb, const Frame& input, const WriteOptions& options = {});

}  // namespace mcr
