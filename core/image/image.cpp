#include "image/image.h"

#include <algorithm>

#include "util/error.h"

namespace mcr {

Roi Roi::clipped(int w, int h) const {
  return {std::max(x0, 0), std::max(y0, 0), std::min(x1, w), std::min(y1, h)};
}

Image::Image(int width, int height, int channels, float fill)
    : width_(width), height_(height), channels_(channels) {
  if (width < 0 || height < 0 || channels < 0)
    throw Error(Errc::Internal, "Image: negative size");
  data_.assign(std::size_t(width) * std::size_t(height) * std::size_t(channels), fill);
}

Image Image::channel_range(int first, int count) const {
  if (first < 0 || count < 0 || first + count > channels_)
    throw Error(Errc::Internal, "Image::channel_range out of bounds");
  Image out(width_, height_, count);
  const std::size_t n = pixel_count();
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < count; ++c)
      out.data_[i * count + c] = data_[i * channels_ + first + c];
  return out;
}

}  // namespace mcr
