#include "io/frame_writer.h"

#include <OpenImageIO/imagebuf.h>

#include <set>

#include "io/atomic_write.h"
#include "io/spec_window.h"
#include "util/error.h"

namespace mcr {

using namespace OIIO;

namespace {
struct Source {
  const Image* image;
  int channel;
};

const char* kSuffixes[] = {"X", "Y", "Z", "W"};
}  // namespace

void write_result(const std::string& path, const Image& rgb, const Frame& input, const WriteOptions& options) {
  if (rgb.width() != input.width || rgb.height() != input.height || rgb.channels() < 3)
    throw Error(Errc::Internal, "write_result: result does not match the frame");
  std::vector<std::string> names = {"R", "G", "B", "A"};
  std::vector<Source> src = {{&rgb, 0}, {&rgb, 1}, {&rgb, 2}, {nullptr, 0}};
  if (const Pass* a = input.find(Role::Alpha)) src[3] = {&a->image, 0};

  std::set<std::string> taken(names.begin(), names.end());
  for (const auto& [name, image] : options.layers) {
    if (!image || image->width() != input.width || image->height() != input.height || image->channels() < 3)
      throw Error(Errc::Internal, "write_result: layer '" + name + "' does not match the frame");
    for (int c = 0; c < 3; ++c) {
      names.push_back(name + "." + "RGB"[c]);
      taken.insert(names.back());
      src.push_back({image, c});
    }
  }
  if (options.keep_passes) {
    auto add = [&](const Pass& p) {
      for (int c = 0; c < p.image.channels(); ++c) {
        // Loose-file passes get "<role>.X" names; the input's keep their own.
        std::string n = (p.source == input.path && c < int(p.channels.size()))
                            ? p.channels[std::size_t(c)]
                            : std::string(role_name(p.role)) + "." + kSuffixes[c % 4];
        if (!taken.insert(n).second) continue;
        names.push_back(n);
        src.push_back({&p.image, c});
      }
    };
    for (const Pass& p : input.passes)
      if (p.role != Role::Colour && p.role != Role::Alpha) add(p);
    for (const Pass& p : input.extra) add(p);
  }

  const int nc = int(names.size());
  ImageSpec spec(input.width, input.height, nc, TypeFloat);
  spec.channelnames = names;
  spec.alpha_channel = 3;
  set_window(spec, input.window);
  spec.attribute("compression", options.compression);
  spec.attribute("Software", "mcrecon");
  for (const auto& kv : options.attributes) spec.attribute(kv.first, kv.second);

  ImageBuf buf(spec);
  std::vector<float> pixels(std::size_t(input.width) * input.height * nc);
  const std::size_t n = std::size_t(input.width) * input.height;
  for (int c = 0; c < nc; ++c) {
    const Source& s = src[std::size_t(c)];
    if (!s.image) {
      for (std::size_t i = 0; i < n; ++i) pixels[i * nc + c] = 1.0f;
      continue;
    }
    const int sc = s.image->channels();
    const float* d = s.image->data();
    for (std::size_t i = 0; i < n; ++i) pixels[i * nc + c] = d[i * sc + s.channel];
  }
  buf.set_pixels(buf.roi(), TypeFloat, pixels.data());
  write_atomic(buf, path, "openexr");
}

}  // namespace mcr
