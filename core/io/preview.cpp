#include "io/preview.h"

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

}  // namespace mcr
