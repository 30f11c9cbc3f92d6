#include "filters/filter.h"

#include <cmath>

#include "util/error.h"

namespace mcr {

Filter::Filter(const FilterInfo& info) : params_(info.name, &info.params), info_(info) {}

void Filter::set(const std::string& name, const ParamValue& value) {
  params_.set(name, value);
  committed_ = false;
}

void Filter::set_text(const std::string& name, const std::string& text) {
  params_.set_text(name, text);
  committed_ = false;
}

void Filter::commit() {
  check_params();
  committed_ = true;
}

std::vector<Role> Filter::missing_passes(const Frame& frame) const {
  std::vector<Role> missing;
  for (Role r : info_.required)
    if (!frame.has(r)) missing.push_back(r);
  return missing;
}

Image Filter::execute(const Frame& frame, const ExecOptions& options) {
  if (!committed_) throw Error(Errc::Internal, "filter '" + info_.name + "': execute() before commit()");
  const std::vector<Role> missing = missing_passes(frame);
  if (!missing.empty()) {
    std::string names;
    for (Role r : missing) names += std::string(names.empty() ? "" : ", ") + role_name(r);
    throw Error(Errc::MissingPass, "filter '" + info_.name + "' needs the " + names + " pass" +
                                       (missing.size() > 1 ? "es" : "") + ", absent in '" + frame.path + "'");
  }
  frame.check_sizes();
  notes_.clear();

  const Image& colour = frame.image(Role::Colour);
  Image out = colour.channels() == 3 ? colour : colour.channel_range(0, 3);
  Roi roi = options.roi.empty() ? Roi::all(frame.width, frame.height) : options.roi.clipped(frame.width, frame.height);
  if (roi.empty()) return out;
  run(frame, roi, out, options.nthreads);

  // Safety net: nothing non-finite ever leaves a filter.
  repaired_ = 0;
  for (float& v : out.storage())
    if (!std::isfinite(v)) { v = 0.0f; ++repaired_; }
  if (repaired_) note(std::to_string(repaired_) + " non-finite output values replaced by 0");
  return out;
}

}  // namespace mcr
