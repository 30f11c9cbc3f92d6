#include "prepare/preparation.h"

#include <algorithm>
#include <cmath>

#include "kernels/noise_scale.h"
#include "prepare/albedo_prefilter.h"
#include "prepare/demodulation.h"
#include "prepare/exposure.h"
#include "prepare/first_hit.h"
#include "prepare/outliers.h"
#include "prepare/pull_push.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

ParamTable with_preparation_params(ParamTable own, const PrepSteps& steps) {
  if (steps.demodulate) {
    own.push_back(ParamSpec::Bool("demodulate", false, "divide the colour by the albedo pass before filtering and multiply after"));
    own.push_back(ParamSpec::Float("albedo_floor", kDefaultAlbedoFloor, 1e-6, 1.0,
                                   "albedo is raised to at least albedo_floor for demodulation and capped at 1 (an albedo above 1 "
                                   "holds light: Blender's follows a mirror's bounce to a lamp)"));
  }
  if (steps.albedo_prefilter) {
    own.push_back(ParamSpec::Float("albedo_prefilter", 0.0, 0.0, 10.0,
                                   "smooth the albedo pass before it is used (demodulation and albedo weights): range sigma, "
                                   "in log albedo, of a first-order cross-bilateral fit on normal and position (1 px; NFOR's "
                                   "feature prefiltering): a 16-spp albedo carries coverage and glossy-bounce noise that "
                                   "remodulation puts back; 0 = off"));
    own.push_back(ParamSpec::Float("albedo_prefilter_position", 0.03, 1e-6, 1e6, "position sigma of albedo_prefilter, in scene units"));
  }
  if (steps.holes) {
    own.push_back(ParamSpec::Enum("holes", "auto", {"auto", "none", "sample_count", "alpha"},
                                  "unsampled pixels to fill by pull-push first: auto = sample_count 0 when that pass exists"));
  }
  if (steps.outliers) {
    own.push_back(ParamSpec::Float("firefly_k", kDefaultFireflyK, 0.0, 1e3,
                                   "firefly suppression before filtering (after demodulation, on the illumination): a pixel whose "
                                   "luminance exceeds mu + max(k sd, 0.01 |mu|) of its window's other pixels is scaled down to "
                                   "that limit (Guo & Pan 2012, 3.3, clamping instead of replacing); 0 = off. 8 (default): a "
                                   "pixel at 1000x its neighbours is cut to a few times them, while a render without fireflies "
                                   "loses under 0.5% of its mean luminance (16- and 64-spp samples)"));
    own.push_back(ParamSpec::Int("firefly_radius", 3, 1, 8, "half width of the firefly statistics window"));
    own.push_back(ParamSpec::Float("clamp", 0.0, 0.0, 1e30,
                                   "clamp every colour channel to [-clamp, clamp] before filtering (after demodulation and "
                                   "firefly suppression); 0 = off"));
  }
  if (steps.exposure) own.push_back(exposure_param());
  if (steps.step_back) {
    own.push_back(ParamSpec::Bool("step_back", true,
                                  "after filtering, blend the result toward the input wherever it is not estimated to beat "
                                  "it (noise estimated from the image; Stein's unbiased risk estimate per window): a clean "
                                  "render stays nearly as it was, a filter's bias (light spread from a highlight, a shadow "
                                  "averaged away) is undone; fireflies still go"));
    own.push_back(ParamSpec::Int("step_back_radius", 4, 1, 16,
                                 "half width of the window over which step_back weighs the result against the input"));
    own.push_back(ParamSpec::Float("step_back_noise", 1.0, 0.0, 2.0,
                                   "without a variance pass, step_back takes the image's noise estimate times this: "
                                   "the estimate is right at a window's median but spreads (about 0.5-1.5x the truth), and a "
                                   "window whose estimate runs low steps back from a sound result; up to 2 the blend "
                                   "is still no worse than the input where the estimate is right (Stein's risk); 0 = by "
                                   "passes: 2 with an albedo pass, 1 without"));
    own.push_back(ParamSpec::Enum("step_back_estimate", "colour", {"colour", "illumination"},
                                  "without a variance pass, where step_back estimates the noise: colour = the image "
                                  "as it is; illumination = the colour divided by the albedo pass (then multiplied "
                                  "back), so the texture the albedo explains is not read as noise (colour when the "
                                  "render has no albedo pass)"));
  }
  own.push_back(components_param());
  return own;
}

void edge_keeping_step_back(ParamTable& t) {
  for (ParamSpec& s : t)
    if (s.name == "step_back_noise") {
      s.default_value = 0.0;
      s.help += " (default 0 for this filter: its weights keep edges, and texture's where an albedo pass says "
                "where it is)";
    } else if (s.name == "step_back_estimate") {
      s.default_value = std::string("illumination");
      s.help += " (default illumination for this filter, which keeps the texture an albedo pass shows)";
    }
}

double step_back_noise_for(const ParamSet& params, const Frame& frame) {
  const double k = params.get_float("step_back_noise");
  if (k > 0) return k;
  return frame.find(Role::Albedo) ? 2.0 : 1.0;
}

const Image* step_back_modulation(const ParamSet& params, const Frame& frame) {
  if (params.get_enum("step_back_estimate") != "illumination") return nullptr;
  const Pass* a = frame.find(Role::Albedo);
  return a ? &a->image : nullptr;
}

ParamSpec components_param() {
  return ParamSpec::Enum("components", "beauty", {"beauty", "light_passes"},
                         "beauty = filter the Combined pass; light_passes = filter Blender's diffuse light (direct + "
                         "indirect) and glossy and transmission light (direct and indirect apart, added after "
                         "filtering), already divided by their colour pass, one by one, multiply each by its colour "
                         "pass, add emission and environment as they are");
}

ParamSpec alpha_param() {
  return ParamSpec::Enum("alpha", "filter", {"filter", "keep"},
                         "filter = the render's alpha (its coverage: a transparent film's edges and veils, a shadow "
                         "catcher's shadows) filtered as a grey colour by a second run of the same filter (auto: pwaf), "
                         "without demodulation, clamped to [0, 1] (or the input's wider range); a constant alpha (an opaque render) is kept; keep = "
                         "the input's alpha as it is");
}

namespace {

Role hole_role(const std::string& mode) { return mode == "alpha" ? Role::Alpha : Role::SampleCount; }

// Weight 0 for unsampled pixels, 1 otherwise; empty when nothing is missing.
std::vector<float> hole_weights(const Frame& frame, const std::string& mode) {
  if (mode == "none") return {};
  const Role role = hole_role(mode);
  const Pass* p = frame.find(role);
  if (!p) {
    if (mode == "auto") return {};
    throw Error(Errc::MissingPass, "holes=" + mode + " needs the " + role_name(role) + " pass, absent in '" + frame.path + "'");
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

// The frame run() reads, copied on the first change.
Frame& own_frame(const Frame& frame, Prepared& out) {
  if (out.frame != &out.own) {
    out.own = frame;
    out.frame = &out.own;
  }
  return out.own;
}

}  // namespace

void preparation_needs(const ParamSet& params, const PrepSteps& steps, std::vector<Role>& required,
                       std::vector<std::string>& why, std::vector<Role>& optional) {
  // A filter whose default is demodulate=true (guided) uses the albedo when present;
  // only a demodulate=true the user gave makes it required.
  if (steps.demodulate && params.get_bool("demodulate")) {
    if (params.was_set("demodulate")) {
      required.push_back(Role::Albedo);
      why.push_back("demodulate=true");
    } else {
      optional.push_back(Role::Albedo);
    }
  }
  if (steps.albedo_prefilter && params.get_float("albedo_prefilter") > 0) {
    for (Role r : {Role::Albedo, Role::Normal, Role::Position}) optional.push_back(r);
  }
  if (steps.holes) {
    const std::string& mode = params.get_enum("holes");
    if (mode == "auto") {
      optional.push_back(Role::SampleCount);
    } else if (mode != "none") {
      required.push_back(hole_role(mode));
      why.push_back("holes=" + mode);
    }
  }
}

std::vector<std::string> preparation_unused(const ParamSet& params, const PrepSteps& steps) {
  std::vector<std::string> notes;
  if (steps.outliers && !(params.get_float("firefly_k") > 0))
    report_unused(params, "firefly_radius", "with firefly_k=0", notes);
  if (steps.albedo_prefilter && !(params.get_float("albedo_prefilter") > 0))
    report_unused(params, "albedo_prefilter_position", "with albedo_prefilter=0", notes);
  if (steps.demodulate && !params.get_bool("demodulate")) report_unused(params, "albedo_floor", "with demodulate=false", notes);
  if (steps.step_back && !params.get_bool("step_back"))
    for (const char* name : {"step_back_radius", "step_back_noise"}) report_unused(params, name, "with step_back=false", notes);
  return notes;
}

Image rgb_copy(const Image& input, int nthreads) {
  if (input.channels() < 3) (void)input.channel_range(0, 3);  // throws: no RGB
  Image colour(input.width(), input.height(), 3);
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
  return colour;
}

void prepare(const Frame& frame, const ParamSet& params, const PrepSteps& steps, const Roi& work_in, int nthreads,
             Prepared& out, double exposure) {
  out.frame = &frame;
  out.notes.clear();
  out.divisor = Image();
  out.holes = 0;
  const int w = frame.width, h = frame.height;
  const Roi work = work_in.clipped(w, h);
  // Each step reads around the region of the next: fireflies read their window.
  const bool fireflies = steps.outliers && params.get_float("firefly_k") > 0;
  const Roi demod_region = fireflies ? work.grown(int(params.get_int("firefly_radius")), w, h) : work;

  // Exposure first: every later step, and run(), sees the render at the scale its constants assume.
  if (exposure != 1.0) scale_exposure(own_frame(frame, out), exposure, nthreads);

  // Sparse renders: fill every pass at the unsampled pixels first (thesis 5.1). The
  // pull-push pyramid spans the frame, so this step fills the whole frame.
  if (steps.holes) {
    const std::vector<float> holes = hole_weights(frame, params.get_enum("holes"));
    if (!holes.empty()) {
      Frame& f = own_frame(frame, out);
      for (Pass& p : f.passes)
        if (p.role != Role::SampleCount && p.role != Role::Alpha) pull_push_fill(p.image, holes, nthreads);
      out.holes = std::size_t(std::count(holes.begin(), holes.end(), 0.0f));
      out.notes.push_back("filled " + std::to_string(out.holes) + " unsampled pixels by pull-push");
    }
  }
  if (steps.holes && steps.first_hit) {
    // The fill reads kFirstHitRadius pixels around the region the filter reads (Filter::band_halo).
    const FirstHitMap map = first_hit_map(*out.frame, work, nthreads);
    if (map.holes) {
      const std::size_t filled = fill_first_hit_holes(own_frame(frame, out), map, nthreads);
      out.notes.push_back("position and depth: " + std::to_string(filled) +
                          " pixels whose first sample met no surface though others did (a volume, an edge) take "
                          "their neighbours'");
    }
  }
  // Albedo prefilter: every later use of the albedo pass sees the smoothed one.
  if (steps.albedo_prefilter && params.get_float("albedo_prefilter") > 0) {
    if (const Pass* a = out.frame->find(Role::Albedo)) {
      AlbedoPrefilter ap;
      ap.range_sigma = params.get_float("albedo_prefilter");
      ap.position_sigma = params.get_float("albedo_prefilter_position");
      // Albedo weights read it over the filter's whole reach: smooth the work region.
      Image smooth = prefilter_albedo(*out.frame, *a, ap, work, nthreads);
      smooth.whole_frame = a->image.whole_frame;  // a tiled run measured the smoothed one
      const std::size_t index = std::size_t(a - out.frame->passes.data());
      own_frame(frame, out).passes[index].image = std::move(smooth);
    } else {
      out.notes.push_back("albedo_prefilter skipped: no albedo pass in '" + frame.path + "'");
    }
  }
  out.colour = rgb_copy(out.frame->image(Role::Colour), nthreads);
  if (work.empty()) return;
  // With a variance pass, a pixel whose own samples agree as well as its neighbours' is detail
  // however bright (kernels/noise_scale.h, NoiseScales::detail): never clamped as a firefly.
  std::vector<std::uint8_t> detail;
  if (fireflies) {
    const Pass* v = out.frame->find(Role::Variance);
    detail = detail_mask(out.colour, v ? &v->image : nullptr, work, nthreads);
  }

  // Albedo demodulation: filter the illumination, not the texture.
  if (steps.demodulate && params.get_bool("demodulate")) {
    const Pass* a = out.frame->find(Role::Albedo);
    if (a) {
      out.divisor = Image(w, h, 3);
      demodulate(a->image, float(params.get_float("albedo_floor")), demod_region, nthreads, out.divisor, out.colour);
    } else if (params.was_set("demodulate")) {
      throw Error(Errc::MissingPass, "demodulate=true needs the albedo pass, absent in '" + frame.path + "'");
    } else {
      out.notes.push_back("demodulation skipped: no albedo pass in '" + frame.path + "' (demodulate is on by default)");
    }
  }
  // Firefly suppression, after demodulation: on the illumination a texture edge is not an
  // outlier, and a firefly stands out of its window more clearly (glossy: 0.0099 -> 0.0090).
  if (fireflies) {
    const std::size_t clamped = clamp_fireflies(out.colour, int(params.get_int("firefly_radius")),
                                                params.get_float("firefly_k"), work, nthreads,
                                                detail.empty() ? nullptr : &detail);
    if (clamped) out.notes.push_back("firefly suppression clamped " + std::to_string(clamped) + " pixels");
  }
  // clamp is in the render's units.
  if (steps.outliers) clamp_channels(out.colour, params.get_float("clamp") * exposure, work, nthreads);
}

std::size_t finish(const Prepared& prepared, const Image& input, const Roi& roi, int nthreads, Image& out) {
  const int w = out.width(), h = out.height();
  const std::size_t rw = std::size_t(w) * 3;
  const int ich = input.channels();
  std::vector<std::size_t> row_repaired(std::size_t(std::max(h, 0)), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    float* o = out.data() + std::size_t(y) * rw;
    const bool inside_rows = y >= roi.y0 && y < roi.y1;
    // Outside the roi: the input colour, bit for bit.
    const float* in = input.pixel(0, y);
    auto keep_input = [&](int x0, int x1) {
      for (int x = x0; x < x1; ++x)
        for (int c = 0; c < 3; ++c)
          o[std::size_t(x) * 3 + std::size_t(c)] = in[std::size_t(x) * std::size_t(ich) + std::size_t(c)];
    };
    if (inside_rows) {
      keep_input(0, roi.x0);
      keep_input(roi.x1, w);
    } else {
      keep_input(0, w);
    }
    if (inside_rows && !prepared.divisor.empty()) {
      const float* al = prepared.divisor.pixel(roi.x0, y);
      float* oo = o + std::size_t(roi.x0) * 3;
      for (std::size_t i = 0, n = std::size_t(roi.width()) * 3; i < n; ++i) oo[i] *= al[i];
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
  std::size_t repaired = 0;
  for (std::size_t v : row_repaired) repaired += v;
  return repaired;
}

}  // namespace mcr
