#include "pipeline/filter_catalog.h"

#include "filters/registry.h"
#include "pipeline/auto_filter.h"
#include "util/error.h"

namespace mcr {

namespace {

void throw_unknown(const std::string& name) {
  std::string known;
  for (const std::string& n : catalog_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error(Errc::UnknownFilter, "unknown filter '" + name + "' (available: " + known + ")");
}

}  // namespace

std::vector<std::string> catalog_names() {
  std::vector<std::string> names = filter_names();
  names.push_back(AutoFilter::static_info().name);
  return names;
}

const FilterInfo& catalog_info(const std::string& name) {
  if (name == AutoFilter::static_info().name) return AutoFilter::static_info();
  for (const std::string& n : filter_names())
    if (n == name) return filter_info(name);
  throw_unknown(name);
  return AutoFilter::static_info();  // not reached
}

std::unique_ptr<Filter> make_catalog_filter(const std::string& name) {
  if (name == AutoFilter::static_info().name) return std::make_unique<AutoFilter>();
  for (const std::string& n : filter_names())
    if (n == name) return make_filter(name);
  throw_unknown(name);
  return nullptr;  // not reached
}

}  // namespace mcr
