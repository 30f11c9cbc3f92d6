#include "io/preview.h"

#include <OpenImageIO/color.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <filesystem>

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
  std::error_code ec;
  if (!std::filesystem::exists(options.config, ec))
    throw Error(Errc::FileNotFound, "OpenColorIO config '" + options.config + "' not found (is blender installed?)");
  ColorConfig config(options.config);
  if (config.has_error()) throw Error(Errc::InvalidArgument, "OpenColorIO config '" + options.config + "': " + config.geterror());
  ImageBuf display = ImageBufAlgo::ociodisplay(strip, options.display, options.view, options.from, "", false, "", "", &config);
  if (display.has_error())
    throw Error(Errc::InvalidArgument, "display transform " + options.display + "/" + options.view + " failed: " + display.geterror());
  display.set_write_format(TypeUInt8);
  write_atomic(display, path, "png", TypeUInt8);
}

}  // namespace mcr
