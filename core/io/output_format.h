#pragma once
// What an output's name says it holds: OpenEXR (scene-linear float, every layer), or a
// display-referred picture (PNG, JPEG, TIFF) through an OpenColorIO view. mcrecon writes what
// the extension says, and refuses a name it cannot honour rather than write EXR data
// under it.
#include <string>

namespace mcr {

enum class OutputFormat { Exr, Png, Jpeg, Tiff };

// By the file name's extension, any case: .exr; .png; .jpg or .jpeg; .tif or .tiff.
// Throws InvalidArgument naming the path and the extensions mcrecon writes.
OutputFormat output_format(const std::string& path);

// PNG, JPEG, TIFF: display-referred (through the view), one RGB(A) image, no layers.
inline bool display_referred(OutputFormat f) { return f != OutputFormat::Exr; }

// "OpenEXR", "PNG", "JPEG", "TIFF": for messages.
const char* format_label(OutputFormat f);

// OpenImageIO's format name: "openexr", "png", "jpeg", "tiff".
const char* oiio_format_name(OutputFormat f);

}  // namespace mcr
