#include <iomanip>
#include <iostream>

#include "commands.h"
#include "json_views.h"
#include "pipeline/filter_catalog.h"

namespace mcr::cli {

Run add_filters(CLI::App& app) {
  auto json_out = std::make_shared<bool>(false);
  app.add_flag("--json", *json_out, "machine-readable output");
  return [json_out] {
    if (*json_out) {
      nlohmann::json list = nlohmann::json::array();
      for (const auto& name : catalog_names()) list.push_back(to_json(catalog_info(name)));
      std::cout << nlohmann::json{{"filters", list}}.dump(2) << "\n";
      return 0;
    }
    for (const auto& name : catalog_names()) {
      const FilterInfo& f = catalog_info(name);
      std::cout << f.name << ": " << f.summary << (f.temporal ? " [temporal]" : "") << (f.lightfield_input ? " [light field: deep EXR input]" : f.deep_input ? " [per-sample: deep EXR input]" : "") << "\n";
      // Under the default settings (other settings may need more: `info` and errors say which).
      auto filter = make_catalog_filter(name);
      filter->commit();
      const PassNeeds need = filter->needs();
      std::cout << "  needs (defaults):";
      for (Role r : need.required) std::cout << " " << role_name(r);
      if (!need.optional.empty()) {
        std::cout << "; uses when present:";
        for (Role r : need.optional) std::cout << " " << role_name(r);
      }
      const PrepSteps& st = f.steps;
      std::cout << "\n  preparation steps:" << (st.holes ? " holes" : "") << (st.albedo_prefilter ? " albedo_prefilter" : "")
                << (st.demodulate ? " demodulate" : "") << (st.outliers ? " outliers" : "")
                << (!st.holes && !st.albedo_prefilter && !st.demodulate && !st.outliers ? " none" : "");
      std::cout << "\n  non-finite input: " << f.nonfinite_policy << "\n";
      for (const ParamSpec& s : f.params) {
        std::cout << "  --set " << std::left << std::setw(16) << s.name << " " << param_type_name(s.type)
                  << ", default " << param_value_text(s.default_value);
        if (s.type != ParamType::Bool) std::cout << ", " << param_range_text(s);
        std::cout << ": " << s.help << "\n";
      }
    }
    return 0;
  };
}

}  // namespace mcr::cli
