#pragma once
// Nothing is lost: every output is written to a hidden temp file of its own in the
// target's directory and renamed over the target only when complete.
//
// Temp names: ".<name>.mcrecon-tmp.<pid>.<n><random>", created exclusively (O_EXCL),
// the visible part cut so the whole fits NAME_MAX. Two runs writing one output each
// write their own temp and rename it: both succeed, the last rename wins, and the
// output is always one complete file (rename is atomic), never a mix.
#include <functional>
#include <string>

#include <OpenImageIO/imagebuf.h>

#include "io/output_guard.h"

namespace mcr {

// Writes buf to path through a temp file + rename; format from the extension unless
// given ("openexr", "png"); dtype: the file's pixel type (TypeUnknown: buf's).
// Refuses a target that is not a regular file or a new path (check_output_target).
// Removes the temps of earlier runs on this target whose process is gone.
void write_atomic(const OIIO::ImageBuf& buf, const std::string& path, const std::string& format = "",
                  OIIO::TypeDesc dtype = OIIO::TypeUnknown);

// The same for a writer of its own: body writes the file to the descriptor (the temp's, open
// for writing) and returns 0, or the errno of its first failed write (reported naming path).
void write_fd_atomic(const std::string& path, const std::function<int(int fd)>& body);

// The same for a text file (reports such as results.json).
void write_text_atomic(const std::string& text, const std::string& path);

// Async-signal-safe: unlinks the temp files being written, if any (for signal handlers).
void remove_pending_temp() noexcept;

// The prefix every temp name for path starts with: ".<name, cut>.mcrecon-tmp.".
std::string temp_prefix_for(const std::string& path);

}  // namespace mcr
