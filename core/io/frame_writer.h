#pragma once
// Writing a filter result as an RGBA float EXR, optionally with the input's passes.
#include <string>
#include <utility>
#include <vector>

#include "image/pass.h"

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
};

// R,G,B from rgb, A from the input's alpha pass (1 when absent), via temp + rename.
void write_result(const std::string& path, const Image& rgb, const Frame& input, const WriteOptions& options = {});

}  // namespace mcr
