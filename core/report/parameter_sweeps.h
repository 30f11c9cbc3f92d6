#pragma once
// Each filter's main parameter and the values the report sweeps it over (every other
// parameter at its default). The sweeps span each filter's useful range around its default;
// they were not chosen by looking at any result.
#include <string>
#include <vector>

namespace mcr {

struct ParameterSweep {
  std::string param;           // empty: the filter has no swept parameter (auto)
  std::vector<double> values;  // in increasing order
};

// An empty sweep for a filter without an entry.
const ParameterSweep& parameter_sweep(const std::string& filter);

}  // namespace mcr
