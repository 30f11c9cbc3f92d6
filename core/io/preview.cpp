#include "io/preview.h"

#include <cmath>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "io/atomic_write.h"
#include "util/error.h"

namespace mcr {

using namespace OIIO;

void write_side_by_side_png(const std::string& path, const std::vector<const Image*>& tiles,
                            const DisplayOptions& options) {
  if (tiles.empty()) throw Error(Errc::Internal, "write_side_by_side_png: no tiles");
  const int h = tiles.front()->height();
  int w = 0;
  for (const Image* t : tiles) {
    if (t->height() != h || t->channels() < 3) throw Error(Errc::SizeMismatch, "preview tiles differ in height");
    w += t->width() + (w ? options.gap : 0);
  }
  ImageBuf strip(ImageSpec(w, h, 3, TypeFloat));
  ImageBufAlgo::zero(strip);
  int x = 0;
  for (const Image* t : tiles) {
    ImageBuf tile(ImageSpec(t->width(), t->height(), t->channels(), TypeFloat));
    tile.set_pixels(tile.roi(), TypeFloat, t->data());
    ImageBufAlgo::paste(strip, x, 0, 0, 0, tile, ROI(0, t->width(), 0, t->height(), 0, 1, 0, 3));
    x += t->width() + options.gap;
  }
  ImageBuf display = to_display(strip, options);
  display.set_write_format(TypeUInt8);
  write_atomic(display, path, "png", TypeUInt8);
}

void write_display_png(const std::string& path, const Image& image, const Roi& region, int zoom,
                       const DisplayTransform& transform) {
  const Roi r = region.empty() ? Roi::all(image.width(), image.height()) : region.clipped(image.width(), image.height());
  if (r.empty() || image.channels() < 3 || zoom < 1) throw Error(Errc::Internal, "write_display_png: empty region or no RGB");
  ImageBuf out(ImageSpec(r.width() * zoom, r.height() * zoom, 3, TypeFloat));
  std::vector<float> row(std::size_t(r.width()) * std::size_t(zoom) * 3);
  for (int y = 0; y < r.height() * zoom; ++y) {
    for (int x = 0; x < r.width() * zoom; ++x) {
      const float* p = image.pixel(r.x0 + x / zoom, r.y0 + y / zoom);
      for (int c = 0; c < 3; ++c) row[std::size_t(x) * 3 + std::size_t(c)] = std::isfinite(p[c]) ? p[c] : 0.0f;  // a peer may write NaN
    }
    out.set_pixels(ROI(0, r.width() * zoom, y, y + 1), TypeFloat, row.data());
  }
  ImageBuf display = to_display(out, transform);
  display.set_write_format(TypeUInt8);
  write_atomic(display, path, "png", TypeUInt8);
}

}  // namespace mcr
