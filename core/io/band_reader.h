#pragma once
// A file's rows on demand for a tiled run (pipeline/tiled_run.h): only the passes the run
// reads, one band at a time. The file is decoded in chunks of rows (every channel of a few
// rows, the needed ones copied out), so memory is one band's needed passes plus a chunk,
// whatever the file holds. One-part flat files (scanline or tiled); a deep or multi-part file,
// loose pass files (--pass ROLE=FILE) and half buffers are read whole (read_frame).
#include <memory>
#include <string>
#include <vector>

#include "io/frame_reader.h"
#include "pipeline/tiled_run.h"

namespace mcr {

class FileBands : public BandSource {
 public:
  // Throws as read_frame (FileNotFound, NotAnImage, MissingPass naming the file), and
  // InvalidArgument when the file cannot be read in bands (why_not_bands() beforehand).
  // roles: the passes to keep (the filter's needs, required and optional); the colour always.
  FileBands(const std::string& path, const ReadOptions& options, const std::vector<Role>& roles);
  ~FileBands() override;
  int width() const override;
  int height() const override;
  Frame rows(int y0, int y1) override;
  void overlap_hint(int rows) override;
  // Channels decoded per pixel (the file's) and kept per pixel (the passes kept).
  int file_channels() const;
  int kept_channels() const;
  // Milliseconds spent in rows() so far (decoding and copying).
  double read_ms() const;
  // The frame's header and passes with one row of pixels (names, roles, window, layers).
  const Frame& layout() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// "" when `path` can be read in bands under `options`, else why not (a deep file, ...).
std::string why_not_bands(const std::string& path, const ReadOptions& options);

}  // namespace mcr
