#pragma once
// Nothing is lost: every output is written to a hidden temp file in the target's
// directory and renamed over the target only when complete.
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace mcr {

// Throws InvalidArgument when output is one of the inputs, WriteFailed when its
// directory is missing or not writable. Call before any expensive work.
void check_output_path(const std::string& output, const std::vector<std::string>& inputs);
// The same for every output of a sequence, in n log n rather than outputs x inputs.
void check_output_paths(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

// Writes buf to path through a temp file + rename; format from the extension
// unless given ("openexr", "png"). Removes stale temps of earlier killed runs.
void write_atomic(const OIIO::ImageBuf& buf, const std::string& path, const std::string& format = "");

// Async-signal-safe: unlinks the temp file being written, if any (for SIGINT/SIGTERM handlers).
void remove_pending_temp() noexcept;

// The temp name used for path: "<dir>/.<name>.mcrecon-tmp.<pid>".
std::string temp_path_for(const std::string& path);

}  // namespace mcr
