#pragma once
// What a name or an output spec asks the mcrecon OpenImageIO plugin to do. Pure
// string work: nothing here calls OpenImageIO, so it is safe on any name OIIO
// hands us, including while OIIO 2.4 holds its global plugin lock.
#include <string>
#include <utility>
#include <vector>

#include "io/frame_reader.h"
#include "pipeline/reconstruction.h"

namespace mcr::plugin {

inline constexpr const char* kFormat = "mcrecon";
inline constexpr const char* kAttribPrefix = "mcrecon:";

// True for "x.exr.mcrecon" and "x.exr.mcrecon?k=v&...": the only input names the
// plugin answers. Anything else is rejected before any OpenImageIO call.
bool is_plugin_name(const std::string& name);

using KeyValues = std::vector<std::pair<std::string, std::string>>;

struct Request {
  std::string source;   // the render to read ("x.exr" for "x.exr.mcrecon?...")
  std::string filter;   // a catalog name: a registered filter or auto (pipeline/filter_catalog.h)
  KeyValues params;     // filter parameters, in the order given (last one wins)
  ReadOptions read;     // layer=, ROLE= pass overrides and half=
  bool accumulate = false;       // accumulation stage before the filter (the CLI's --accumulate)
  bool keep_passes = false;      // output side only (mcrecon:keep_passes)
  bool keep_components = false;  // output side only (mcrecon:keep_components; needs components=light_passes)
  std::string compression = "zip";  // output side only (mcrecon:compression)
};

// Splits "x.exr.mcrecon?filter=box&radius=3" into the source and its key=value
// list (split on '&', then the first '='; no URL decoding, like OIIO's
// Strutil::get_rest_arguments). Throws InvalidArgument for a malformed query.
std::pair<std::string, KeyValues> split_name(const std::string& name);

// Builds a request from key=value settings, in order: first `config` (the
// "mcrecon:" attributes of --iconfig or of the output spec, prefix removed), then
// the name's query. Keys: filter, layer, a pass role (colour, albedo, normal, ...,
// as the CLI's --pass ROLE=VALUE), half (input only: the other half buffer, as --half),
// accumulate (0, 1, true, false), keep_passes,
// keep_components and compression (output only), anything else is a parameter of the filter's table
// (checked by the filter). Throws InvalidArgument (no filter, bad role value, bad
// accumulate or keep_passes).
Request make_request(const std::string& source, const KeyValues& settings, bool output_side);

// The request's filter (every parameter set and committed) behind its accumulation
// stage: parameter errors surface here.
std::unique_ptr<Reconstruction> make_reconstruction(const Request& r);

// The reconstruction's notes as the mcreconNotes attribute (pipeline/reconstruction.h).
using mcr::notes_text;

// "filter=box layer= normal=... accumulate=0 radius=3": a stable text of what determines the
// result (after the filter canonicalised its parameters), to key caches and history.
std::string settings_key(const Request& r, const std::string& canonical_params);

// oiiotool writes "o_0001.exr" as "o_0001.963d536f.temp.exr" and renames it: the
// name the user gave, for messages and frame numbers. Other names are returned as is.
std::string strip_oiiotool_temp(const std::string& name);

// Shortest decimal text that reads back as the same float ("0.1", not "0.100000001").
std::string float_text(float v);

}  // namespace mcr::plugin
