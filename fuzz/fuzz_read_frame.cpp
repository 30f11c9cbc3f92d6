// Fuzz target: the frame reader on mutated flat EXRs (seeds: make_seeds.py, "flat": Blender-like
// multilayer, multi-part, tiled, every compression, half and float).
#include "exr_file_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mcr::fuzz::write_input(data, size);
  mcr::fuzz::read_every_way();
  return 0;
}
