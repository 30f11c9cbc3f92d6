#include "io/frame_writer.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <set>

#include "io/atomic_write.h"
#include "io/exr_output.h"
#include "io/exr_scanline_io.h"
#include "io/output_format.h"
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

float clamp_coverage(float a) { return a >= 0.0f ? (a <= 1.0f ? a : 1.0f) : (a < 0.0f ? 0.0f : 1.0f); }

// The file's bits per channel for a display format.
int display_bits(OutputFormat f, int bits) {
  if (bits) return bits;
  return f == OutputFormat::Tiff ? 16 : 8;
}

// PNG/JPEG/TIFF: R,G,B(,A) through the view, quantised by the writer.
void write_display(const std::string& path, OutputFormat f, const Image& rgb, const Frame& input,
                   const WriteOptions& options) {
  const bool alpha = f != OutputFormat::Jpeg;
  const int nc = alpha ? 4 : 3;
  ImageSpec spec(input.width, input.height, nc, TypeFloat);
  spec.channelnames = alpha ? std::vector<std::string>{"R", "G", "B", "A"} : std::vector<std::string>{"R", "G", "B"};
  spec.alpha_channel = alpha ? 3 : -1;
  ImageBuf linear(spec);
  const Pass* a = input.find(Role::Alpha);
  const std::size_t n = std::size_t(input.width) * input.height;
  std::vector<float> pixels(n * std::size_t(nc));
  const int rc = rgb.channels();
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) pixels[i * nc + c] = rgb.data()[i * rc + c];
    // Coverage in [0, 1] (a NaN as opaque): an 8/16-bit alpha cannot hold more.
    if (alpha) pixels[i * nc + 3] = a ? clamp_coverage(a->image.data()[i * a->image.channels()]) : 1.0f;
  }
  linear.set_pixels(linear.roi(), TypeFloat, pixels.data());
  // Cycles' colour is premultiplied. PNG and TIFF get straight colour through the view, as
  // Blender saves them, handed to the writer as such (no 8-bit premultiplied round trip);
  // JPEG, without alpha, the premultiplied colour: the image over black.
  if (alpha) linear = ImageBufAlgo::unpremult(linear);
  ImageBuf display = to_display(linear, options.display);
  ImageSpec& out = display.specmod();
  if (alpha) out.attribute("oiio:UnassociatedAlpha", 1);
  out.attribute("Software", "mcrecon");
  if (f == OutputFormat::Jpeg) out.attribute("compression", "jpeg:95");
  for (const auto& kv : options.attributes) out.attribute(kv.first, kv.second);
  const TypeDesc dtype = display_bits(f, options.bits) == 16 ? TypeUInt16 : TypeUInt8;
  display.set_write_format(dtype);
  write_atomic(display, path, oiio_format_name(f), dtype);
}
}  // namespace

void check_write(const std::string& path, const WriteOptions& options) {
  const OutputFormat f = output_format(path);
  if (!display_referred(f)) {
    checked_exr_compression(options.compression);
    if (options.bits)
      throw Error(Errc::InvalidArgument, "output '" + path + "': a bit depth (" + std::to_string(options.bits) +
                                             ") is for PNG and TIFF; EXR output is 32-bit float");
    return;
  }
  const std::string why = std::string("' is ") + format_label(f) + ": one display-referred RGB" +
                          (f == OutputFormat::Jpeg ? "" : "A") + " image; ";
  if (options.keep_passes)
    throw Error(Errc::InvalidArgument, "output '" + path + why + "--keep-passes (keep_passes) needs a .exr output");
  if (options.keep_components || !options.layers.empty())
    throw Error(Errc::InvalidArgument, "output '" + path + why + "--keep-components (keep_components) needs a .exr output");
  if (options.bits != 0 && options.bits != 8 && !(options.bits == 16 && f != OutputFormat::Jpeg))
    throw Error(Errc::InvalidArgument, "output '" + path + "': bit depth " + std::to_string(options.bits) + " for " +
                                           format_label(f) + "; " +
                                           (f == OutputFormat::Jpeg ? "JPEG takes 8" : "8 or 16"));
  check_display_transform(options.display);
}

Image rgba_result(const Image& rgb, const Frame& input) {
  Image out(rgb.width(), rgb.height(), 4, 1.0f);
  const Pass* a = input.find(Role::Alpha);
  const std::size_t rc = std::size_t(rgb.channels()), ac = a ? std::size_t(a->image.channels()) : 0;
  for (std::size_t i = 0, n = out.pixel_count(); i < n; ++i) {
    for (std::size_t c = 0; c < 3; ++c) out.data()[i * 4 + c] = rgb.data()[i * rc + c];
    if (a) out.data()[i * 4 + 3] = a->image.data()[i * ac];
  }
  return out;
}

void write_result(const std::string& path, const Image& rgb, const Frame& input, const WriteOptions& options) {
  if (rgb.width() != input.width || rgb.height() != input.height || rgb.channels() < 3)
    throw Error(Errc::Internal, "write_result: result does not match the frame");
  const OutputFormat format = output_format(path);
  if (display_referred(format)) {
    check_write(path, options);
    write_display(path, format, rgb, input, options);
    return;
  }
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
  if (exr_scanline_compression(options.compression)) {
    write_fd_atomic(path, [&](int fd) {
      return write_exr_scanlines(fd, path, input.width, input.height, input.window, names, pixels.data(),
                                 options.compression, options.attributes);
    });
    return;
  }
  const ImageBuf buf(spec, pixels.data());  // wraps the pixels: no second copy of a huge frame
  write_atomic(buf, path, "openexr");
}

}  // namespace mcr
