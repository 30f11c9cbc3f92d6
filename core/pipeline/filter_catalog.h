#pragma once
// Every filter a user can name, for the front ends: the registry's filters, then `auto`
// (pipeline/auto_filter.h), which runs and compares them and so lives above them.
#include <memory>
#include <string>
#include <vector>

#include "filters/filter.h"

namespace mcr {

std::vector<std::string> catalog_names();
const FilterInfo& catalog_info(const std::string& name);           // throws UnknownFilter
std::unique_ptr<Filter> make_catalog_filter(const std::string& name);  // throws UnknownFilter

}  // namespace mcr
