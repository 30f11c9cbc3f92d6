#pragma once
// A small deep OpenEXR file for reader tests: w x h RGBA, n samples in every pixel.
#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <string>

namespace mcr {

// Colour `value` in every sample, alpha 0.5.
inline void write_deep_file(const std::string& path, int w, int h, int n, float value) {
  OIIO::ImageSpec spec(w, h, 4, OIIO::TypeFloat);
  spec.channelnames = {"R", "G", "B", "A"};
  spec.alpha_channel = 3;
  spec.deep = true;
  spec.attribute("compression", "zips");
  OIIO::DeepData dd(spec);
  for (int p = 0; p < w * h; ++p) {
    dd.set_samples(p, n);
    for (int s = 0; s < n; ++s)
      for (int c = 0; c < 4; ++c) dd.set_deep_value(p, c, s, c == 3 ? 0.5f : value);
  }
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out && out->open(path, spec) && out->write_deep_image(dd)) << OIIO::geterror();
  out->close();
}

}  // namespace mcr
