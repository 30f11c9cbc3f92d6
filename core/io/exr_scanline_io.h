#pragma once
// Flat one-part scanline OpenEXR files with no, ZIP or ZIPS compression, read and written
// through OpenEXRCore's chunk API with the ZIP codec on libdeflate (io/exr_zip.h), chunks in
// parallel. Renders (Blender writes zip) and mcrecon's own outputs are such files; every other
// file goes through OpenImageIO as before. Same pixels, bit for bit, either way.
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "image/pass.h"
#include "io/native_pixels.h"

namespace mcr {

// Off: every EXR goes through OpenImageIO (the path before this one; the benchmark compares
// them). On by default; MCRECON_EXR_IO=openimageio in the environment turns it off.
void set_exr_scanline_io(bool on);
bool exr_scanline_io();


// A file of those opened to read rows, as often as needed (a frame read in bands).
class ExrScanlineReader {
 public:
  // Null when the file is not one of the above, or its channels are not the layout's (half or
  // float as laid out). Throws ReadFailed when its chunk table cannot be read.
  static std::unique_ptr<ExrScanlineReader> open(const std::string& path, int width, int height, const NativeLayout& layout);
  ~ExrScanlineReader();
  // Rows per chunk: reads that start on a multiple of it decode each chunk once.
  int chunk_rows() const;
  // Rows [y0, y1) of the data window (0: its first row) into dst, (y1 - y0) rows of width
  // pixels of layout.stride bytes. Throws ReadFailed on a chunk that does not decode (truncated
  // or corrupt), naming the file and the row.
  void read(int y0, int y1, unsigned char* dst);

 private:
  struct Impl;
  explicit ExrScanlineReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Reads all of `path`'s pixels (width x height, as OpenImageIO's header said) into dst when
// the file is one of the above and its channels are the layout's, half or float as laid out.
// False, with nothing read, for any other file. Throws ReadFailed on a chunk that does not
// decode (truncated or corrupt), naming the file and the row.
bool read_exr_scanlines(const std::string& path, int width, int height, const NativeLayout& layout, unsigned char* dst);

// Whether write_exr_scanlines writes this compression ("none", "zip", "zips", "zip:N", "zips:N").
bool exr_scanline_compression(const std::string& compression);

// Writes float channels (pixels interleaved in `names` order) to the open descriptor fd,
// as an OpenEXR file with the given windows, compression and string attributes (plus
// Software and capDate, as OpenImageIO writes them). Returns 0, or the errno of the first
// failed write; throws WriteFailed for anything else, naming `path`.
int write_exr_scanlines(int fd, const std::string& path, int width, int height, const PixelWindow& window,
                        const std::vector<std::string>& names, const float* pixels, const std::string& compression,
                        const std::vector<std::pair<std::string, std::string>>& attributes);

}  // namespace mcr
