#include "filters/filter.h"

#include <algorithm>

#include "util/error.h"
#include "util/isa.h"

namespace mcr {

ParamTable with_common_params(ParamTable own) { return with_preparation_params(std::move(own), PrepSteps{}); }

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
  (void)isa();  // a bad MCRECON_ISA surfaces here, before any work
  unused_ = preparation_unused(params_, info_.steps);
  for (std::string& s : own_unused()) unused_.push_back(std::move(s));
  committed_ = true;
}

void Filter::unused_when(bool no_effect, const std::string& name, const std::string& why,
                         std::vector<std::string>& out) const {
  if (no_effect && params_.was_set(name)) out.push_back(name + " has no effect " + why);
}

void PassNeeds::require(Role r, const std::string& setting) {
  if (std::find(required.begin(), required.end(), r) != required.end()) return;
  required.push_back(r);
  why.push_back(setting);
  optional.erase(std::remove(optional.begin(), optional.end(), r), optional.end());
}

void PassNeeds::use(Role r) {
  if (std::find(required.begin(), required.end(), r) == required.end() &&
      std::find(optional.begin(), optional.end(), r) == optional.end())
    optional.push_back(r);
}

PassNeeds Filter::own_needs() const {
  PassNeeds n;
  for (Role r : info_.required) n.require(r);
  for (Role r : info_.optional) n.use(r);
  return n;
}

PassNeeds Filter::needs() const {
  PassNeeds n = own_needs();
  std::vector<Role> req, opt;
  std::vector<std::string> why;
  preparation_needs(params_, info_.steps, req, why, opt);
  for (std::size_t i = 0; i < req.size(); ++i) n.require(req[i], why[i]);
  for (Role r : opt) n.use(r);
  return n;
}

std::vector<Role> Filter::missing_passes(const Frame& frame) const {
  std::vector<Role> missing;
  for (Role r : needs().required)
    if (!frame.has(r)) missing.push_back(r);
  return missing;
}

Image Filter::execute(const Frame& frame, const ExecOptions& options) {
  if (!committed_) throw Error(Errc::Internal, "filter '" + info_.name + "': execute() before commit()");
  const PassNeeds need = needs();
  std::string names;
  std::size_t count = 0;
  for (std::size_t i = 0; i < need.required.size(); ++i)
    if (!frame.has(need.required[i])) {
      names += std::string(count++ ? ", " : "") + role_name(need.required[i]) +
               (need.why[i].empty() ? "" : " (for " + need.why[i] + ")");
    }
  if (count)
    throw Error(Errc::MissingPass, "filter '" + info_.name + "' needs the " + names + " pass" + (count > 1 ? "es" : "") +
                                       ", absent in '" + frame.path + "'");
  frame.check_sizes();
  notes_.clear();
  const int nthreads = options.nthreads;
  const int w = frame.width, h = frame.height;
  const Image& input = frame.image(Role::Colour);
  const Roi roi = options.roi.empty() ? Roi::all(w, h) : options.roi.clipped(w, h);
  if (roi.empty()) {  // nothing to filter: the input as it is
    prepared_ = Prepared{};
    Image out = rgb_copy(input, nthreads);
    repaired_ = finish(prepared_, input, roi, nthreads, out);
    return out;
  }

  prepare(frame, params_, info_.steps, reads(roi, w, h), nthreads, prepared_);
  for (std::string& n : prepared_.notes) notes_.push_back(std::move(n));

  Image out;
  if (run_in_place()) {
    run(*prepared_.frame, prepared_.colour, roi, prepared_.colour, nthreads);
    out = std::move(prepared_.colour);
  } else {
    out = prepared_.colour;
    run(*prepared_.frame, prepared_.colour, roi, out, nthreads);
  }
  if (out.width() != w || out.height() != h || out.channels() != 3)
    throw Error(Errc::Internal, "filter '" + info_.name + "' returned an output of another size");
  repaired_ = finish(prepared_, input, roi, nthreads, out);
  if (repaired_) note(std::to_string(repaired_) + " non-finite output values replaced by 0");
  prepared_.own = Frame{};  // the copied passes are not kept between frames
  prepared_.colour = Image{};
  return out;
}

}  // namespace mcr
