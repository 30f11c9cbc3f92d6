#include "filters/filter.h"

#include <algorithm>

#include "kernels/feature_activity.h"
#include "kernels/feature_guides.h"
#include "kernels/foveation.h"
#include "kernels/noise_scale.h"
#include "prepare/empty_pixels.h"
#include "prepare/first_hit.h"
#include "prepare/step_back.h"
#include "util/error.h"
#include "util/isa.h"

namespace mcr {

ParamTable with_common_params(ParamTable own) {
  ParamTable t = with_preparation_params(std::move(own), PrepSteps{});
  t.push_back(alpha_param());
  return t;
}

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
  if (no_effect) report_unused(params_, name, why, out);
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

void check_passes(const PassNeeds& need, const Frame& frame, const std::string& who) {
  // Missing passes grouped by the setting that needs them, in order of first mention:
  // "the normal, position passes (for guide=normal_position)".
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;
  for (std::size_t i = 0; i < need.required.size(); ++i) {
    if (frame.has(need.required[i])) continue;
    auto g = std::find_if(groups.begin(), groups.end(), [&](const auto& e) { return e.first == need.why[i]; });
    if (g == groups.end()) g = groups.insert(groups.end(), {need.why[i], {}});
    g->second.push_back(role_name(need.required[i]));
  }
  if (groups.empty()) return;
  std::string text;
  for (const auto& [why, roles] : groups) {
    std::string names;
    for (const std::string& r : roles) names += (names.empty() ? "" : ", ") + r;
    text += std::string(text.empty() ? "the " : "; the ") + names + (roles.size() > 1 ? " passes" : " pass") +
            (why.empty() ? "" : " (for " + why + ")");
  }
  throw Error(Errc::MissingPass, who + " needs " + text + ", absent in '" + frame.path + "'");
}

PassNeeds Filter::own_needs() const {
  PassNeeds n;
  for (Role r : info_.required) n.require(r);
  // The feature block's use_<f>=on makes a pass required, use_<f>=off unused (no-op
  // without the block).
  std::vector<Role> req, off;
  std::vector<std::string> why;
  feature_needs(params_, req, why, off);
  for (std::size_t i = 0; i < req.size(); ++i) n.require(req[i], why[i]);
  for (Role r : info_.optional)
    if (std::find(off.begin(), off.end(), r) == off.end()) n.use(r);
  return n;
}

std::vector<std::string> Filter::own_unused() const {
  std::vector<std::string> u = feature_unused(params_);
  for (std::string& s : foveation_unused(params_)) u.push_back(std::move(s));
  return u;
}

PassNeeds Filter::needs() const {
  PassNeeds n = own_needs();
  std::vector<Role> req, opt;
  std::vector<std::string> why;
  preparation_needs(params_, prep_steps(), req, why, opt);
  for (std::size_t i = 0; i < req.size(); ++i) n.require(req[i], why[i]);
  for (Role r : opt) n.use(r);
  return n;
}

PrepSteps Filter::prep_steps() const {
  PrepSteps s = info_.steps;
  if (s.holes) {  // the first-hit holes of position and depth, for a filter that reads them
    const PassNeeds own = own_needs();
    const auto reads = [&](Role r) {
      return std::find(own.required.begin(), own.required.end(), r) != own.required.end() ||
             std::find(own.optional.begin(), own.optional.end(), r) != own.optional.end();
    };
    s.first_hit = reads(Role::Position) || reads(Role::Depth);
  }
  return s;
}

std::vector<Role> Filter::missing_passes(const Frame& frame) const {
  std::vector<Role> missing;
  for (Role r : needs().required)
    if (!frame.has(r)) missing.push_back(r);
  return missing;
}

// ---- Tiled runs ----

namespace {

constexpr int kUnknownReach = 1 << 20;
// What the noise estimate reads around its box (kernels/noise_scale.h: 12 pixels, and its
// tiles of 8 on the frame's grid, grown by 4), with room to spare.
constexpr int kNoiseEstimateReach = 24;

}  // namespace

int Filter::own_reach() const {
  const Roi probe{kUnknownReach, kUnknownReach, kUnknownReach + 1, kUnknownReach + 1};
  const Roi r = reads(probe, 2 * kUnknownReach + 1, 2 * kUnknownReach + 1);
  const int grow = std::max({probe.x0 - r.x0, probe.y0 - r.y0, r.x1 - probe.x1, r.y1 - probe.y1});
  return grow >= kUnknownReach ? -1 : grow;
}

std::string Filter::why_not_tileable() const {
  if (info_.temporal) return "it keeps history between frames";
  if (info_.deep_input || info_.lightfield_input) return "it reads per-sample data";
  if (params_.has("foveated") && params_.get_bool("foveated")) return "foveated=true centres on the whole frame";
  if (own_reach() < 0) return "its reach is not bounded";
  return "";
}

int Filter::band_margin() const {
  if (!(info_.steps.step_back && params_.get_bool("step_back") && step_back_applies())) return 0;
  return int(params_.get_int("step_back_radius")) + 1 + kNoiseEstimateReach;
}

int Filter::band_halo() const {
  if (!why_not_tileable().empty()) return -1;
  int prep = 1;  // the firefly clamp's keep mask reads the 8 neighbours
  if (prep_steps().first_hit) prep += kFirstHitRadius;
  if (info_.steps.outliers && params_.get_float("firefly_k") > 0) prep += int(params_.get_int("firefly_radius"));
  if (info_.steps.albedo_prefilter && params_.get_float("albedo_prefilter") > 0) prep += 16;
  return band_margin() + own_reach() + prep + kNoiseEstimateReach;
}

void Filter::begin_statistics() {
  measuring_ranges_.clear();
  ranges_.clear();
  measured_holes_ = 0;
  stats_pass_ = 0;
  drop_own_statistics();
  stats_state_ = StatsState::Measuring;
  // A band cannot see the frame's level: a first pass over every band measures it.
  exposure_measuring_ = exposure_applies() && exposure_pin_ == ExposurePin::None;
  exposure_level_ = ExposureLevel{};
}

void Filter::measure(const Frame& band, const Roi& rows, int nthreads) {
  if (!committed_) throw Error(Errc::Internal, "filter '" + info_.name + "': measure() before commit()");
  if (stats_state_ != StatsState::Measuring) throw Error(Errc::Internal, "filter '" + info_.name + "': measure() outside begin/end_statistics()");
  check_passes(needs(), band, "filter '" + info_.name + "'");
  band.check_sizes();
  notes_.clear();
  const Roi r = rows.clipped(band.width, band.height);
  if (r.empty()) return;
  if (exposure_measuring_) {
    exposure_level_.add(band.image(Role::Colour), r, nthreads);
    return;
  }
  prepare(band, params_, prep_steps(), reads(r, band.width, band.height), nthreads, prepared_, exposure_);
  if (stats_pass_ == 0) {  // the first pass: the holes and every pass's spread
    measured_holes_ += prepared_.holes;
    for (const Pass& p : prepared_.frame->passes) {
      if (p.image.channels() < 1) continue;
      auto it = std::find_if(measuring_ranges_.begin(), measuring_ranges_.end(), [&](const auto& e) { return e.first == p.name; });
      if (it == measuring_ranges_.end()) it = measuring_ranges_.insert(measuring_ranges_.end(), {p.name, WholeFrameRange{}});
      extend_frame_range(p.image, std::min(p.image.channels(), 3), r, it->second);
    }
  }
  measure_band(*prepared_.frame, prepared_.colour, r, nthreads);
  prepared_ = Prepared{};
}

void Filter::run_to_measure(const Frame& band, const Image& colour, const Roi& rows, int nthreads) {
  measuring_run_ = true;
  try {
    Image none;
    run(band, colour, rows, none, nthreads);
  } catch (...) {
    measuring_run_ = false;
    throw;
  }
  measuring_run_ = false;
}

bool Filter::end_statistics_pass() {
  if (stats_state_ != StatsState::Measuring) throw Error(Errc::Internal, "filter '" + info_.name + "': end_statistics_pass() without begin");
  if (exposure_measuring_) {  // the exposure's pass: the statistics' own passes follow at its scale
    exposure_measuring_ = false;
    exposure_ = mcr::exposure_scale(exposure_level_);
    exposure_level_seen_ = exposure_level_.level();
    exposure_pin_ = ExposurePin::Statistics;
    return true;
  }
  if (stats_pass_ == 0) {
    for (auto& [name, range] : measuring_ranges_) ranges_.emplace_back(name, std::make_shared<const WholeFrameRange>(range));
    measuring_ranges_.clear();
  }
  const bool more = statistics_pass_done();
  ++stats_pass_;
  if (more) return true;
  fix_statistics();
  stats_state_ = StatsState::Fixed;
  return false;
}

void Filter::attach_statistics(Frame& band) const {
  for (Pass& p : band.passes) {
    auto it = std::find_if(ranges_.begin(), ranges_.end(), [&](const auto& e) { return e.first == p.name; });
    p.image.whole_frame = it == ranges_.end() ? nullptr : it->second;
  }
}

void Filter::drop_statistics() {
  measuring_ranges_.clear();
  ranges_.clear();
  drop_own_statistics();
  stats_state_ = StatsState::None;
  stats_pass_ = 0;
  exposure_measuring_ = false;
  if (exposure_pin_ == ExposurePin::Statistics) exposure_pin_ = ExposurePin::None;
}

void Filter::reset() {
  if (exposure_pin_ == ExposurePin::History) exposure_pin_ = ExposurePin::None;
  reset_history();
}

void Filter::pin_exposure(double k, double prior) {
  exposure_ = k;
  exposure_prior_ = prior;
  exposure_pin_ = ExposurePin::Caller;
}

bool Filter::exposure_applies() const { return info_.steps.exposure && params_.get_enum("exposure") == "auto"; }

double Filter::exposure_for(const Image& colour, int nthreads) {
  if (!exposure_applies()) return exposure_ = 1.0;
  if (exposure_pin_ != ExposurePin::None) return exposure_;
  ExposureLevel level;
  level.add(colour, Roi::all(colour.width(), colour.height()), nthreads);
  exposure_ = mcr::exposure_scale(level);
  exposure_level_seen_ = level.level();
  if (info_.temporal) exposure_pin_ = ExposurePin::History;  // its history is at this scale
  return exposure_;
}

namespace {

// A region must lie inside the image, in the pixel indices of its data window: a region
// partly or wholly outside is a mistake the user should hear about, not a smaller region.
Roi checked_roi(const Roi& r, int w, int h) {
  const std::string text = "region " + std::to_string(r.x0) + "," + std::to_string(r.y0) + "," +
                           std::to_string(r.x1) + "," + std::to_string(r.y1);
  if (r.empty())
    throw Error(Errc::InvalidArgument, text + " is empty (X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1, end exclusive)");
  if (r.x0 < 0 || r.y0 < 0 || r.x1 > w || r.y1 > h)
    throw Error(Errc::InvalidArgument, text + " is outside the " + std::to_string(w) + "x" + std::to_string(h) +
                                           " image (x in [0, " + std::to_string(w) + "), y in [0, " +
                                           std::to_string(h) + "))");
  return r;
}

// Where the step back's noise came from, for its note ("" for the plain image estimate).
std::string noise_source(bool variance_pass, bool on_illumination, double k) {
  if (variance_pass) return " (noise from the variance pass)";
  if (!on_illumination && k == 1.0) return "";
  return std::string(" (noise estimate") + (on_illumination ? " on the illumination" : "") +
         (k != 1.0 ? " x" + rounded_text(k, 2) : "") + ")";
}

}  // namespace

Image Filter::execute(const Frame& frame, const ExecOptions& options) {
  if (!committed_) throw Error(Errc::Internal, "filter '" + info_.name + "': execute() before commit()");
  check_passes(needs(), frame, "filter '" + info_.name + "'");
  frame.check_sizes();
  notes_.clear();
  const int nthreads = options.nthreads;
  const int w = frame.width, h = frame.height;
  const Image& input = frame.image(Role::Colour);
  const Roi roi = options.roi == Roi{} ? Roi::all(w, h) : checked_roi(options.roi, w, h);
  if (roi.empty()) {  // a 0-pixel frame: the input as it is
    prepared_ = Prepared{};
    Image out = rgb_copy(input, nthreads);
    repaired_ = finish(prepared_, input, roi, nthreads, out);
    return out;
  }

  const double exposure = exposure_for(input, nthreads);
  prepare(frame, params_, prep_steps(), reads(roi, w, h), nthreads, prepared_, exposure);
  if (exposure != 1.0) {
    const char* whose = exposure_pin_ == ExposurePin::History ? ", the first frame's"
                        : exposure_pin_ == ExposurePin::Statistics ? ", the whole frame's" : "";
    note("exposure: filtered at " + rounded_text(exposure, 3) + "x the render's" +
         (exposure_pin_ == ExposurePin::Caller ? std::string(" (as set)")
                                               : " (mean luminance " + rounded_text(exposure_level_seen_, 3) + whose +
                                                     ", outside [" + rounded_text(kExposureLow, 2) + ", " +
                                                     rounded_text(kExposureHigh, 2) + "])") +
         ", scaled back");
  }
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
  if (info_.steps.step_back && params_.get_bool("step_back") && step_back_applies()) {
    const Pass* variance = prepared_.frame->find(Role::Variance);
    const double k = step_back_noise_for(params_, *prepared_.frame);
    const Image* modulation = step_back_modulation(params_, *prepared_.frame);
    const StepBackStats sb = step_back(prepared_.frame->image(Role::Colour), roi, int(params_.get_int("step_back_radius")),
                                       nthreads, out, variance ? &variance->image : nullptr, k,
                                       modulation, kRelMseEps * metric_scale() * metric_scale());
    note("step_back" + noise_source(variance != nullptr, modulation != nullptr, k) + ": mean weight of the filtered result " +
         rounded_text(sb.mean_weight, 2) + ", input kept (weight < 0.5) at " +
         rounded_text(100.0 * sb.input_share, 3) + "% of the pixels, " + std::to_string(sb.fireflies) + " fireflies removed");
  }
  // Back to the render's exposure; outside the roi finish() kept the input bit for bit.
  unscale_exposure(out, roi, exposure, nthreads);
  if (const Pass* alpha = frame.find(Role::Alpha))
    if (const std::size_t kept = keep_empty_pixels(alpha->image, input, roi, out))
      note(std::to_string(kept) + " pixels with nothing rendered (alpha 0, colour 0) kept at 0");
  prepared_.own = Frame{};  // the copied passes are not kept between frames
  prepared_.colour = Image{};
  return out;
}

}  // namespace mcr
