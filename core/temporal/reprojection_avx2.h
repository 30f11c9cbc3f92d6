#pragma once
// GeometryHistory::row's discard tests for 8 pixels at a time (AVX2), on the x86-64 GCC
// build; the scalar loop in reprojection.cpp does the rest of a row and other targets.
#include <cstddef>
#include <cstdint>

namespace mcr::detail {

// Row y of the tests, inputs and outputs as GeometryHistory::row uses them; position and
// normal with 3 channels, a history present.
struct TapRow {
  int w, h, y;
  const float* prow;           // current position, row y (row y-1 / y+1 at -/+ 3w when they exist)
  const float* nrow;           // current normal, row y
  float* grow;                 // out: row y of the packed geometry records (kGeoRecord floats per pixel)
  const float* mrow;           // motion row (nullptr: none), mch channels
  int mch;
  const float* hgeo;           // previous frame's packed records (whole frame)
  float thr2, cs, cs2;
  bool relative;
  float* prev_x;  // row y of the outputs
  float* prev_y;
  std::uint8_t* taps;
  std::uint8_t* inside;
};

// Whether this CPU runs tap_row_avx2().
bool tap_row_avx2_available();
// Pixels [x0, x1) of the row, 1 <= x0, x1 <= w - 1 (the horizontal neighbours exist),
// x1 - x0 a multiple of 8: their records and tests. Returns the pixels with no kept tap. The same float operations
// in the same order as the scalar loop: the same results bit for bit.
std::size_t tap_row_avx2(const TapRow& a, int x0, int x1);

}  // namespace mcr::detail
