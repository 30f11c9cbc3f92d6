#pragma once
// Shared by the channel-role and frame-reading tests: the channel names Blender writes for
// one view layer of a multilayer EXR with the denoising data passes on.
#include <string>
#include <vector>

namespace mcr::testutil {

inline std::vector<std::string> blender_layer(const std::string& layer) {
  const std::string p = layer + ".";
  return {p + "Combined.R", p + "Combined.G", p + "Combined.B", p + "Combined.A",
          p + "Denoising Albedo.R", p + "Denoising Albedo.G", p + "Denoising Albedo.B",
          p + "Normal.X", p + "Normal.Y", p + "Normal.Z",
          p + "Position.X", p + "Position.Y", p + "Position.Z", p + "Depth.Z",
          p + "Vector.X", p + "Vector.Y", p + "Vector.Z", p + "Vector.W",
          p + "Denoising Normal.X", p + "Denoising Normal.Y", p + "Denoising Normal.Z",
          p + "Denoising Depth.Z"};
}

}  // namespace mcr::testutil
