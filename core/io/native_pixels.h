#pragma once
// Interleaved pixels in the file's own types (half or float), as io/exr_scanline_io.h and
// OpenImageIO's native reads leave them: their layout, and one channel out of them as floats.
#include <Imath/half.h>
#include <OpenImageIO/imageio.h>

#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

namespace mcr {

// Where each channel is in a pixel of `stride` bytes: the channel named names[c] at byte
// offset[c], half when is_half[c] else float.
struct NativeLayout {
  std::vector<std::string> names;
  std::vector<std::size_t> offset;
  std::vector<char> is_half;
  std::size_t stride = 0;
};

// The layout OpenImageIO's native read of spec gives; false when a channel is neither half nor float.
inline bool native_layout_of(const OIIO::ImageSpec& spec, NativeLayout& layout) {
  layout = NativeLayout{};
  for (int c = 0; c < spec.nchannels; ++c) {
    const OIIO::TypeDesc t = spec.channelformat(c);
    if (t != OIIO::TypeHalf && t != OIIO::TypeFloat) return false;
    layout.names.push_back(spec.channelnames[std::size_t(c)]);
    layout.offset.push_back(layout.stride);
    layout.is_half.push_back(t == OIIO::TypeHalf);
    layout.stride += t.size();
  }
  return true;
}

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
