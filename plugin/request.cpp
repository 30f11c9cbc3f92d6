#include "request.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>

#include "io/exr_output.h"
#include "util/error.h"

namespace mcr::plugin {

namespace {
constexpr const char kExt[] = ".mcrecon";
constexpr std::size_t kExtLen = sizeof(kExt) - 1;

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A yes/no setting: 0, 1, true or false, as typed (the error names the image, the setting
// and the text).
bool parse_switch(const std::string& key, const std::string& value, const std::string& image) {
  if (value == "1" || value == "true") return true;
  if (value == "0" || value == "false") return false;
  throw Error(Errc::InvalidArgument, "'" + strip_oiiotool_temp(image) + "': " + key +
                                         " expects 0, 1, true or false, got '" + value + "'");
}
}  // namespace

bool is_plugin_name(const std::string& name) {
  const std::string base = name.substr(0, name.find('?'));
  return base.size() > kExtLen && lower(base.substr(base.size() - kExtLen)) == kExt;
}

std::pair<std::string, KeyValues> split_name(const std::string& name) {
  const auto q = name.find('?');
  std::string base = name.substr(0, q);
  if (!is_plugin_name(base))
    throw Error(Errc::InvalidArgument, "'" + name + "' is not an mcrecon name (RENDER.exr.mcrecon?filter=NAME&...)");
  KeyValues kv;
  if (q != std::string::npos) {
    const std::string query = name.substr(q + 1);
    std::size_t start = 0;
    while (start <= query.size()) {
      const auto amp = query.find('&', start);
      const std::string tok = query.substr(start, amp == std::string::npos ? std::string::npos : amp - start);
      const auto eq = tok.find('=');
      if (eq == std::string::npos || eq == 0)
        throw Error(Errc::InvalidArgument,
                    "'" + name + "': expected KEY=VALUE between '&' after '?', got '" + tok + "'");
      kv.emplace_back(tok.substr(0, eq), tok.substr(eq + 1));
      if (amp == std::string::npos) break;
      start = amp + 1;
    }
  }
  return {base.substr(0, base.size() - kExtLen), kv};
}

Request make_request(const std::string& source, const KeyValues& settings, bool output_side) {
  Request r;
  r.source = source;
  for (const auto& [key, value] : settings) {
    if (key == "filter") {
      r.filter = value;
    } else if (key == "layer") {
      r.read.layer = value;
    } else if (role_from_name(key)) {
      r.read.overrides.push_back(parse_pass_override(key + "=" + value));  // the CLI's --pass checks
    } else if (key == "half") {
      // The other half buffer of the source file: the input side reads both (the output side
      // is handed pixels, not a file).
      if (output_side)
        throw Error(Errc::InvalidArgument, "half=" + value + " for '" + source + "': the output plugin is handed the "
                                           "pixels, not the file; read the render through the input plugin "
                                           "(x.exr.mcrecon?filter=F&half=OTHER.exr)");
      if (value.empty()) throw Error(Errc::InvalidArgument, "half= for '" + source + "' names no file");
      r.read.second_half = value;
    } else if (key == "accumulate") {
      r.accumulate = parse_switch(key, value, source);
    } else if (output_side && key == "keep_passes") {
      r.keep_passes = parse_switch(key, value, source);
    } else if (output_side && key == "keep_components") {
      r.keep_components = parse_switch(key, value, source);
    } else if (output_side && key == "compression") {
      r.compression = checked_exr_compression(value);  // OIIO would write zip for a bad name
    } else {
      r.params.emplace_back(key, value);
    }
  }
  if (r.filter.empty())
    throw Error(Errc::InvalidArgument,
                "no filter given for '" + source + "': add ?filter=NAME to the name, --iconfig mcrecon:filter NAME, "
                "or --attrib mcrecon:filter NAME for the output (see `mcrecon filters`)");
  r.read.keep_extra = r.keep_passes;
  return r;
}

std::unique_ptr<Reconstruction> make_reconstruction(const Request& r) {
  return std::make_unique<Reconstruction>(make_committed_filter(r.filter, r.params), r.accumulate);
}

std::string settings_key(const Request& r, const std::string& canonical_params) {
  std::string key = "filter=" + r.filter + " layer=" + r.read.layer;
  for (const PassOverride& o : r.read.overrides) key += std::string(" ") + role_name(o.role) + "=" + o.value;
  key += " half=" + r.read.second_half;
  key += " keep_passes=" + std::to_string(int(r.keep_passes)) + " accumulate=" + std::to_string(int(r.accumulate)) +
         " " + canonical_params;
  return key;
}

std::string strip_oiiotool_temp(const std::string& name) {
  // ".<8 hex digits>.temp" right before the extension (or at the end).
  const auto slash = name.find_last_of('/');
  const std::size_t stem = slash == std::string::npos ? 0 : slash + 1;
  auto dot = name.find_last_of('.');
  std::string ext;
  if (dot != std::string::npos && dot >= stem && name.compare(dot, std::string::npos, ".temp") != 0) {
    ext = name.substr(dot);
  } else {
    dot = name.size();
  }
  const std::string head = name.substr(0, dot);
  constexpr std::size_t kTail = 1 + 8 + 5;  // ".xxxxxxxx.temp"
  if (head.size() < stem + kTail + 1 || head.compare(head.size() - 5, 5, ".temp") != 0) return name;
  const std::size_t h = head.size() - kTail;
  if (head[h] != '.') return name;
  for (std::size_t i = h + 1; i < h + 9; ++i)
    if (!std::isxdigit(static_cast<unsigned char>(head[i]))) return name;
  return head.substr(0, h) + ext;
}

std::string float_text(float v) {
  char buf[64];
  for (int prec = 6; prec <= 9; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, double(v));
    if (std::strtof(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace mcr::plugin
