#pragma once
// Scene-linear RGB(A) to display-referred values through an OpenColorIO view, as Blender
// saves a PNG or JPEG: exposure (stops) in scene linear, the view (and look) of a display,
// then the display gamma. Blender's OCIO config by default: Blender renders are in its
// "Linear" space.
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>

namespace mcr {

struct DisplayTransform {
  std::string config = "/usr/share/blender/datafiles/colormanagement/config.ocio";
  std::string display = "sRGB";
  std::string view = "Standard";
  std::string look;             // "" = none
  std::string from = "Linear";  // scene-linear space of the renders in that config
  double exposure = 0.0;        // stops, applied before the view (Blender's Exposure)
  double gamma = 1.0;           // display gamma, applied after the view (Blender's Gamma)
};

// Throws unless the config file exists and reads, and display, view, look and the source
// space are in it (the message lists the names it has), exposure is finite and gamma > 0.
void check_display_transform(const DisplayTransform& t);

// The display-referred image (float, values in [0, 1] for the display's range). Channels past
// the third pass through unchanged: the caller un-premultiplies colour first when it wants
// straight alpha (PNG, TIFF).
OIIO::ImageBuf to_display(const OIIO::ImageBuf& linear, const DisplayTransform& t);

}  // namespace mcr
