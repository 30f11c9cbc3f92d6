#pragma once
// Reading a frame (colour + feature passes) with OpenImageIO.
#include <string>
#include <utility>
#include <vector>

#include "image/pass.h"

namespace mcr {

struct PassOverride {
  Role role;
  std::string value;  // a file (loose pass) or a channel group of the input ("ViewLayer.Normal")
};

struct ReadOptions {
  std::string layer;                    // "" = the first view layer with a colour pass
  std::vector<PassOverride> overrides;  // --pass ROLE=VALUE
  bool require_colour = true;           // MissingPass when no colour pass is found
  bool keep_extra = false;              // fill Frame::extra with every unused channel group
  std::string second_half;              // the other half buffer of this render (io/half_buffers.h): the
                                        // frame is their mean, with a variance pass from their difference
};

// Parses "normal=normals.exr" into an override; throws InvalidArgument.
PassOverride parse_pass_override(const std::string& text);

// The overrides that name a file (not a channel group) and the second half buffer: inputs
// of the run, which no output may overwrite.
std::vector<std::string> loose_pass_files(const ReadOptions& options);

// Reads every pass of the file (deep files: the per-sample buffer plus the
// flattened passes). Throws FileNotFound, NotAnImage, ReadFailed, MissingPass,
// SizeMismatch, each naming the file and pass.
Frame read_frame(const std::string& path, const ReadOptions& options = {});

// The checks read_frame makes before reading pixels (a regular file, an image, a header its
// bytes can back), without reading them: for front ends that take many files and should fail
// on a bad one before any work. Throws as read_frame.
void check_image_file(const std::string& path);

// The same frame from channels already in memory (interleaved float, one name per
// channel, as read_frame would find them in `path`, which names them in messages):
// same layer choice, roles, overrides and checks. For front ends that receive
// pixels rather than a file (the OpenImageIO output plugin).
Frame frame_from_channels(const std::string& path, int width, int height, const std::vector<std::string>& channel_names,
                          std::vector<float> pixels, const ReadOptions& options = {});

// A loose pass file or a plain image read as one pass of the given role.
Pass read_pass_file(const std::string& path, Role role);

}  // namespace mcr
