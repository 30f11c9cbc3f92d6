// Fuzz target: the frame reader on mutated deep EXRs (seeds: make_seeds.py, "deep": deep
// scanline and deep tiled, 0, 1 and several samples per pixel). The same reads as
// fuzz_read_frame; a target of its own so that its corpus stays deep.
#include "exr_file_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mcr::fuzz::write_input(data, size);
  mcr::fuzz::read_every_way();
  return 0;
}
