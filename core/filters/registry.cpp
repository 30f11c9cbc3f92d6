#include "filters/registry.h"

#include "filters/image/atrous.h"
#include "filters/image/bilateral.h"
#include "filters/temporal/bmfr.h"
#include "filters/image/box.h"
#include "filters/image/guided.h"
#include "filters/image/gaussian.h"
#include "filters/image/pwaf.h"
#include "filters/lightfield/aaf.h"
#include "filters/lightfield/sheared.h"
#include "filters/lightfield/sheared4d.h"
#include "filters/samples/sweep.h"
#include "util/error.h"

namespace mcr {

namespace {

struct Entry {
  const FilterInfo& (*info)();
  std::unique_ptr<Filter> (*make)();
};

template <class F>
Entry entry() {
  return {&F::static_info, [] { return std::unique_ptr<Filter>(new F()); }};
}

const std::vector<Entry>& entries() {
  static const std::vector<Entry> list = {
      entry<BoxFilter>(),
      entry<GuidedFilter>(),
      entry<GaussianFilter>(),
      entry<BilateralFilter>(),
      entry<AtrousFilter>(),
      entry<PwafFilter>(),
      entry<BmfrFilter>(),
      entry<SweepFilter>(),
      entry<ShearedFilter>(),
      entry<Sheared4dFilter>(),
      entry<AafFilter>(),
  };
  return list;
}

const Entry& find(const std::string& name) {
  for (const Entry& e : entries())
    if (e.info().name == name) return e;
  std::string known;
  for (const Entry& e : entries()) known += (known.empty() ? "" : ", ") + e.info().name;
  throw Error(Errc::UnknownFilter, "unknown filter '" + name + "' (available: " + known + ")");
}

}  // namespace

std::vector<std::string> filter_names() {
  std::vector<std::string> names;
  for (const Entry& e : entries()) names.push_back(e.info().name);
  return names;
}

std::vector<std::string> image_filter_names() {
  std::vector<std::string> names;
  for (const Entry& e : entries())
    if (!e.info().deep_input) names.push_back(e.info().name);
  return names;
}

const FilterInfo& filter_info(const std::string& name) { return find(name).info(); }

std::unique_ptr<Filter> make_filter(const std::string& name) { return find(name).make(); }

}  // namespace mcr
