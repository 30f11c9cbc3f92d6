#pragma once
// Float image with interleaved channels, the currency of every pass and filter.
#include <cstddef>
#include <memory>
#include <vector>

namespace mcr {

// Half-open pixel rectangle [x0,x1) x [y0,y1).
struct Roi {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  static Roi all(int w, int h) { return {0, 0, w, h}; }
  Roi clipped(int w, int h) const;  // intersection with the image
  // Grown by `by` pixels on every side, clipped to a w x h image.
  Roi grown(int by, int w, int h) const { return Roi{x0 - by, y0 - by, x1 + by, y1 + by}.clipped(w, h); }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  bool operator==(const Roi& o) const { return x0 == o.x0 && y0 == o.y0 && x1 == o.x1 && y1 == o.y1; }
};

// The spread of an image over the whole frame when the image holds a band of it (a tiled
// run, pipeline/tiled_run.h): what kernels/feature_activity.h asks of a pass, answered for
// the frame instead of the band. Over the pixels whose `channels` first channels are all
// finite ("counted"): the first one in row-major order, and each channel's least and
// greatest value.
struct WholeFrameRange {
  int channels = 0;
  bool any_counted = false, some_uncounted = false;
  float first[4] = {0, 0, 0, 0}, lo[4] = {0, 0, 0, 0}, hi[4] = {0, 0, 0, 0};
};

class Image {
 public:
  Image() = default;
  Image(int width, int height, int channels, float fill = 0.0f);

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  bool empty() const { return data_.empty(); }
  std::size_t pixel_count() const { return std::size_t(width_) * std::size_t(height_); }

  float* pixel(int x, int y) { return data_.data() + index(x, y); }
  const float* pixel(int x, int y) const { return data_.data() + index(x, y); }
  float& at(int x, int y, int c) { return data_[index(x, y) + std::size_t(c)]; }
  float at(int x, int y, int c) const { return data_[index(x, y) + std::size_t(c)]; }

  float* data() { return data_.data(); }
  const float* data() const { return data_.data(); }
  std::vector<float>& storage() { return data_; }
  const std::vector<float>& storage() const { return data_; }

  // A copy holding channels [first, first+count) of this image.
  Image channel_range(int first, int count) const;

  // Set on a band's passes by a tiled run (null otherwise); copies share it.
  std::shared_ptr<const WholeFrameRange> whole_frame;

 private:
  std::size_t index(int x, int y) const {
    return (std::size_t(y) * std::size_t(width_) + std::size_t(x)) * std::size_t(channels_);
  }
  int width_ = 0, height_ = 0, channels_ = 0;
  std::vector<float> data_;
};

}  // namespace mcr
