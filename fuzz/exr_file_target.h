#pragma once
// Shared by the frame reader targets: the fuzz bytes become a file (one per process,
// rewritten for every input) that read_frame and read_pass_file then read; bad files must
// give mcr::Error, and a frame that is returned must be consistent.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz_check.h"
#include "io/frame_reader.h"

namespace mcr::fuzz {

inline const std::string& input_path() {
  static const std::string path = [] {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir && *dir ? dir : "/tmp") + "/mcrecon_fuzz_" + std::to_string(getpid()) + ".exr";
  }();
  return path;
}

inline void remove_input() { std::remove(input_path().c_str()); }

inline void write_input(const std::uint8_t* data, std::size_t size) {
  static const bool cleanup = std::atexit(remove_input) == 0;  // after input_path() exists
  // Pixel budget 64 MB (the floor every file gets) unless MCRECON_MAX_MEMORY says otherwise:
  // what a file's budget allows is legitimate, but under ASan filling and freeing a few
  // hundred MB takes longer than libFuzzer's -timeout, so a 2.8 KB WebP allowed 310 MB was
  // reported as a hang. The budget rule itself is unit-tested (input_limits_test.cpp).
  static const bool budget = ::setenv("MCRECON_MAX_MEMORY", "64M", 0) == 0;
  (void)cleanup;
  (void)budget;
  std::FILE* f = std::fopen(input_path().c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) fail("cannot write the fuzz input file");
}

inline void check_image(const Image& im, int width, int height) {
  if (im.width() != width || im.height() != height) fail("a pass has another size than its frame");
  if (im.storage().size() != im.pixel_count() * std::size_t(im.channels())) fail("an image's buffer does not match its size");
}

inline void check_frame(const Frame& f) {
  if (f.width <= 0 || f.height <= 0) fail("read_frame returned an empty frame");
  for (const Pass& p : f.passes) check_image(p.image, f.width, f.height);
  for (const Pass& p : f.extra) check_image(p.image, f.width, f.height);
  if (f.deep) {
    const DeepSamples& d = *f.deep;
    if (d.width != f.width || d.height != f.height) fail("the deep samples have another size than the frame");
    if (d.offsets.size() != std::size_t(d.width) * std::size_t(d.height) + 1) fail("deep offsets of the wrong length");
    for (std::size_t i = 1; i < d.offsets.size(); ++i)
      if (d.offsets[i] < d.offsets[i - 1]) fail("deep offsets decrease");
    if (d.values.size() != d.channel_names.size()) fail("deep channels and names differ in count");
    for (const auto& v : d.values)
      if (v.size() != d.total_samples()) fail("a deep channel has another sample count than the offsets");
  }
}

inline void read_every_way() {
  const std::string& path = input_path();
  try {
    check_frame(read_frame(path));
  } catch (const Error& e) {
    expect_user_error(e);
  }
  try {
    ReadOptions o;
    o.require_colour = false;
    o.keep_extra = true;
    check_frame(read_frame(path, o));
  } catch (const Error& e) {
    expect_user_error(e);
  }
  for (Role r : {Role::Colour, Role::Depth}) {
    try {
      const Pass p = read_pass_file(path, r);
      check_image(p.image, p.image.width(), p.image.height());
    } catch (const Error& e) {
      expect_user_error(e);
    }
  }
}

}  // namespace mcr::fuzz
