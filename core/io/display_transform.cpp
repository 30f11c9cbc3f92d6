#include "io/display_transform.h"

#include <OpenImageIO/color.h>
#include <OpenImageIO/imagebufalgo.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "util/error.h"

namespace mcr {

using namespace OIIO;

namespace {

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "(none)" : s;
}

bool contains(const std::vector<std::string>& names, const std::string& n) {
  for (const std::string& m : names)
    if (m == n) return true;
  return false;
}

// One config per path and thread: reading Blender's config takes milliseconds, and OIIO's
// ColorConfig is not documented as safe to share between threads.
const ColorConfig& config_for(const std::string& path) {
  thread_local std::string loaded;
  thread_local std::unique_ptr<ColorConfig> config;
  if (!config || loaded != path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      throw Error(Errc::FileNotFound, "OpenColorIO config '" + path + "' not found (is blender installed?)");
    auto c = std::make_unique<ColorConfig>(path);
    if (c->has_error()) throw Error(Errc::InvalidArgument, "OpenColorIO config '" + path + "': " + c->geterror());
    config = std::move(c);
    loaded = path;
  }
  return *config;
}

}  // namespace

void check_display_transform(const DisplayTransform& t) {
  const ColorConfig& c = config_for(t.config);
  const std::string where = " in OpenColorIO config '" + t.config + "'";
  const std::vector<std::string> displays = c.getDisplayNames();
  if (!contains(displays, t.display))
    throw Error(Errc::InvalidArgument, "display '" + t.display + "' is not" + where + "; it has: " + joined(displays));
  const std::vector<std::string> views = c.getViewNames(t.display);
  if (!contains(views, t.view))
    throw Error(Errc::InvalidArgument, "view '" + t.view + "' is not a view of display '" + t.display + "'" + where +
                                           "; it has: " + joined(views));
  if (!t.look.empty() && !contains(c.getLookNames(), t.look))
    throw Error(Errc::InvalidArgument, "look '" + t.look + "' is not" + where + "; it has: " + joined(c.getLookNames()));
  if (!contains(c.getColorSpaceNames(), t.from))
    throw Error(Errc::InvalidArgument, "colour space '" + t.from + "' is not" + where);
  if (!std::isfinite(t.exposure) || std::abs(t.exposure) > 64)
    throw Error(Errc::InvalidArgument, "exposure " + std::to_string(t.exposure) + " is out of range (stops, -64 to 64)");
  if (!(t.gamma > 0) || !std::isfinite(t.gamma) || t.gamma > 100)
    throw Error(Errc::InvalidArgument, "gamma " + std::to_string(t.gamma) + " is out of range (above 0, at most 100)");
}

ImageBuf to_display(const ImageBuf& linear, const DisplayTransform& t) {
  check_display_transform(t);
  ImageBuf src = linear;
  const int nc = linear.nchannels();
  const int rgb = nc < 3 ? nc : 3;
  if (t.exposure != 0.0) {
    std::vector<float> scale(std::size_t(nc), 1.0f);
    for (int ch = 0; ch < rgb; ++ch) scale[std::size_t(ch)] = float(std::exp2(t.exposure));
    src = ImageBufAlgo::mul(linear, scale);
  }
  // ColorConfig::createDisplayTransform is const in use; ociodisplay takes a non-const pointer.
  ColorConfig* config = const_cast<ColorConfig*>(&config_for(t.config));
  ImageBuf out = ImageBufAlgo::ociodisplay(src, t.display, t.view, t.from, t.look, false, "", "", config);
  if (out.has_error())
    throw Error(Errc::InvalidArgument, "display transform " + t.display + "/" + t.view + " failed: " + out.geterror());
  if (t.gamma != 1.0) {
    std::vector<float> power(std::size_t(nc), 1.0f);
    for (int ch = 0; ch < rgb; ++ch) power[std::size_t(ch)] = float(1.0 / t.gamma);
    out = ImageBufAlgo::pow(ImageBufAlgo::max(out, 0.0f), power);
  }
  return out;
}

}  // namespace mcr
