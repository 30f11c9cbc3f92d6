#pragma once
// Writing a per-sample buffer as a deep OpenEXR (the convention in the README): the Blender
// per-sample export and the tests make their files with it.
#include <string>

#include "image/deep.h"

namespace mcr {

// Float channels in d's order, ZIPS compression, Z as the file's depth channel when present;
// d.attributes become header attributes (float when the text is a number). Through a temp file
// + rename (io/atomic_write.h); throws InvalidArgument for a path that is not .exr or a buffer
// whose sizes do not agree, WriteFailed when writing fails.
void write_deep_samples(const DeepSamples& d, const std::string& path);

}  // namespace mcr
