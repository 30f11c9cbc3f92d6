#pragma once
// The filter registry: make_filter("box"), filter_names(). Adding a filter means
// one line in registry.cpp plus the filter's own files.
#include <memory>
#include <string>
#include <vector>

#include "filters/filter.h"

namespace mcr {

std::vector<std::string> filter_names();
// The filters that run on flat frames (all but the deep_input ones, which read per-sample buffers).
std::vector<std::string> image_filter_names();
const FilterInfo& filter_info(const std::string& name);     // throws UnknownFilter
std::unique_ptr<Filter> make_filter(const std::string& name);  // throws UnknownFilter

}  // namespace mcr
