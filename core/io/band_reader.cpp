#include "io/band_reader.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <chrono>
#include <cstring>

#include "io/exr_scanline_io.h"
#include "io/input_limits.h"
#include "io/native_pixels.h"
#include "io/spec_window.h"
#include "util/error.h"
#include "util/parallel.h"

OIIO_NAMESPACE_USING

namespace mcr {

namespace {

constexpr int kChunkRows = 32;     // rows decoded at a time (two zip blocks of 16)
constexpr int kMaxTileRows = 1024;  // a tiled file is decoded a row of tiles at a time

std::unique_ptr<ImageInput> open_for_bands(const std::string& path, std::string& why) {
  check_image_file(path);  // FileNotFound, NotAnImage, a header its bytes cannot back
  auto in = open_image(path);  // its extension's reader, as check_image_file opened it
  const ImageSpec& spec = in->spec();
  if (spec.deep) why = "it is a deep file";
  else if (in->seek_subimage(1, 0)) why = "it has several parts";
  else if (spec.depth > 1) why = "it is a volume";
  else if (spec.tile_width > 0 && spec.tile_height > kMaxTileRows)
    why = "its tiles are " + std::to_string(spec.tile_height) + " rows tall (bands read whole rows of tiles, at most " +
          std::to_string(kMaxTileRows) + ")";
  in->seek_subimage(0, 0);
  return in;
}

}  // namespace

std::string why_not_bands(const std::string& path, const ReadOptions& options) {
  if (!options.second_half.empty()) return "the frame is the mean of two half buffers";
  if (!loose_pass_files(options).empty()) return "a pass comes from another file (--pass ROLE=FILE)";
  std::string why;
  open_for_bands(path, why);
  return why;
}

struct FileBands::Impl {
  std::string path;
  std::unique_ptr<ImageInput> in;
  ImageSpec spec;
  Frame layout;
  // Per kept pass: the file channel of each of its image's channels.
  std::vector<std::vector<int>> sources;
  // The last band given: bands in order overlap by their halos, whose rows are copied from
  // it instead of decoded again.
  Frame last;  // its last rows only: [last_y0, last_y1)
  int last_y0 = 0, last_y1 = 0, keep = 0;
  double read_ms = 0;
  // A scanline zip, zips or uncompressed file of half and float channels: read in its own
  // types through io/exr_scanline_io.h (libdeflate), as read_frame reads it; else OpenImageIO,
  // as floats. `native` lays out the rows either gives.
  std::unique_ptr<ExrScanlineReader> scan;
  NativeLayout native;
};

FileBands::FileBands(const std::string& path, const ReadOptions& options, const std::vector<Role>& roles)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = path;
  const std::string why = why_not_bands(path, options);
  if (!why.empty()) throw Error(Errc::InvalidArgument, "'" + path + "' cannot be read in bands: " + why);
  std::string ignored;
  m.in = open_for_bands(path, ignored);
  m.spec = m.in->spec();
  const int nch = m.spec.nchannels;
  std::vector<std::string> names(m.spec.channelnames.begin(), m.spec.channelnames.end());
  // The passes as read_frame chooses them, from one row of zeros: names and roles only.
  ReadOptions layout_options = options;
  layout_options.keep_extra = false;
  Frame all = frame_from_channels(path, m.spec.width, 1, names, std::vector<float>(std::size_t(m.spec.width) * nch, 0.0f),
                                  layout_options);
  m.layout = all.header(m.spec.width, 1);
  m.layout.window = window_of(m.spec);
  for (Pass& p : all.passes) {
    const bool keep = p.role == Role::Colour || std::find(roles.begin(), roles.end(), p.role) != roles.end();
    if (!keep) continue;
    std::vector<int> src;
    for (const std::string& c : p.channels) {
      const auto it = std::find(names.begin(), names.end(), c);
      if (it == names.end()) throw Error(Errc::Internal, "band reader: channel '" + c + "' not in '" + path + "'");
      src.push_back(int(it - names.begin()));
    }
    if (int(src.size()) != p.image.channels())
      throw Error(Errc::Internal, "band reader: pass '" + p.name + "' of '" + path + "' has another channel count");
    m.sources.push_back(std::move(src));
    m.layout.passes.push_back(std::move(p));
  }
  if (m.spec.tile_width == 0 && native_layout_of(m.spec, m.native))
    m.scan = ExrScanlineReader::open(path, m.spec.width, m.spec.height, m.native);
  if (!m.scan) {  // OpenImageIO's reads, as floats
    m.native = NativeLayout{};
    m.native.names = names;
    for (int c = 0; c < nch; ++c) m.native.offset.push_back(std::size_t(c) * sizeof(float)), m.native.is_half.push_back(0);
    m.native.stride = std::size_t(nch) * sizeof(float);
  }
}

FileBands::~FileBands() = default;

void FileBands::overlap_hint(int rows) { impl_->keep = std::max(0, rows); }

int FileBands::width() const { return impl_->spec.width; }
int FileBands::height() const { return impl_->spec.height; }
int FileBands::file_channels() const { return impl_->spec.nchannels; }
int FileBands::kept_channels() const {
  int n = 0;
  for (const Pass& p : impl_->layout.passes) n += p.image.channels();
  return n;
}
const Frame& FileBands::layout() const { return impl_->layout; }

double FileBands::read_ms() const { return impl_->read_ms; }

Frame FileBands::rows(int y0, int y1) {
  Impl& m = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  const int w = m.spec.width, nch = m.spec.nchannels;
  if (y0 < 0 || y1 > m.spec.height || y0 >= y1)
    throw Error(Errc::Internal, "band reader: rows " + std::to_string(y0) + ".." + std::to_string(y1) + " outside '" + m.path + "'");
  Frame f = m.layout.header(w, y1 - y0);
  f.window = m.layout.window;
  for (const Pass& p : m.layout.passes) f.passes.push_back(with_pixels(p, Image(w, y1 - y0, p.image.channels())));
  // Rows the last band holds (the overlap at the top of this one): copied.
  int from = y0;
  if (m.last_y1 > y0 && m.last_y0 <= y0) {
    const int c1 = std::min(y1, m.last_y1);
    for (std::size_t k = 0; k < f.passes.size(); ++k) {
      Image& im = f.passes[k].image;
      const std::size_t row = std::size_t(w) * std::size_t(im.channels());
      std::memcpy(im.pixel(0, 0), m.last.passes[k].image.pixel(0, y0 - m.last_y0), row * std::size_t(c1 - y0) * sizeof(float));
    }
    from = c1;
  }
  // Scanline files in chunks of kChunkRows, starting on the scanline reader's chunk grid (each
  // zip block decoded once); tiled ones a row of tiles at a time (OpenImageIO reads tiles only on
  // their grid), of which the rows wanted are copied.
  const int tile_h = m.spec.tile_width > 0 ? std::max(1, m.spec.tile_height) : 0;
  const int grid = tile_h > 0 ? tile_h : m.scan ? m.scan->chunk_rows() : 1;
  const int chunk_rows = tile_h > 0 ? tile_h : kChunkRows;
  std::vector<unsigned char> chunk(std::size_t(w) * m.native.stride * std::size_t(chunk_rows));
  for (int c0 = from; c0 < y1;) {
    const int t0 = c0 / grid * grid;  // the chunk's first row in the file
    const int t1 = std::min(m.spec.height, t0 + chunk_rows);
    const int c1 = std::min(y1, t1);
    const unsigned char* rows = chunk.data();  // row c0
    if (m.scan) {
      m.scan->read(c0, c1, chunk.data());
    } else {
      const bool ok = tile_h > 0 ? m.in->read_tiles(0, 0, m.spec.x, m.spec.x + w, m.spec.y + t0, m.spec.y + t1, m.spec.z,
                                                     m.spec.z + 1, 0, nch, TypeDesc::FLOAT, chunk.data())
                                 : m.in->read_scanlines(0, 0, m.spec.y + t0, m.spec.y + t1, 0, 0, nch, TypeDesc::FLOAT, chunk.data());
      if (!ok)
        throw Error(Errc::ReadFailed, "cannot read rows " + std::to_string(t0) + ".." + std::to_string(t1) + " of '" + m.path +
                                          "': " + m.in->geterror());
      rows += std::size_t(c0 - t0) * std::size_t(w) * m.native.stride;
    }
    for (std::size_t k = 0; k < f.passes.size(); ++k) {
      Image& im = f.passes[k].image;
      const std::vector<int>& src = m.sources[k];
      const std::size_t pc = std::size_t(im.channels());
      parallel_rows(c0, c1, 0, [&](int y) {
        const unsigned char* s = rows + std::size_t(y - c0) * std::size_t(w) * m.native.stride;
        for (std::size_t c = 0; c < pc; ++c) {
          const std::size_t ch = std::size_t(src[c]);
          native_channel_to_float(s + m.native.offset[ch], m.native.stride, m.native.is_half[ch], std::size_t(w),
                                  im.pixel(0, y - y0) + c, pc);
        }
      });
    }
    c0 = c1;
  }
  // The rows the next band may share, copied: the caller's band may be changed.
  m.last_y1 = y1;
  m.last_y0 = std::max(y0, y1 - m.keep);
  m.last = f.header(w, m.last_y1 - m.last_y0);
  for (const Pass& p : f.passes) {
    Image tail(w, m.last_y1 - m.last_y0, p.image.channels());
    const std::size_t row = std::size_t(w) * std::size_t(p.image.channels());
    if (tail.height() > 0) std::memcpy(tail.data(), p.image.pixel(0, m.last_y0 - y0), row * std::size_t(tail.height()) * sizeof(float));
    m.last.passes.push_back(with_pixels(p, std::move(tail)));
  }
  m.read_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return f;
}

}  // namespace mcr
