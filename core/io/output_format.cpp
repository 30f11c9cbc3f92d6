#include "io/output_format.h"

#include <cctype>

#include "util/error.h"

namespace mcr {

OutputFormat output_format(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  const auto dot = base.find_last_of('.');
  std::string ext = dot == std::string::npos || dot == 0 ? std::string() : base.substr(dot + 1);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == "exr") return OutputFormat::Exr;
  if (ext == "png") return OutputFormat::Png;
  if (ext == "jpg" || ext == "jpeg") return OutputFormat::Jpeg;
  if (ext == "tif" || ext == "tiff") return OutputFormat::Tiff;
  throw Error(Errc::InvalidArgument,
              "output '" + path + "': " + (ext.empty() ? std::string("no extension") : "'." + ext + "'") +
                  " is not a format mcrecon writes; use .exr (scene-linear float, every layer) or .png, .jpg, "
                  ".tif (display-referred through an OpenColorIO view)");
}

const char* format_label(OutputFormat f) {
  switch (f) {
    case OutputFormat::Exr: return "OpenEXR";
    case OutputFormat::Png: return "PNG";
    case OutputFormat::Jpeg: return "JPEG";
    case OutputFormat::Tiff: return "TIFF";
  }
  return "?";
}

const char* oiio_format_name(OutputFormat f) {
  switch (f) {
    case OutputFormat::Exr: return "openexr";
    case OutputFormat::Png: return "png";
    case OutputFormat::Jpeg: return "jpeg";
    case OutputFormat::Tiff: return "tiff";
  }
  return "";
}

}  // namespace mcr
