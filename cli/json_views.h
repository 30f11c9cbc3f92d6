#pragma once
// JSON views of core objects, shared by info, filters and the demo.
#include <nlohmann/json.hpp>

#include "filters/filter.h"
#include "image/pass.h"

namespace mcr::cli {

nlohmann::json to_json(const ParamValue& v);
nlohmann::json to_json(const ParamSpec& s);
nlohmann::json to_json(const FilterInfo& info);
nlohmann::json to_json(const Pass& p);
// A number, or null when not finite (JSON has no infinity).
nlohmann::json number(double v);

}  // namespace mcr::cli
