#pragma once
// One channel out of interleaved pixels stored in the file's own types (half or float, as
// io/exr_scanline_io.h and OpenImageIO's native reads leave them), as floats.
#include <Imath/half.h>

#include <cstddef>
#include <cstring>

namespace mcr {

// n values: the one at in + i * stride (half when is_half, else float) to out[i * out_stride].
inline void native_channel_to_float(const unsigned char* in, std::size_t stride, bool is_half, std::size_t n, float* out,
                                    std::size_t out_stride) {
  if (is_half) {
    for (std::size_t i = 0; i < n; ++i) {
      Imath::half h;
      std::memcpy(&h, in + i * stride, sizeof h);
      out[i * out_stride] = float(h);
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) std::memcpy(out + i * out_stride, in + i * stride, sizeof(float));
  }
}

}  // namespace mcr
