#include "report/report_images.h"

#include <algorithm>
#include <cmath>

#include <OpenImageIO/imagebuf.h>

#include "io/atomic_write.h"
#include "util/error.h"

namespace mcr {

Image relative_error_map(const Image& reference, const Image& image) {
  if (reference.width() != image.width() || reference.height() != image.height() || reference.channels() < 3 ||
      image.channels() < 3)
    throw Error(Errc::SizeMismatch, "relative_error_map: the image and its reference differ in size");
  Image map(image.width(), image.height(), 1);
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      double sum = 0;
      for (int c = 0; c < 3; ++c) {
        const float r0 = reference.at(x, y, c), x0 = image.at(x, y, c);
        const double r = std::isfinite(r0) ? r0 : 0.0, v = std::isfinite(x0) ? x0 : 0.0;
        sum += (v - r) * (v - r) / (r * r + 0.01);
      }
      map.at(x, y, 0) = float(sum / 3);
    }
  return map;
}

namespace {

// Summed-area table of one channel: window sums in O(1).
struct Integral {
  int w = 0, h = 0;
  std::vector<double> s;  // (w+1) x (h+1)
  explicit Integral(const Image& m) : w(m.width()), h(m.height()), s(std::size_t(w + 1) * std::size_t(h + 1), 0.0) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        at(x + 1, y + 1) = m.at(x, y, 0) + at(x, y + 1) + at(x + 1, y) - at(x, y);
  }
  double& at(int x, int y) { return s[std::size_t(y) * std::size_t(w + 1) + std::size_t(x)]; }
  double sum(const Roi& r) const {
    auto v = [&](int x, int y) { return s[std::size_t(y) * std::size_t(w + 1) + std::size_t(x)]; };
    return v(r.x1, r.y1) - v(r.x0, r.y1) - v(r.x1, r.y0) + v(r.x0, r.y0);
  }
};

// The size_w x size_h window of r with the highest sum (first found on ties: top-left).
Roi best_window(const Integral& in, const Roi& r, int size_w, int size_h, const std::vector<Roi>& avoid) {
  Roi best{};
  double best_sum = -1;
  for (int y = r.y0; y + size_h <= r.y1; ++y)
    for (int x = r.x0; x + size_w <= r.x1; ++x) {
      const Roi c{x, y, x + size_w, y + size_h};
      bool overlaps = false;
      for (const Roi& a : avoid) overlaps |= c.x0 < a.x1 && a.x0 < c.x1 && c.y0 < a.y1 && a.y0 < c.y1;
      if (overlaps) continue;
      const double s = in.sum(c);
      if (s > best_sum) {
        best_sum = s;
        best = c;
      }
    }
  return best;
}

}  // namespace

std::vector<CropRegion> highest_error_regions(const std::vector<const Image*>& maps, int count, int size, int zoom) {
  if (maps.empty()) return {};
  const int w = maps.front()->width(), h = maps.front()->height();
  Image total(w, h, 1);
  for (const Image* m : maps)
    for (std::size_t i = 0; i < total.storage().size(); ++i) total.storage()[i] += m->storage()[i];
  const Integral in(total);
  const int cw = std::min(size, w), ch = std::min(size, h);
  std::vector<CropRegion> out;
  std::vector<Roi> taken;
  for (int k = 0; k < count; ++k) {
    const Roi crop = best_window(in, Roi::all(w, h), cw, ch, taken);
    if (crop.empty()) break;
    taken.push_back(crop);
    out.push_back({crop, best_window(in, crop, std::min(zoom, cw), std::min(zoom, ch), {})});
  }
  return out;
}

void write_error_map(const std::string& path, const Image& map) {
  OIIO::ImageSpec spec(map.width(), map.height(), 1, OIIO::TypeFloat);
  spec.channelnames = {"Y"};
  OIIO::ImageBuf buf(spec);
  buf.set_pixels(buf.roi(), OIIO::TypeFloat, map.data());
  write_atomic(buf, path, "openexr", OIIO::TypeFloat);
}

}  // namespace mcr
