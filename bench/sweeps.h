#pragma once
// What the run-time-against-error benchmarks sweep per filter: the main parameter, its
// values, and further settings ("key=value key=value") it is swept under. Benchmark data,
// kept out of the core's filter descriptors.
#include <string>
#include <vector>

#include "filters/filter.h"

namespace mcr::bench {

struct Sweep {
  std::string param;              // empty: only the filter's defaults
  std::vector<double> values;
  std::vector<std::string> variants;  // the filter's own, after the common ones
};

// The sweep of a registered filter (an empty one for a filter without an entry).
const Sweep& sweep_for(const std::string& filter);

// Every setting the quality benchmark runs for a filter, in its order: the common
// variants ("", firefly_k=2, firefly_k=1), then the filter's own.
std::vector<std::string> sweep_variants(const std::string& filter);

// "a,b" -> {"a", "b"} (empty items dropped), for --scenes / --filters; sep '+' splits auto's
// choice of two filters.
std::vector<std::string> split_list(const std::string& s, char sep = ',');
// True when `list` is empty (everything wanted) or holds `name`.
bool wanted(const std::vector<std::string>& list, const std::string& name);
// Sets every key=value of `variant` ("k=v k=v") on the filter; returns them space-separated.
std::string apply_variant(Filter& filter, const std::string& variant);

}  // namespace mcr::bench
