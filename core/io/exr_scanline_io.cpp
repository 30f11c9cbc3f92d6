#include "io/exr_scanline_io.h"

#include <openexr.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <mutex>

#include "io/exr_zip.h"
#include "util/error.h"
#include "util/parallel.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "OpenEXR chunks are little-endian: copied as is here");

namespace mcr {

namespace {

std::atomic<int> g_enabled{-1};  // -1: not yet read from the environment

// The message OpenEXRCore last reported on this thread (it would print to stderr otherwise).
// Kept per thread, not through the context's user data: exr_get_user_data locks the context,
// which a writing context holds while it reports (a deadlock).
thread_local std::string t_message;

void keep_message(exr_const_context_t, exr_result_t, const char* msg) { t_message = msg ? msg : ""; }

// What a write through the descriptor met.
struct Sink {
  int fd = -1;
  std::mutex lock;
  int write_errno = 0;
};

exr_context_initializer_t initializer(void* user) {
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = keep_message;
  init.user_data = user;
  return init;
}

// Closes a context on every path out (exr_finish also completes a file being written).
struct Context {
  exr_context_t ctxt = nullptr;
  ~Context() {
    if (ctxt) exr_finish(&ctxt);
  }
};

int lines_per_chunk(exr_compression_t c) { return c == EXR_COMPRESSION_ZIP ? 16 : 1; }

bool handled(exr_compression_t c) {
  return c == EXR_COMPRESSION_NONE || c == EXR_COMPRESSION_ZIP || c == EXR_COMPRESSION_ZIPS;
}

// A file channel's place in the caller's pixels.
struct Plane {
  std::size_t bytes;   // 2 (half) or 4 (float) per value
  std::size_t offset;  // byte offset in a pixel
};

// One decoded chunk's rows (channel by channel within a row, as the file lays them out)
// scattered into the interleaved pixels.
void scatter(const unsigned char* raw, int rows, int width, const std::vector<Plane>& planes, std::size_t stride,
             unsigned char* dst) {
  for (int r = 0; r < rows; ++r) {
    unsigned char* row = dst + std::size_t(r) * std::size_t(width) * stride;
    for (const Plane& p : planes) {
      unsigned char* d = row + p.offset;
      if (p.bytes == 2)
        for (int x = 0; x < width; ++x, raw += 2, d += stride) std::memcpy(d, raw, 2);
      else
        for (int x = 0; x < width; ++x, raw += 4, d += stride) std::memcpy(d, raw, 4);
    }
  }
}

// The reverse for writing: float pixels with nc channels, file channel k from source[k].
void gather(const float* pixels, int nc, int rows, int width, const std::vector<int>& source, unsigned char* raw) {
  for (int r = 0; r < rows; ++r) {
    const float* row = pixels + std::size_t(r) * std::size_t(width) * std::size_t(nc);
    for (int s : source)
      for (int x = 0; x < width; ++x, raw += 4) std::memcpy(raw, row + std::size_t(x) * std::size_t(nc) + std::size_t(s), 4);
  }
}

int64_t write_to_fd(exr_const_context_t ctxt, void* user, const void* buffer, uint64_t size, uint64_t offset,
                    exr_stream_error_func_ptr_t) {
  (void)ctxt;
  auto* m = static_cast<Sink*>(user);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pwrite(m->fd, static_cast<const char*>(buffer) + done, size - done, off_t(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::lock_guard<std::mutex> hold(m->lock);
      if (!m->write_errno) m->write_errno = n < 0 ? errno : EIO;
      return -1;
    }
    done += std::size_t(n);
  }
  return int64_t(done);
}

// The chunk offset table as the file stores it (it follows the header of a one-part file).
// OpenEXRCore rebuilds a damaged table by scanning the chunks; OpenImageIO refuses such a file,
// and so does this reader, so that a file reads the same way through either. Empty when the
// header cannot be walked (then OpenImageIO reads the file).
std::vector<std::uint64_t> stored_offsets(const std::string& path, int chunks) {
  std::ifstream f(path, std::ios::binary);
  char magic_version[8];
  if (!f.read(magic_version, 8)) return {};
  std::uint32_t version;
  std::memcpy(&version, magic_version + 4, 4);
  if (version & 0x1000u) return {};  // the multi-part layout: another header structure
  for (std::string name, type;;) {
    if (!std::getline(f, name, '\0')) return {};
    if (name.empty()) break;  // the header's end
    std::int32_t size = 0;
    if (!std::getline(f, type, '\0') || !f.read(reinterpret_cast<char*>(&size), 4) || size < 0) return {};
    f.seekg(size, std::ios::cur);
  }
  std::vector<std::uint64_t> table(static_cast<std::size_t>(chunks));
  if (!f.read(reinterpret_cast<char*>(table.data()), std::streamsize(table.size() * 8))) return {};
  return table;
}

}  // namespace

void set_exr_scanline_io(bool on) { g_enabled.store(on ? 1 : 0); }

bool exr_scanline_io() {
  int v = g_enabled.load();
  if (v < 0) {
    const char* env = std::getenv("MCRECON_EXR_IO");
    v = env && std::strcmp(env, "openimageio") == 0 ? 0 : 1;
    g_enabled.store(v);
  }
  return v == 1;
}

struct ExrScanlineReader::Impl {
  std::string path;
  Context c;
  exr_compression_t comp = EXR_COMPRESSION_NONE;
  exr_attr_box2i_t dw{};
  std::vector<Plane> planes;
  std::size_t line_bytes = 0, stride = 0;
  int width = 0, lines = 1, chunks = 0;
  std::vector<std::uint64_t> table;
};

std::unique_ptr<ExrScanlineReader> ExrScanlineReader::open(const std::string& path, int width, int height,
                                                           const NativeLayout& layout) {
  if (!exr_scanline_io()) return nullptr;
  t_message.clear();  // not an earlier file's
  auto m = std::make_unique<Impl>();
  m->path = path;
  m->width = width;
  m->stride = layout.stride;
  const exr_context_initializer_t init = initializer(nullptr);
  if (exr_start_read(&m->c.ctxt, path.c_str(), &init) != EXR_ERR_SUCCESS) return nullptr;  // OpenImageIO says why
  int parts = 0;
  exr_storage_t storage;
  const exr_attr_chlist_t* channels = nullptr;
  exr_context_t ctxt = m->c.ctxt;
  if (exr_get_count(ctxt, &parts) != EXR_ERR_SUCCESS || parts != 1 ||
      exr_get_storage(ctxt, 0, &storage) != EXR_ERR_SUCCESS || storage != EXR_STORAGE_SCANLINE ||
      exr_get_compression(ctxt, 0, &m->comp) != EXR_ERR_SUCCESS || !handled(m->comp) ||
      exr_get_data_window(ctxt, 0, &m->dw) != EXR_ERR_SUCCESS || exr_get_channels(ctxt, 0, &channels) != EXR_ERR_SUCCESS)
    return nullptr;
  if (int64_t(m->dw.max.x) - m->dw.min.x + 1 != width || int64_t(m->dw.max.y) - m->dw.min.y + 1 != height) return nullptr;
  if (!channels || std::size_t(channels->num_channels) != layout.names.size()) return nullptr;
  for (int k = 0; k < channels->num_channels; ++k) {
    const exr_attr_chlist_entry_t& e = channels->entries[k];
    if (e.x_sampling != 1 || e.y_sampling != 1) return nullptr;
    if (e.pixel_type != EXR_PIXEL_HALF && e.pixel_type != EXR_PIXEL_FLOAT) return nullptr;
    const std::string name(e.name.str, std::size_t(e.name.length));
    const auto at = std::find(layout.names.begin(), layout.names.end(), name);
    if (at == layout.names.end()) return nullptr;
    const std::size_t i = std::size_t(at - layout.names.begin());
    if (bool(layout.is_half[i]) != (e.pixel_type == EXR_PIXEL_HALF)) return nullptr;
    m->planes.push_back({e.pixel_type == EXR_PIXEL_HALF ? 2u : 4u, layout.offset[i]});
    m->line_bytes += m->planes.back().bytes * std::size_t(width);
  }
  m->lines = lines_per_chunk(m->comp);
  m->chunks = (height + m->lines - 1) / m->lines;
  int32_t counted = 0;
  if (exr_get_chunk_count(ctxt, 0, &counted) != EXR_ERR_SUCCESS || counted != m->chunks) return nullptr;
  exr_chunk_info_t first;
  if (exr_read_scanline_chunk_info(ctxt, 0, m->dw.min.y, &first) != EXR_ERR_SUCCESS)  // loads the chunk table
    throw Error(Errc::ReadFailed, "cannot read pixels of '" + path + "' (truncated or corrupt?): " + t_message);
  m->table = stored_offsets(path, m->chunks);
  if (m->table.empty()) return nullptr;
  return std::unique_ptr<ExrScanlineReader>(new ExrScanlineReader(std::move(m)));
}

ExrScanlineReader::ExrScanlineReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ExrScanlineReader::~ExrScanlineReader() = default;

int ExrScanlineReader::chunk_rows() const { return impl_->lines; }

void ExrScanlineReader::read(int y0, int y1, unsigned char* dst) {
  Impl& m = *impl_;
  if (y0 < 0 || y1 > m.dw.max.y - m.dw.min.y + 1 || y0 >= y1)
    throw Error(Errc::Internal, "scanline reader: rows " + std::to_string(y0) + ".." + std::to_string(y1) + " outside '" + m.path + "'");
  std::atomic<bool> failed{false};
  std::string failure;
  std::mutex failure_lock;
  auto fail = [&](int y, const std::string& why) {
    const std::lock_guard<std::mutex> hold(failure_lock);
    if (!failed.exchange(true)) failure = "rows from " + std::to_string(y) + ": " + (why.empty() ? "unreadable chunk" : why);
  };
  const std::size_t row_bytes = std::size_t(m.width) * m.stride;
  parallel_rows(y0 / m.lines, (y1 - 1) / m.lines + 1, 0, [&](int k) {
    if (failed.load()) return;
    const int y = m.dw.min.y + k * m.lines;
    const int rows = std::min(m.lines, m.dw.max.y + 1 - y);
    const std::size_t expect = std::size_t(rows) * m.line_bytes;
    exr_chunk_info_t ci;
    t_message.clear();
    if (exr_read_scanline_chunk_info(m.c.ctxt, 0, y, &ci) != EXR_ERR_SUCCESS) return fail(y, t_message);
    if (ci.data_offset != m.table[std::size_t(k)] + 8)  // after the chunk's row and size fields
      return fail(y, "the chunk offset table is damaged (chunk " + std::to_string(k) + " at byte " +
                         std::to_string(m.table[std::size_t(k)]) + ")");
    // A chunk holds what the header says, stored smaller or raw: nothing bigger is allocated.
    if (ci.start_y != y || ci.height != rows || ci.unpacked_size != expect || ci.packed_size == 0 || ci.packed_size > expect)
      return fail(y, "chunk of " + std::to_string(ci.packed_size) + " bytes where " + std::to_string(expect) +
                         " raw bytes are expected");
    thread_local std::vector<unsigned char> packed, raw;
    packed.resize(ci.packed_size);
    if (exr_read_chunk(m.c.ctxt, 0, &ci, packed.data()) != EXR_ERR_SUCCESS) return fail(y, t_message);
    const unsigned char* data = packed.data();
    if (ci.packed_size < expect) {
      if (m.comp == EXR_COMPRESSION_NONE) return fail(y, "short uncompressed chunk");
      raw.resize(expect);
      if (!exr_zip::decode(packed.data(), packed.size(), raw.data(), expect)) return fail(y, "zip data does not decode");
      data = raw.data();
    }
    // The chunk's rows inside [y0, y1) (a read need not start or end on the chunk grid).
    const int r0 = std::max(y0, k * m.lines), r1 = std::min(y1, k * m.lines + rows);
    scatter(data + std::size_t(r0 - k * m.lines) * m.line_bytes, r1 - r0, m.width, m.planes, m.stride,
            dst + std::size_t(r0 - y0) * row_bytes);
  });
  if (failed.load()) throw Error(Errc::ReadFailed, "cannot read pixels of '" + m.path + "' (truncated or corrupt?): " + failure);
}

bool read_exr_scanlines(const std::string& path, int width, int height, const NativeLayout& layout, unsigned char* dst) {
  const auto reader = ExrScanlineReader::open(path, width, height, layout);
  if (!reader) return false;
  reader->read(0, height, dst);
  return true;
}

bool exr_scanline_compression(const std::string& compression) {
  const std::string name = compression.substr(0, compression.find(':'));
  return exr_scanline_io() && (name == "none" || name == "zip" || name == "zips");
}

int write_exr_scanlines(int fd, const std::string& path, int width, int height, const PixelWindow& window,
                        const std::vector<std::string>& names, const float* pixels, const std::string& compression,
                        const std::vector<std::pair<std::string, std::string>>& attributes) {
  const std::string name = compression.substr(0, compression.find(':'));
  const exr_compression_t comp = name == "zip" ? EXR_COMPRESSION_ZIP : name == "zips" ? EXR_COMPRESSION_ZIPS : EXR_COMPRESSION_NONE;
  // OpenImageIO leaves OpenEXR 3.1's zip level (4) unless one is given.
  const int level = compression.find(':') == std::string::npos ? 4 : std::atoi(compression.c_str() + compression.find(':') + 1);

  t_message.clear();
  Sink sink;
  sink.fd = fd;
  exr_context_initializer_t init = initializer(&sink);
  init.write_fn = write_to_fd;
  Context c;
  auto check = [&](exr_result_t rv, const char* step) {
    if (rv == EXR_ERR_SUCCESS) return;
    if (sink.write_errno) throw Error(Errc::WriteFailed, "cannot write '" + path + "'");  // caught below
    throw Error(Errc::WriteFailed, "cannot write '" + path + "': " + step + ": " + t_message);
  };
  try {
    check(exr_start_write(&c.ctxt, path.c_str(), EXR_WRITE_FILE_DIRECTLY, &init), "start");
    // Names over 31 bytes need the file's long-name flag (OpenEXR 2.0 and later read them).
    bool long_names = false;
    for (const std::string& n : names) long_names = long_names || n.size() > 31;
    for (const auto& kv : attributes) long_names = long_names || kv.first.size() > 31;
    if (long_names) check(exr_set_longname_support(c.ctxt, 1), "long names");
    int part = 0;
    check(exr_add_part(c.ctxt, nullptr, EXR_STORAGE_SCANLINE, &part), "part");
    const bool display = window.full_width > 0 && window.full_height > 0;
    const exr_attr_box2i_t data = {{window.x, window.y}, {window.x + width - 1, window.y + height - 1}};
    const exr_attr_box2i_t shown = display ? exr_attr_box2i_t{{window.full_x, window.full_y},
                                                              {window.full_x + window.full_width - 1, window.full_y + window.full_height - 1}}
                                           : exr_attr_box2i_t{{0, 0}, {width - 1, height - 1}};
    const exr_attr_v2f_t centre = {0.0f, 0.0f};
    check(exr_initialize_required_attr(c.ctxt, part, &shown, &data, 1.0f, &centre, 1.0f, EXR_LINEORDER_INCREASING_Y, comp),
          "header");
    for (const std::string& n : names)
      if (exr_add_channel(c.ctxt, part, n.c_str(), EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) != EXR_ERR_SUCCESS)
        check(EXR_ERR_INVALID_ARGUMENT, ("channel '" + n + "'").c_str());
    check(exr_attr_set_string(c.ctxt, part, "Software", "mcrecon"), "attribute Software");
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::tm local;
    if (localtime_r(&now, &local) && std::strftime(date, sizeof date, "%Y:%m:%d %H:%M:%S", &local))
      check(exr_attr_set_string(c.ctxt, part, "capDate", date), "attribute capDate");
    for (const auto& kv : attributes)
      check(exr_attr_set_string(c.ctxt, part, kv.first.c_str(), kv.second.c_str()), ("attribute " + kv.first).c_str());
    check(exr_write_header(c.ctxt), "header");

    const exr_attr_chlist_t* sorted = nullptr;
    check(exr_get_channels(c.ctxt, part, &sorted), "channels");
    std::vector<int> source;  // the file lists channels sorted by name
    for (int k = 0; k < sorted->num_channels; ++k) {
      const std::string n(sorted->entries[k].name.str, std::size_t(sorted->entries[k].name.length));
      source.push_back(int(std::find(names.begin(), names.end(), n) - names.begin()));
    }
    const int nc = int(names.size());
    const int lines = lines_per_chunk(comp);
    const int chunks = (height + lines - 1) / lines;
    const std::size_t line_bytes = std::size_t(width) * std::size_t(nc) * 4;
    // Chunks compressed in parallel a batch of ~256 rows at a time (a 4096-wide RGBA batch holds
    // 16 MB raw and at most as much packed), written in order.
    const int batch = std::max(1, 256 / lines);
    const std::size_t slots = std::size_t(batch);
    std::vector<std::vector<unsigned char>> raw(slots), packed(slots);
    std::vector<std::size_t> size(slots);
    for (int k0 = 0; k0 < chunks; k0 += batch) {
      const int k1 = std::min(chunks, k0 + batch);
      parallel_rows(k0, k1, 0, [&](int k) {
        const std::size_t i = std::size_t(k - k0);
        const int rows = std::min(lines, height - k * lines);
        raw[i].resize(std::size_t(rows) * line_bytes);
        gather(pixels + std::size_t(k) * std::size_t(lines) * std::size_t(width) * std::size_t(nc), nc, rows, width, source,
               raw[i].data());
        size[i] = comp == EXR_COMPRESSION_NONE ? 0 : exr_zip::encode(raw[i].data(), raw[i].size(), level, packed[i]);
      });
      for (int k = k0; k < k1; ++k) {
        const std::size_t i = std::size_t(k - k0);
        const bool stored = size[i] == 0;  // not smaller compressed: the raw bytes
        check(exr_write_scanline_chunk(c.ctxt, part, window.y + k * lines, stored ? raw[i].data() : packed[i].data(),
                                       stored ? raw[i].size() : size[i]),
              "pixels");
      }
    }
    exr_context_t done = c.ctxt;
    c.ctxt = nullptr;
    check(exr_finish(&done), "finish");
  } catch (const Error&) {
    if (sink.write_errno) return sink.write_errno;
    throw;
  }
  return sink.write_errno;
}

}  // namespace mcr
