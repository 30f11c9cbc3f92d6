// Fuzz target: the OpenImageIO plugin's query-name parser (plugin/request.cpp, pure string
// work). Input = the name OIIO would hand the plugin, e.g. "x.exr.mcrecon?filter=box&radius=3";
// a first byte with bit 0 set reads it as an output spec, bit 1 adds the input's ".mcrecon"
// suffix when missing (so the fuzzer gets past the name check). Bad names must give
// mcr::Error, never a crash.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.h"
#include "request.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const bool output_side = data[0] & 1;
  std::string name(reinterpret_cast<const char*>(data + 1), size - 1);
  if ((data[0] & 2) && name.find('?') == std::string::npos) name += ".mcrecon";
  (void)mcr::plugin::is_plugin_name(name);
  (void)mcr::plugin::strip_oiiotool_temp(name);
  try {
    const auto [source, settings] = mcr::plugin::split_name(name);
    if (!mcr::plugin::is_plugin_name(name)) mcr::fuzz::fail("split_name accepted a name is_plugin_name refuses");
    const mcr::plugin::Request r = mcr::plugin::make_request(source, settings, output_side);
    const auto rec = mcr::plugin::make_reconstruction(r);
    (void)mcr::plugin::settings_key(r, rec->parameters_text());
    (void)mcr::plugin::notes_text(rec->notes());
  } catch (const mcr::Error& e) {
    mcr::fuzz::expect_user_error(e);
  }
  return 0;
}
