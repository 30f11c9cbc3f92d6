#include "filters/filter.h"

#include <algorithm>
#include <cmath>

#include "filters/pull_push.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

ParamTable with_common_params(ParamTable own) {
  own.push_back(ParamSpec::Bool("demodulate", false, "divide the colour by the albedo pass before filtering and multiply after"));
  own.push_back(ParamSpec::Float("albedo_floor", 0.01, 1e-6, 1.0, "albedo is clamped to [albedo_floor, 1] for demodulation"));
  own.push_back(ParamSpec::Enum("holes", "auto", {"auto", "none", "sample_count", "alpha"},
                                "unsampled pixels to fill by pull-push first: auto = sample_count 0 when that pass exists"));
  return own;
}

namespace {

// Weight 0 for unsampled pixels, 1 otherwise; empty when nothing is missing.
std::vector<float> hole_weights(const Frame& frame, const std::string& mode) {
  Role role = Role::SampleCount;
  if (mode == "none") return {};
  if (mode == "alpha") role = Role::Alpha;
  const Pass* p = frame.find(role);
  if (!p) {
    if (mode == "auto") return {};
    throw Error(Errc::MissingPass, std::string("holes=") + mode + " needs the " + role_name(role) + " pass, absent in '" + frame.path + "'");
  }
  std::vector<float> w(p->image.pixel_count());
  bool any = false;
  for (std::size_t i = 0; i < w.size(); ++i) {
    const float v = p->image.data()[i * std::size_t(p->image.channels())];
    w[i] = v > 0.0f ? 1.0f : 0.0f;
    any = any || w[i] == 0.0f;
  }
  return any ? w : std::vector<float>{};
}

}  // namespace

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

  // Sparse renders: fill every pass at the unsampled pixels first (thesis 5.1).
  const Frame* src = &frame;
  Frame filled;
  const std::vector<float> holes = hole_weights(frame, params_.get_enum("holes"));
  if (!holes.empty()) {
    filled = frame;
    for (Pass& p : filled.passes)
      if (p.role != Role::SampleCount && p.role != Role::Alpha) pull_push_fill(p.image, holes, options.nthreads);
    src = &filled;
    note("filled " + std::to_string(std::count(holes.begin(), holes.end(), 0.0f)) + " unsampled pixels by pull-push");
  }
  const Image& input = src->image(Role::Colour);
  Image colour = input.channels() == 3 ? input : input.channel_range(0, 3);

  // Albedo demodulation: filter the illumination, not the texture.
  Image albedo;
  if (params_.get_bool("demodulate")) {
    const Pass* a = src->find(Role::Albedo);
    if (!a) throw Error(Errc::MissingPass, "filter '" + info_.name + "': demodulate=true needs the albedo pass, absent in '" + frame.path + "'");
    const float lo = float(params_.get_float("albedo_floor"));
    albedo = Image(frame.width, frame.height, 3);
    for (std::size_t i = 0; i < albedo.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c) {
        const float v = a->image.data()[i * std::size_t(a->image.channels()) + std::size_t(std::min(c, a->image.channels() - 1))];
        albedo.data()[i * 3 + c] = std::isfinite(v) ? std::clamp(v, lo, 1.0f) : 1.0f;
      }
    for (std::size_t i = 0; i < colour.storage().size(); ++i) colour.storage()[i] /= albedo.storage()[i];
  }

  Image out = colour;
  Roi roi = options.roi.empty() ? Roi::all(frame.width, frame.height) : options.roi.clipped(frame.width, frame.height);
  if (roi.empty()) return out;
  run(*src, colour, roi, out, options.nthreads);
  if (!albedo.empty())
    for (std::size_t i = 0; i < out.storage().size(); ++i) out.storage()[i] *= albedo.storage()[i];

  // Safety net: nothing non-finite ever leaves a filter.
  repaired_ = 0;
  for (float& v : out.storage())
    if (!std::isfinite(v)) { v = 0.0f; ++repaired_; }
  if (repaired_) note(std::to_string(repaired_) + " non-finite output values replaced by 0");
  return out;
}

}  // namespace mcr
