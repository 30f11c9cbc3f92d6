#pragma once
// The one output guard every writer goes through (CLI, plugin, Python, add-on, demo):
// an output is never one of the run's inputs (same path, another spelling, a
// symlink or hard link to it), is a regular file or a new path (never a device,
// FIFO, socket or directory), and, for a sequence, every frame has its own file.
#include <string>
#include <vector>

#include "io/sequence.h"

namespace mcr {

// Throws WriteFailed unless `path` is a new path or (through symlinks) a regular file.
void check_output_target(const std::string& path);

// Throws InvalidArgument when output is one of the inputs, WriteFailed when it is not
// a regular file or a new path, or its directory is missing or not writable.
// Call before any expensive work.
void check_output_path(const std::string& output, const std::vector<std::string>& inputs);
// The same for every output of a run, in n log n; also InvalidArgument when two
// outputs are one file.
void check_output_paths(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);
// A sequence's outputs (pattern over frames), once for the whole run: an error names
// the pattern and the two frames that would share a file.
void check_sequence_outputs(const std::string& pattern, const FrameList& frames,
                            const std::vector<std::string>& inputs);

// "the disk is full (No space left on device)" for ENOSPC, likewise EDQUOT and
// EFBIG; strerror otherwise.
std::string write_error_text(int err);

}  // namespace mcr
