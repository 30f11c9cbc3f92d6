#pragma once
// Limits from the input: which paths are read as images, and how much memory a
// file may make us allocate. A header can claim any size; what a file can hold
// is bounded by its size on disk times the best ratio its compression reaches.
// MCRECON_MAX_MEMORY (bytes: "8G", "500M", "2GiB") replaces that bound in every
// front end (CLI, OIIO plugin, Python module, Blender add-on).
#include <cstdint>
#include <memory>
#include <string>

#include <OpenImageIO/imageio.h>

namespace mcr {

// Throws unless `path` names a regular file (symlinks followed): FileNotFound, or
// NotAnImage for a directory, FIFO, device or socket. Uses stat only: opening a
// FIFO for reading blocks, and /dev/zero never ends.
void require_regular_file(const std::string& path);

// "8G" -> 8e9, "2GiB" -> 2^31, "500000" -> 500000 (K, M, G, T: powers of 1000;
// Ki, Mi, Gi, Ti: of 1024; an optional trailing B). Throws InvalidArgument naming `what`.
std::uint64_t parse_byte_count(const std::string& text, const std::string& what);

// "160 GB", "800 KB", "12 bytes" (decimal units, 3 significant digits).
std::string byte_text(double bytes);

// The most float pixel bytes one byte of a file in this format and compression
// can hold (see input_limits.cpp for the measurements behind each figure).
double max_expansion(const std::string& format, const std::string& compression);

// The pixel memory one input may make us allocate.
class InputBudget {
 public:
  // MCRECON_MAX_MEMORY when set, else file size x max_expansion + a floor, at
  // most absolute_cap(). Throws InvalidArgument for a malformed MCRECON_MAX_MEMORY.
  static InputBudget for_file(const std::string& path, const std::string& format, const std::string& compression);
  std::uint64_t bytes() const { return bytes_; }
  // Throws ReadFailed when `bytes` exceeds the budget: "cannot read 'x.exr': <claim>
  // (160 GB) but the 800 KB file can hold at most ~3.28 GB of pixels (set
  // MCRECON_MAX_MEMORY to allow more)"; claim: "its header asks for 100000x100000x4 float".
  void check(const std::string& path, double bytes, const std::string& claim) const;

  static constexpr double kAbsoluteCap = 32e9;  // without MCRECON_MAX_MEMORY, whatever the file
  // kAbsoluteCap, or half this machine's memory when less: a claim past that cannot be
  // served (a frame is held several times over while it is filtered), whatever the
  // compression ratio would allow (DWA reaches ~64000:1 on black frames).
  static double absolute_cap();
  static constexpr double kFloor = 64e6;         // any file may use this much: small images always read

 private:
  std::uint64_t bytes_ = 0;
  std::uint64_t file_bytes_ = 0;
  std::string user_limit_;  // MCRECON_MAX_MEMORY as the user typed it ("" = from the file)
  bool capped_ = false;     // the absolute cap, not the file, set bytes_
};

// For an OpenEXR file (by its magic number; any other file passes untouched), before
// anything opens it: OpenEXR allocates an attribute's value at the size its header
// declares before comparing that size with the file, and tile buffers at the tile
// size the header claims. Reads the headers' attribute lists (at most the file) and
// throws ReadFailed naming the file and attribute for a declared size past the end
// of the file, a name without terminator or longer than 255 bytes, a preview or
// string vector whose contents claim more than the attribute holds, and tiles larger
// than the data window (past a usual tile size) or than the input budget.
void check_exr_header_sizes(const std::string& path);

// Checks an opened image's header against its file's budget before any pixel is
// allocated: every part's pixels as float (all parts are held at once), a row of
// tiles (what a tiled read buffers), and a deep part's per-pixel tables.
InputBudget check_header_fits(OIIO::ImageInput& in, const std::string& path);

// For a deep OpenEXR file: counts the samples of part 0 from its sample-count
// tables alone (a row band at a time, no sample data) and checks samples x
// channels as float against the budget, before anything reads them.
void check_deep_samples(const std::string& path, int nchannels, const InputBudget& budget);

// For a WebP file (RIFF ... WEBP, whatever its name), before anything opens it: OpenImageIO's
// reader decodes the whole image when it opens the file (a 1 KB file claiming 9574x15486 made it
// allocate 593 MB), so the canvas size its first chunk declares is checked against the file's
// budget first (ReadFailed, as InputBudget::check words it). Any other file passes untouched.
void check_webp_header_size(const std::string& path);

// Every check before a file is opened, in order: require_regular_file, check_exr_header_sizes,
// check_webp_header_size (every front end's open goes through it).
void check_before_open(const std::string& path);

// check_before_open, then the file opened by the reader its extension names (x.exr by OpenEXR's),
// never by another: OpenImageIO otherwise tries every reader on a file the named one refuses,
// and some allocate what a header claims inside open() (a WebP bitstream in a file named .exr;
// JPEG 2000 decodes whole images there too). A name without a known extension is opened as
// OpenImageIO finds it. Throws NotAnImage naming the file and the reader's words.
std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path);

// A single-part deep EXR's chunk headers (scanlines, or one level of tiles) claim the sizes OpenEXR allocates before it
// reads them: refused (ReadFailed, naming the chunk) when a chunk's packed bytes lie past the
// file or its unpacked bytes exceed what they can expand to. Call after the checks above.
void check_deep_chunk_sizes(const std::string& path);

}  // namespace mcr
