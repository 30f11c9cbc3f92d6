#pragma once
// What an mcrecon output may be: an OpenEXR file under a .exr name, with a compression
// OpenImageIO's EXR writer knows, and when an existing one counts as complete (--resume).
#include <string>

namespace mcr {

// The compressions OpenImageIO 2.4 writes to OpenEXR: none, rle, zip, zips, piz, pxr24,
// b44, b44a, dwaa, dwab; zip and zips take a level "zip:1".."zip:9", dwaa and dwab a
// quality "dwaa:45" (> 0). OIIO silently writes zip for any other name, so every front
// end checks here first. Returns the name in lower case; throws InvalidArgument naming
// the text and the valid names.
std::string checked_exr_compression(const std::string& text);

// Throws InvalidArgument unless `path` ends in .exr (any case): mcrecon writes OpenEXR
// only, and a .xyz name holding EXR data misleads every later reader.
void check_exr_name(const std::string& path);

// Why an existing file cannot be read completely (every pixel of every part decoded),
// "" when it can: a truncated or corrupt output is not a finished one.
std::string incomplete_file_reason(const std::string& path);

}  // namespace mcr
