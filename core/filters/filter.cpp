#include "filters/filter.h"

#include <algorithm>
#include <cmath>

#include "prepare/albedo_prefilter.h"
#include "prepare/fireflies.h"
#include "prepare/pull_push.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

ParamTable with_common_params(ParamTable own) {
  own.push_back(ParamSpec::Bool("demodulate", false, "divide the colour by the albedo pass before filtering and multiply after"));
  own.push_back(ParamSpec::Float("albedo_floor", 0.01, 1e-6, 1.0, "albedo is raised to at least albedo_floor for demodulation (no upper clamp: colour is divided and multiplied by the same value, and Blender's albedo exceeds 1 on highlights)"));
  own.push_back(ParamSpec::Float("albedo_prefilter", 0.0, 0.0, 10.0,
                                 "smooth the albedo pass before it is used (demodulation and albedo weights): range sigma, "
                                 "in log albedo, of a first-order cross-bilateral fit on normal and position (1 px; NFOR's "
                                 "feature prefiltering): a 16-spp albedo carries coverage and glossy-bounce noise that "
                                 "remodulation puts back; 0 = off"));
  own.push_back(ParamSpec::Float("albedo_prefilter_position", 0.03, 1e-6, 1e6,
                                 "position sigma of albedo_prefilter, in scene units"));
  own.push_back(ParamSpec::Enum("holes", "auto", {"auto", "none", "sample_count", "alpha"},
                                "unsampled pixels to fill by pull-push first: auto = sample_count 0 when that pass exists"));
  own.push_back(ParamSpec::Float("firefly_k", 0.0, 0.0, 1e3,
                                 "firefly suppression before filtering (after demodulation, on the illumination): a pixel whose luminance "
                                 "exceeds mu + max(k sd, 0.01 |mu|) of its window's other pixels is scaled down to that "
                                 "limit (Guo & Pan 2012, 3.3, clamping instead of replacing); 0 = off"));
  own.push_back(ParamSpec::Int("firefly_radius", 3, 1, 8, "half width of the firefly statistics window"));
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
  // Albedo prefilter: every later use of the albedo pass sees the smoothed one.
  if (params_.get_float("albedo_prefilter") > 0) {
    if (const Pass* a = src->find(Role::Albedo)) {
      AlbedoPrefilter ap;
      ap.range_sigma = params_.get_float("albedo_prefilter");
      ap.position_sigma = params_.get_float("albedo_prefilter_position");
      ap.floor = params_.get_float("albedo_floor");
      Image smooth = prefilter_albedo(*src, *a, ap, options.nthreads);
      const std::size_t index = std::size_t(a - src->passes.data());
      if (src != &filled) {  // the hole-filled frame is already a copy of our own
        filled = *src;
        src = &filled;
      }
      filled.passes[index].image = std::move(smooth);
    } else {
      note("albedo_prefilter skipped: no albedo pass in '" + frame.path + "'");
    }
  }
  const Image& input = src->image(Role::Colour);
  const int nthreads = options.nthreads;
  const int w = frame.width, h = frame.height;
  // The RGB working copy of the colour, row-parallel (it becomes the output for filters
  // that run in place).
  if (input.channels() < 3) (void)input.channel_range(0, 3);  // throws: no RGB
  Image colour(input.width(), input.height(), 3);
  {
    const int ich = input.channels();
    const std::size_t iw = std::size_t(input.width());
    parallel_rows(0, input.height(), nthreads, [&](int y) {
      const float* s = input.data() + std::size_t(y) * iw * std::size_t(ich);
      float* d = colour.data() + std::size_t(y) * iw * 3;
      if (ich == 3) {
        std::copy(s, s + iw * 3, d);
        return;
      }
      for (std::size_t x = 0; x < iw; ++x)
        for (int c = 0; c < 3; ++c) d[x * 3 + std::size_t(c)] = s[x * std::size_t(ich) + std::size_t(c)];
    });
  }

  Roi roi = options.roi.empty() ? Roi::all(frame.width, frame.height) : options.roi.clipped(frame.width, frame.height);
  if (roi.empty()) return colour;  // nothing to filter: the input as it is

  // Albedo demodulation: filter the illumination, not the texture.
  Image albedo;
  if (params_.get_bool("demodulate")) {
    const Pass* a = src->find(Role::Albedo);
    if (!a) throw Error(Errc::MissingPass, "filter '" + info_.name + "': demodulate=true needs the albedo pass, absent in '" + frame.path + "'");
    const float lo = float(params_.get_float("albedo_floor"));
    albedo = Image(frame.width, frame.height, 3);
    const int ach = a->image.channels();
    parallel_rows(0, h, nthreads, [&](int y) {
      const std::size_t b = std::size_t(y) * std::size_t(w), e = b + std::size_t(w);
      for (std::size_t i = b; i < e; ++i)
        for (int c = 0; c < 3; ++c) {
          const float v = a->image.data()[i * std::size_t(ach) + std::size_t(std::min(c, ach - 1))];
          const float al = demodulation_albedo(v, lo);
          albedo.data()[i * 3 + std::size_t(c)] = al;
          colour.data()[i * 3 + std::size_t(c)] /= al;
        }
    });
  }

  // Firefly suppression, after demodulation: on the illumination a texture edge is not an
  // outlier, and a firefly stands out of its window more clearly (glossy: 0.0099 -> 0.0090).
  if (params_.get_float("firefly_k") > 0) {
    std::size_t clamped = 0;
    colour = suppress_fireflies(colour, int(params_.get_int("firefly_radius")), params_.get_float("firefly_k"),
                                options.nthreads, &clamped);
    note("firefly suppression clamped " + std::to_string(clamped) + " pixels");
  }

  Image out;
  if (run_in_place()) {
    run(*src, colour, roi, colour, nthreads);
    out = std::move(colour);
  } else {
    out = colour;
    run(*src, colour, roi, out, nthreads);
  }

  // Remodulation and the safety net (nothing non-finite ever leaves a filter), one
  // row-parallel pass; the per-row counts are added in row order.
  std::vector<std::size_t> row_repaired(std::size_t(std::max(h, 0)), 0);
  const std::size_t rw = std::size_t(w) * 3;
  if (out.storage().size() != rw * std::size_t(h))
    throw Error(Errc::Internal, "filter '" + info_.name + "' returned an output of another size");
  parallel_rows(0, h, nthreads, [&](int y) {
    float* o = out.data() + std::size_t(y) * rw;
    if (!albedo.empty()) {
      const float* al = albedo.data() + std::size_t(y) * rw;
      for (std::size_t i = 0; i < rw; ++i) o[i] *= al[i];
    }
    // Branch-free scan first: almost every row is finite.
    bool all = true;
    for (std::size_t i = 0; i < rw; ++i) all &= std::fabs(o[i]) <= 3.402823466e38f;
    if (all) return;
    std::size_t n = 0;
    for (std::size_t i = 0; i < rw; ++i)
      if (!std::isfinite(o[i])) { o[i] = 0.0f; ++n; }
    row_repaired[std::size_t(y)] = n;
  });
  repaired_ = 0;
  for (std::size_t v : row_repaired) repaired_ += v;
  if (repaired_) note(std::to_string(repaired_) + " non-finite output values replaced by 0");
  return out;
}

}  // namespace mcr
