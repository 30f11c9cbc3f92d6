#include "report/parameter_sweeps.h"

#include <map>

namespace mcr {

const ParameterSweep& parameter_sweep(const std::string& filter) {
  static const std::map<std::string, ParameterSweep> table = {
      {"box", {"radius", {1, 2, 3, 4, 6}}},
      {"gaussian", {"sigma", {0.5, 1, 1.5, 2, 3}}},
      {"bilateral", {"spatial_sigma", {1, 2, 3, 4, 5}}},
      {"atrous", {"iterations", {1, 2, 3, 4, 5, 6}}},
      {"guided", {"radius", {2, 4, 8, 12, 16}}},
      {"pwaf", {"max_radius", {4, 6, 8, 12}}},
      {"bmfr", {"block_size", {16, 32, 64}}},
      {"sweep", {"width", {1.5, 2, 3, 4, 6}}},
      {"sheared", {"max_width", {8, 16, 24, 32}}},
      {"sheared4d", {"max_width", {8, 16, 32}}},
      {"aaf", {"max_width", {8, 16, 24, 32}}},
  };
  static const ParameterSweep none;
  const auto it = table.find(filter);
  return it == table.end() ? none : it->second;
}

}  // namespace mcr
