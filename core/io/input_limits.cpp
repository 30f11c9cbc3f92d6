#include "io/input_limits.h"

#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineInputPart.h>
#include <OpenEXR/ImfDeepTiledInputPart.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "util/error.h"

namespace mcr {

void require_regular_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT || err == ENOTDIR) throw Error(Errc::FileNotFound, "cannot read '" + path + "': no such file");
    throw Error(Errc::ReadFailed, "cannot read '" + path + "': " + std::strerror(err));
  }
  if (S_ISREG(st.st_mode)) return;
  const char* what = S_ISDIR(st.st_mode)    ? "it is a directory"
                     : S_ISFIFO(st.st_mode) ? "not a regular file (a FIFO)"
                     : S_ISCHR(st.st_mode)  ? "not a regular file (a character device)"
                     : S_ISBLK(st.st_mode)  ? "not a regular file (a block device)"
                     : S_ISSOCK(st.st_mode) ? "not a regular file (a socket)"
                                            : "not a regular file";
  throw Error(Errc::NotAnImage, "cannot read '" + path + "': " + what);
}

std::uint64_t parse_byte_count(const std::string& text, const std::string& what) {
  const auto bad = [&] {
    return Error(Errc::InvalidArgument, what + "='" + text +
                                            "': expected a positive byte count such as 500M, 8G or 2GiB "
                                            "(K, M, G, T: powers of 1000; Ki, Mi, Gi, Ti: of 1024)");
  };
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    throw bad();
  }
  std::string unit = text.substr(used);
  if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b')) unit.pop_back();
  double scale = 1.0;
  if (!unit.empty()) {
    const bool binary = unit.size() == 2 && (unit[1] == 'i' || unit[1] == 'I');
    if (unit.size() != 1 && !binary) throw bad();
    const std::string prefixes = "KMGT";
    const auto k = prefixes.find(char(std::toupper(static_cast<unsigned char>(unit[0]))));
    if (k == std::string::npos) throw bad();
    scale = std::pow(binary ? 1024.0 : 1000.0, double(k + 1));
  }
  const double bytes = value * scale;
  if (!std::isfinite(bytes) || bytes < 1.0 || bytes > 1e18) throw bad();
  return std::uint64_t(bytes);
}

std::string byte_text(double bytes) {
  static const char* units[] = {"bytes", "KB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 999.5 && u < 6) {
    bytes /= 1000.0;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
  return buf;
}

// Float bytes per file byte, measured on constant images (the best case of every
// compression) written by OpenImageIO 2.4 / OpenEXR 3.1, 1024^2 to 8192^2, RGB(A),
// half and float, scanline and tiled; each bound is about twice the best seen:
//   none 2 (half read as float), rle 128, b44/b44a 21, piz 744, pxr24 1608,
//   zip/zips 2055 (deflate's 1032:1 on half data), dwaa/dwab 63777.
// Other formats (PNG palette or 1-bit images, GIF) can exceed zip's figure, so
// they, and compressions not listed, get the largest bound.
double max_expansion(const std::string& format, const std::string& compression) {
  constexpr double kLargest = 262144;
  if (format != "openexr") return kLargest;
  const std::string c = compression.substr(0, compression.find(':'));  // "dwaa:45" -> "dwaa"
  if (c == "none" || c.empty()) return 4;
  if (c == "rle") return 256;
  if (c == "b44" || c == "b44a") return 64;
  if (c == "zip" || c == "zips" || c == "piz" || c == "pxr24") return 4096;
  return kLargest;
}

double InputBudget::absolute_cap() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return kAbsoluteCap;
  return std::min(kAbsoluteCap, 0.5 * double(pages) * double(page));
}

InputBudget InputBudget::for_file(const std::string& path, const std::string& format, const std::string& compression) {
  InputBudget b;
  struct stat st {};
  b.file_bytes_ = ::stat(path.c_str(), &st) == 0 ? std::uint64_t(st.st_size) : 0;
  if (const char* env = std::getenv("MCRECON_MAX_MEMORY"); env && *env) {
    b.user_limit_ = env;
    b.bytes_ = parse_byte_count(env, "MCRECON_MAX_MEMORY");
    return b;
  }
  const double from_file = double(b.file_bytes_) * max_expansion(format, compression) + kFloor;
  const double cap = absolute_cap();
  b.capped_ = from_file > cap;
  b.bytes_ = std::uint64_t(std::min(from_file, cap));
  return b;
}

void InputBudget::check(const std::string& path, double bytes, const std::string& claim) const {
  if (bytes <= double(bytes_)) return;
  std::string limit;
  if (!user_limit_.empty())
    limit = "MCRECON_MAX_MEMORY=" + user_limit_ + " allows " + byte_text(double(bytes_));
  else if (capped_)
    limit = "no input may use more than " + byte_text(double(bytes_)) +
            " (half this machine's memory, at most 32 GB; set MCRECON_MAX_MEMORY to allow more)";
  else
    limit = "the " + byte_text(double(file_bytes_)) + " file can hold at most ~" + byte_text(double(bytes_)) +
            " of pixels (set MCRECON_MAX_MEMORY to allow more)";
  throw Error(Errc::ReadFailed,
              "cannot read '" + path + "': " + claim + " (" + byte_text(bytes) + ") but " + limit);
}

namespace {

std::string dims(std::int64_t w, std::int64_t h, std::int64_t c) {
  return std::to_string(w) + "x" + std::to_string(h) + "x" + std::to_string(c) + " float";
}

// A name from a file as a message shows it: bytes outside printable ASCII as \xNN.
std::string printable(const std::string& s) {
  std::string out;
  for (unsigned char c : s) {
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  return out;
}

// An OpenEXR header read in order from its file, never past the file's end.
class ExrHeaderReader {
 public:
  ExrHeaderReader(const std::string& path, std::ifstream& file, std::uint64_t size, std::uint64_t pos)
      : path_(path), file_(file), size_(size), pos_(pos) {}
  std::uint64_t pos() const { return pos_; }
  std::uint64_t left() const { return size_ - pos_; }

  // A NUL-terminated name ("" ends a header): at most 255 bytes, as OpenEXR's long names.
  std::string name(const std::string& what) {
    std::string s;
    for (;;) {
      const int c = file_.get();
      if (c == std::char_traits<char>::eof())
        fail(what + (s.empty() ? "" : " '" + printable(s) + "'") + " has no terminator: the file ends inside it (truncated?)");
      ++pos_;
      if (c == 0) return s;
      if (s.size() == 255) fail(what + " '" + printable(s.substr(0, 32)) + "...' is longer than 255 bytes");
      s += char(c);
    }
  }
  std::int64_t i32(const std::string& what) { return std::int32_t(u32(what)); }
  std::uint32_t u32(const std::string& what) {
    unsigned char b[4];
    if (left() < 4 || !file_.read(reinterpret_cast<char*>(b), 4))
      fail(what + " is cut off by the end of the file (truncated?)");
    pos_ += 4;
    return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
  }
  int byte(const std::string& what) {
    const int c = left() ? file_.get() : std::char_traits<char>::eof();
    if (c == std::char_traits<char>::eof()) fail(what + " is cut off by the end of the file (truncated?)");
    ++pos_;
    return c;
  }
  void seek(std::uint64_t to) {  // to <= the file's size (callers check)
    file_.seekg(std::streamoff(to));
    pos_ = to;
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw Error(Errc::ReadFailed, "cannot read '" + path_ + "': " + why);
  }

 private:
  const std::string& path_;
  std::ifstream& file_;
  std::uint64_t size_, pos_;
};

// What the tile checks need from one part's header.
struct ExrPartHeader {
  bool has_window = false, has_tiles = false;
  bool tiled = false;  // read as tiles: set from the version flags and the "type" attribute
  std::string type;    // the "type" attribute (multi-part and deep files)
  std::int64_t width = 0, height = 0;
  std::int64_t tile_width = 0, tile_height = 0;
  int channels = 0;
  int compression = -1;
  std::int64_t chunk_count = -1;  // the "chunkCount" attribute (required in deep files)
};

// OpenEXR's compression enum, as max_expansion names them.
std::string exr_compression_name(int c) {
  static const char* names[] = {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"};
  return c >= 0 && c < 10 ? names[c] : "unknown";
}

// The bytes OpenEXR reads for a value of a fixed-size type, whatever size the header
// declares (0: not such a type).
std::uint64_t exr_fixed_size(const std::string& type) {
  static const std::pair<const char*, int> sizes[] = {
      {"box2i", 16},  {"box2f", 16},   {"compression", 1}, {"chromaticities", 32}, {"deepImageState", 1},
      {"double", 8},  {"envmap", 1},   {"float", 4},       {"int", 4},             {"keycode", 28},
      {"lineOrder", 1}, {"m33d", 72},  {"m33f", 36},       {"m44d", 128},          {"m44f", 64},
      {"rational", 8}, {"tiledesc", 9}, {"timecode", 8},   {"v2d", 16},            {"v2f", 8},
      {"v2i", 8},     {"v3d", 24},     {"v3f", 12},        {"v3i", 12}};
  for (const auto& [t, n] : sizes)
    if (type == t) return std::uint64_t(n);
  return 0;
}

// Reads one attribute's value (the reader stands at its start; the file holds the
// `size` bytes declared) as far as OpenEXR would, keeping what the part checks need,
// and refuses contents that claim more than `size`: OpenEXR allocates those claims
// first. Leaves the reader where OpenEXR's would stand: past `size` bytes, except for
// fixed-size types and channel lists, which OpenEXR reads by their layout, ignoring
// the declared size.
void read_exr_value(ExrHeaderReader& r, const std::string& name, const std::string& type, std::uint64_t size,
                    const std::string& label, ExrPartHeader& part) {
  const std::uint64_t start = r.pos();
  std::uint64_t end = start + size;
  if (const std::uint64_t fixed = exr_fixed_size(type)) {
    end = start + fixed;
    if (fixed > r.left()) r.fail(label + " is cut off by the end of the file (truncated?)");
    if (name == "dataWindow" && type == "box2i") {
      const std::int64_t x0 = r.i32(label), y0 = r.i32(label), x1 = r.i32(label), y1 = r.i32(label);
      part.has_window = true;
      part.width = x1 - x0 + 1;
      part.height = y1 - y0 + 1;
    } else if (name == "tiles" && type == "tiledesc") {
      part.has_tiles = true;
      part.tile_width = r.u32(label);
      part.tile_height = r.u32(label);
    } else if (name == "compression" && type == "compression") {
      part.compression = r.byte(label);
    } else if (name == "chunkCount" && type == "int") {
      part.chunk_count = r.i32(label);
    }
  } else if (type == "chlist") {
    // name\0 then pixel type, pLinear, reserved, x and y sampling (16 bytes), until an empty name.
    // OpenImageIO 2.4 aborts on a pixel type it does not know: refuse any but uint, half, float.
    for (;;) {
      const std::string channel = r.name("a channel name in " + label);
      if (channel.empty()) break;
      if (r.left() < 16) r.fail(label + " is cut off by the end of the file (truncated?)");
      const std::int64_t pixel_type = r.i32(label);
      if (name == "channels" && (pixel_type < 0 || pixel_type > 2))
        r.fail("channel '" + printable(channel) + "' has pixel type " + std::to_string(pixel_type) +
               " (OpenEXR's are 0 uint, 1 half, 2 float)");
      r.seek(r.pos() + 12);
      if (name == "channels") ++part.channels;
    }
    end = r.pos();
  } else if (name == "type" && type == "string" && size <= 64) {
    for (std::uint64_t i = 0; i < size; ++i) part.type += char(r.byte(label));
  } else if (type == "preview") {
    if (size < 8) r.fail(label + " holds " + std::to_string(size) + " bytes, too few for a preview's size");
    const double w = r.u32(label), h = r.u32(label);
    if (8.0 + w * h * 4.0 > double(size))
      r.fail(label + " claims a " + std::to_string(std::uint64_t(w)) + "x" + std::to_string(std::uint64_t(h)) +
             " preview (" + byte_text(w * h * 4.0) + ") in " + std::to_string(size) + " bytes");
    end = start + 8 + std::uint64_t(w * h * 4.0);
  } else if (type == "floatvector") {
    end = start + size / 4 * 4;
  } else if (type == "stringvector") {
    while (r.pos() < end) {
      const std::int64_t n = r.i32(label);
      if (n < 0 || std::uint64_t(n) > end - std::min(end, r.pos()))
        r.fail(label + " holds a string that claims " + std::to_string(n) + " bytes but only " +
               std::to_string(end - std::min(end, r.pos())) + " of the attribute's " + std::to_string(size) +
               " bytes follow it");
      r.seek(r.pos() + std::uint64_t(n));
    }
  }
  r.seek(end);
}

// Scanlines per chunk of each OpenEXR compression (unknown ones: the most, 256).
std::int64_t exr_lines_per_chunk(int c) {
  switch (c) {
    case 0: case 1: case 2: return 1;  // none, rle, zips
    case 3: case 5: return 16;         // zip, pxr24
    case 4: case 6: case 7: case 8: return 32;  // piz, b44, b44a, dwaa
    default: return 256;               // dwab
  }
}

// What opening a part allocates from its header. A chunk of scanlines or a tile:
// refuse one past the input budget. Its table of chunk offsets (8 bytes
// a chunk) is part of the file, so a file smaller than that table claims a data
// window it cannot hold. A tile past the data window by more than a writer that uses
// one tile size for every image would use is refused too (OpenEXR's and OpenImageIO's
// default is 64).
void check_exr_part(const std::string& path, const ExrPartHeader& part, const std::string& where,
                    std::uint64_t file_size) {
  constexpr std::int64_t kUsualTile = 1024;
  const std::int64_t tw = part.tile_width, th = part.tile_height;
  const bool window = part.has_window && part.width > 0 && part.height > 0;  // else OpenEXR refuses it
  if (part.tiled && part.has_tiles) {
    const InputBudget budget = InputBudget::for_file(path, "openexr", exr_compression_name(part.compression));
    budget.check(path, double(tw) * double(th) * std::max(part.channels, 1) * 4.0,
                 "its header asks for tiles of " + dims(tw, th, std::max(part.channels, 1)) + where);
    if (window && ((tw > part.width && tw > kUsualTile) || (th > part.height && th > kUsualTile)))
      throw Error(Errc::ReadFailed, "cannot read '" + path + "': its header asks for tiles of " + std::to_string(tw) +
                                        "x" + std::to_string(th) + " pixels" + where + ", larger than its " +
                                        std::to_string(part.width) + "x" + std::to_string(part.height) +
                                        " data window (and than " + std::to_string(kUsualTile) +
                                        ", the most a tile may exceed it by)");
  }
  if (!window || (part.tiled && (!part.has_tiles || tw <= 0 || th <= 0))) return;  // OpenEXR refuses those
  if (!part.tiled) {  // a chunk of scanlines is allocated when the file opens, as a tile is
    const std::int64_t lines = std::min(exr_lines_per_chunk(part.compression), part.height);
    const int c = std::max(part.channels, 1);
    InputBudget::for_file(path, "openexr", exr_compression_name(part.compression))
        .check(path, double(part.width) * double(lines) * c * 4.0,
               "its header asks for scanlines of " + std::to_string(part.width) + "x" + std::to_string(c) +
                   " float" + where + ", read " + std::to_string(lines) + " at a time");
  }
  const double chunks = part.tiled ? std::ceil(double(part.width) / double(tw)) * std::ceil(double(part.height) / double(th))
                                   : std::ceil(double(part.height) / double(exr_lines_per_chunk(part.compression)));
  if (chunks * 8.0 > double(file_size))
    throw Error(Errc::ReadFailed, "cannot read '" + path + "': its header asks for a " + std::to_string(part.width) +
                                      "x" + std::to_string(part.height) + " data window" + where + " in " +
                                      std::to_string(std::uint64_t(chunks)) + (part.tiled ? " tiles" : " chunks") +
                                      ", whose table of offsets alone (" + byte_text(chunks * 8.0) +
                                      ") exceeds the " + byte_text(double(file_size)) + " file (truncated or corrupt?)");
}

}  // namespace

namespace {

// A single-part deep scanline file's chunks, after its header: each chunk's header claims the unpacked
// size of its samples, which OpenEXR allocates before it reads them (a 1 KB file made it allocate
// 973 MB). No chunk may claim more than its packed bytes can expand to, or lie past the file.
void check_deep_chunks(ExrHeaderReader& r, const ExrPartHeader& part) {
  // Scanline files whose chunk count agrees with their window (1 line a chunk, 16 for zip), any
  // other header being refused by the size checks that follow, with their own message; tiled
  // files by their chunkCount as it stands (every level's tiles, as OpenEXR counts them).
  // Without a chunkCount OpenEXR counts the chunks from the window (one level of tiles at least).
  if (!part.has_window) return;
  if (part.tiled && (!part.has_tiles || part.tile_width <= 0 || part.tile_height <= 0)) return;
  const std::int64_t lines = part.compression == 3 ? 16 : 1;
  const std::int64_t from_window =
      part.tiled ? ((part.width + part.tile_width - 1) / part.tile_width) * ((part.height + part.tile_height - 1) / part.tile_height)
                 : (part.height + lines - 1) / lines;
  if (!part.tiled && part.chunk_count >= 0 && part.chunk_count != from_window) return;
  const std::int64_t count = part.chunk_count >= 0 ? part.chunk_count : from_window;
  if (std::uint64_t(count) > r.left() / 8)
    r.fail("its chunkCount " + std::to_string(count) + " needs a " + std::to_string(std::uint64_t(count) * 8) +
           "-byte offset table, more than the file holds");
  std::vector<std::uint64_t> offsets(static_cast<std::size_t>(count));
  for (auto& o : offsets) o = std::uint64_t(r.u32("the chunk offset table")) | std::uint64_t(r.u32("the chunk offset table")) << 32;
  const std::uint64_t size = r.pos() + r.left();
  const double expand = max_expansion("openexr", exr_compression_name(part.compression));
  const std::uint64_t head = part.tiled ? 16 : 4;  // the chunk's tile (x, y, level x, level y) or first scanline
  for (std::size_t k = 0; k < offsets.size(); ++k) {
    const std::string chunk = (part.tiled ? "deep tile chunk " : "deep chunk ") + std::to_string(k);
    if (offsets[k] > size || size - offsets[k] < head + 24) continue;  // OpenEXR reports a bad offset itself
    r.seek(offsets[k] + head);
    auto u64 = [&](const char* what) {
      return std::uint64_t(r.u32(chunk + what)) | std::uint64_t(r.u32(chunk + what)) << 32;
    };
    const std::uint64_t table = u64("'s packed sample table size"), packed = u64("'s packed data size"),
                        unpacked = u64("'s unpacked data size");
    const std::uint64_t room = r.left();
    if (table > room || packed > room - table)
      r.fail(chunk + " claims " + std::to_string(table) + " + " + std::to_string(packed) + " packed bytes but only " +
             std::to_string(room) + " follow it (truncated or corrupt?)");
    if (double(unpacked) > double(packed) * expand + 65536.0)
      r.fail(chunk + " claims " + std::to_string(unpacked) + " unpacked bytes from " + std::to_string(packed) +
             " packed ones (" + exr_compression_name(part.compression) + " expands at most " +
             std::to_string(std::uint64_t(expand)) + "x)");
  }
}

void scan_exr(const std::string& path, bool deep_chunks) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;  // require_regular_file reports that
  const std::uint64_t size = std::uint64_t(st.st_size);
  std::ifstream file(path, std::ios::binary);
  unsigned char head[8];
  if (!file.read(reinterpret_cast<char*>(head), 8)) return;  // too short for an EXR: its reader says so
  if (std::memcmp(head, "\x76\x2f\x31\x01", 4) != 0) return;
  // Version flags (bits 8-31): 0x200 a single-part tiled file, 0x800 deep, 0x1000 multi-part.
  const bool single_tiled = head[5] & 0x02, deep = head[5] & 0x08, multipart = head[5] & 0x10;
  ExrHeaderReader r(path, file, size, 8);
  // A single-part file has one header; a multi-part file a list of them, each ended
  // by an empty name, the list by one more.
  for (int index = 0;; ++index) {
    const std::string where = multipart ? " in part " + std::to_string(index) : "";
    ExrPartHeader part;
    for (int k = 0;; ++k) {
      const std::string name = r.name("the name of header attribute " + std::to_string(k + 1) + where);
      if (name.empty()) {
        if (multipart && k == 0 && index > 0) return;  // the end of the list of headers
        break;
      }
      const std::string label = "header attribute '" + printable(name) + "'" + where;
      const std::string type = r.name("the type of " + label);
      const std::int64_t claim = r.i32("the size of " + label);
      if (claim < 0 || std::uint64_t(claim) > r.left())
        r.fail(label + " claims " + std::to_string(claim) + " bytes but only " + std::to_string(r.left()) +
               " of the file's " + std::to_string(size) + " bytes follow it (truncated or corrupt?)");
      read_exr_value(r, name, type, std::uint64_t(claim), label, part);
    }
    // Tiled as OpenEXR decides: multi-part and deep files by their type, others by the flag.
    part.tiled = multipart || deep ? part.type == "tiledimage" || part.type == "deeptile" : single_tiled;
    check_exr_part(path, part, where, size);
    if (!multipart) {
      if (deep && deep_chunks) check_deep_chunks(r, part);
      return;
    }
  }
}

}  // namespace

void check_exr_header_sizes(const std::string& path) { scan_exr(path, false); }

void check_before_open(const std::string& path) {
  require_regular_file(path);
  check_exr_header_sizes(path);
  check_webp_header_size(path);
}

std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path) {
  check_before_open(path);
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty()) ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  std::unique_ptr<OIIO::ImageInput> in = ext.empty() ? nullptr : OIIO::ImageInput::create(ext, false);
  std::string msg;
  if (!in) {
    OIIO::geterror();  // no reader for that extension: nothing to report from the lookup
    in = OIIO::ImageInput::open(path);
    if (!in) msg = OIIO::geterror();
  } else if (OIIO::ImageSpec spec; !in->open(path, spec)) {
    msg = in->geterror();
    in.reset();
  }
  if (!in) throw Error(Errc::NotAnImage, "cannot read '" + path + "' as an image" + (msg.empty() ? "" : ": " + msg));
  return in;
}

void check_webp_header_size(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  unsigned char b[30] = {};
  file.read(reinterpret_cast<char*>(b), sizeof b);
  const int got = int(file.gcount());
  if (got >= 4 && std::memcmp(b, "\x76\x2f\x31\x01", 4) == 0) return;  // OpenEXR
  auto le = [&](int at, int n) {
    std::uint32_t v = 0;
    for (int k = n - 1; k >= 0; --k) v = v << 8 | b[at + k];
    return v;
  };
  // A lossless bitstream at `at` (signature 0x2f, then 14 bits each of width - 1 and height - 1)
  // or a lossy one (a 3-byte frame tag, the start code 9d 01 2a, then 14 bits each).
  std::int64_t w = 0, h = 0;
  auto bitstream = [&](int at) {
    if (got >= at + 5 && b[at] == 0x2f) {
      const std::uint32_t v = le(at + 1, 4);
      w = std::int64_t(v & 0x3fff) + 1;
      h = std::int64_t((v >> 14) & 0x3fff) + 1;
    } else if (got >= at + 10 && b[at + 3] == 0x9d && b[at + 4] == 0x01 && b[at + 5] == 0x2a) {
      w = le(at + 6, 2) & 0x3fff;
      h = le(at + 8, 2) & 0x3fff;
    }
  };
  if (got >= 16 && std::memcmp(b, "RIFF", 4) == 0 && std::memcmp(b + 8, "WEBP", 4) == 0) {
    if (std::memcmp(b + 12, "VP8X", 4) == 0 && got >= 30) {  // extended: the canvas, 24 bits each of size - 1
      w = std::int64_t(le(24, 3)) + 1;
      h = std::int64_t(le(27, 3)) + 1;
    } else if (std::memcmp(b + 12, "VP8L", 4) == 0 || std::memcmp(b + 12, "VP8 ", 4) == 0) {
      bitstream(20);
    }
  } else {
    bitstream(0);  // libwebp also takes a bare bitstream, and OpenImageIO tries every reader on a file
  }
  if (w <= 0 || h <= 0) return;  // not a header this knows: OpenImageIO's readers say what it is
  InputBudget::for_file(path, "webp", "").check(path, double(w) * double(h) * 4.0 * 4.0,
                                               "its WebP header asks for " + dims(w, h, 4));
}

void check_deep_chunk_sizes(const std::string& path) { scan_exr(path, true); }

InputBudget check_header_fits(OIIO::ImageInput& in, const std::string& path) {
  const OIIO::ImageSpec first = in.spec();  // a copy: seek_subimage changes in.spec()
  const InputBudget budget =
      InputBudget::for_file(path, in.format_name(), first.get_string_attribute("compression"));
  // Sizes in double: a header's int fields multiplied in int would overflow.
  double total = 0.0;
  std::int64_t channels = 0;
  int parts = 0;
  bool same_size = true;
  for (int part = 0; in.seek_subimage(part, 0); ++part) {
    const OIIO::ImageSpec& s = in.spec();
    if (s.width <= 0 || s.height <= 0 || s.nchannels <= 0)
      throw Error(Errc::ReadFailed, "cannot read '" + path + "': implausible size " + std::to_string(s.width) + "x" +
                                        std::to_string(s.height) + "x" + std::to_string(s.nchannels));
    if (part > 0 && s.deep) continue;  // the reader skips deep parts after the first
    const double w = s.width, h = s.height, c = s.nchannels, d = std::max(s.depth, 1);
    // A deep part: per-pixel sample tables (counts, offsets, capacities) beside the flattened float pixels.
    total += w * h * d * (c * 4.0 + (s.deep ? 32.0 : 0.0));
    channels += s.nchannels;
    same_size = same_size && s.width == first.width && s.height == first.height;
    ++parts;
    if (s.tile_width <= 0 && !s.channelformats.empty()) {
      // OpenImageIO reads scanlines of mixed channel types 256 rows at a time, however few the image has.
      budget.check(path, 256.0 * w * double(s.pixel_bytes(true)),
                   "its header asks for rows of " + std::to_string(s.width) +
                       " pixels of mixed channel types, which OpenImageIO reads 256 rows at a time");
    }
    if (s.tile_width > 0) {  // a tiled read buffers a whole row of tiles, and a tile may exceed the image
      const double tw = s.tile_width, th = s.tile_height, td = std::max(s.tile_depth, 1);
      const double row = std::ceil(w / tw) * tw * th * td * c * 4.0;
      budget.check(path, row, "its header asks for tiles of " + dims(s.tile_width, s.tile_height, s.nchannels) + ", read a row at a time");
    }
  }
  in.seek_subimage(0, 0);
  std::string asks = same_size ? dims(first.width, first.height, channels) +
                                           (parts > 1 ? " in " + std::to_string(parts) + " parts" : "")
                                     : std::to_string(parts) + " parts of " + std::to_string(channels) +
                                           " float channels in all";
  if (first.deep) asks += " deep, with per-pixel sample tables";
  budget.check(path, total, "its header asks for " + asks);
  return budget;
}

void check_deep_samples(const std::string& path, int nchannels, const InputBudget& budget) {
  namespace imf = OPENEXR_IMF_NAMESPACE;
  std::uint64_t samples = 0;
  try {
    imf::MultiPartInputFile file(path.c_str());
    const imf::Header& header = file.header(0);
    const IMATH_NAMESPACE::Box2i dw = header.dataWindow();
    const std::int64_t width = std::int64_t(dw.max.x) - dw.min.x + 1;
    std::vector<unsigned> counts;
    // Counts land in `counts`, laid out as rows [y0, y0 + rows) of the data window.
    const auto frame_for = [&](int y0, std::int64_t rows) {
      counts.assign(std::size_t(width * rows), 0u);
      char* origin = reinterpret_cast<char*>(counts.data()) -
                     (std::intptr_t(dw.min.x) + std::intptr_t(y0) * width) * std::intptr_t(sizeof(unsigned));
      imf::DeepFrameBuffer fb;
      fb.insertSampleCountSlice(imf::Slice(imf::UINT, origin, sizeof(unsigned), std::size_t(width) * sizeof(unsigned)));
      return fb;
    };
    const auto add = [&] {
      for (unsigned n : counts) samples += n;
    };
    if (header.type() == imf::DEEPSCANLINE) {
      imf::DeepScanLineInputPart part(file, 0);
      constexpr int kBand = 64;
      for (std::int64_t y = dw.min.y; y <= dw.max.y; y += kBand) {
        const std::int64_t y1 = std::min<std::int64_t>(y + kBand - 1, dw.max.y);
        part.setFrameBuffer(frame_for(int(y), y1 - y + 1));
        part.readPixelSampleCounts(int(y), int(y1));
        add();
      }
    } else if (header.type() == imf::DEEPTILE) {
      imf::DeepTiledInputPart part(file, 0);
      for (int ty = 0; ty < part.numYTiles(0); ++ty) {
        const IMATH_NAMESPACE::Box2i tile = part.dataWindowForTile(0, ty, 0);
        part.setFrameBuffer(frame_for(tile.min.y, std::int64_t(tile.max.y) - tile.min.y + 1));
        part.readPixelSampleCounts(0, part.numXTiles(0) - 1, ty, ty, 0, 0);
        add();
      }
    } else {
      return;  // not deep: nothing to count
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(Errc::ReadFailed, "cannot read the sample counts of deep '" + path + "' (truncated or corrupt?): " +
                                      e.what());
  }
  budget.check(path, double(samples) * nchannels * 4.0,
               "its sample counts ask for " + std::to_string(samples) + " deep samples x " + std::to_string(nchannels) +
                   " float channels");
}

}  // namespace mcr
