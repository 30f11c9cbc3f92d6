#include "json_views.h"

#include <cmath>

namespace mcr::cli {

using nlohmann::json;

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json to_json(const ParamValue& v) {
  return std::visit([](const auto& x) { return json(x); }, v);
}

json to_json(const ParamSpec& s) {
  json j = {{"name", s.name}, {"type", param_type_name(s.type)}, {"default", to_json(s.default_value)}, {"help", s.help}};
  if (s.type == ParamType::Int) { j["min"] = std::int64_t(s.min); j["max"] = std::int64_t(s.max); }
  if (s.type == ParamType::Float) { j["min"] = s.min; j["max"] = s.max; }
  if (s.type == ParamType::Enum) j["choices"] = s.choices;
  return j;
}

json to_json(const FilterInfo& info) {
  json params = json::array();
  for (const ParamSpec& s : info.params) params.push_back(to_json(s));
  json req = json::array(), opt = json::array();
  for (Role r : info.required) req.push_back(role_name(r));
  for (Role r : info.optional) opt.push_back(role_name(r));
  return {{"name", info.name},     {"summary", info.summary},   {"reference", info.reference},
          {"temporal", info.temporal}, {"input", info.deep_input ? "deep" : "image"}, {"lightfield", info.lightfield_input}, {"required_passes", req}, {"optional_passes", opt},
          {"nonfinite_policy", info.nonfinite_policy}, {"parameters", params}};
}

json to_json(const Pass& p) {
  return {{"role", role_name(p.role)}, {"name", p.name},   {"channels", p.channels},
          {"space", space_name(p.space)}, {"source", p.source}};
}

}  // namespace mcr::cli
