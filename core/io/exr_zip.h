#pragma once
// OpenEXR's ZIP and ZIPS chunk codec (the file format's, not the library's code) on libdeflate,
// which inflates ~2.3x and deflates ~2x faster than zlib at equal size on render passes
// (bench_sequence): most of a sequence's time went to zlib inside OpenEXR 3.1.
//
// A chunk's raw bytes are split into even and odd bytes (two halves), each byte replaced by
// its difference from the previous one (+128, mod 256), then zlib-compressed. A chunk whose
// compressed form is not smaller is stored raw, which readers tell by its size.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mcr::exr_zip {

// Decodes `packed` into `out` (exactly `raw_size` bytes). False when the data is not a zlib
// stream that inflates to exactly raw_size bytes (a corrupt chunk).
bool decode(const std::uint8_t* packed, std::size_t packed_size, std::uint8_t* out, std::size_t raw_size);

// Encodes `raw` (n bytes) at zlib-style level 1..9 into `out` (resized). Returns the
// compressed size, or 0 when compressing does not make it smaller: store the raw bytes.
std::size_t encode(const std::uint8_t* raw, std::size_t n, int level, std::vector<std::uint8_t>& out);

}  // namespace mcr::exr_zip
