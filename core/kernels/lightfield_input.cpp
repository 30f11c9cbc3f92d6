#include "kernels/lightfield_input.h"

#include <algorithm>

#include "kernels/lightfield_variance.h"
#include "kernels/residual_shrink.h"
#include "kernels/risk_blend.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr::lf {

ParamSpec max_width_param() {
  return ParamSpec::Int("max_width", 32, 1, 128,
                        "widest filter support, pixels (a diameter; the paper clamps to 32): radius per axis "
                        "min(ceil(2 sigma_x |e_i|), max_width/2)");
}
ParamSpec reject_param() {
  return ParamSpec::Bool("reject", true,
                         "soft shadows and gi with geometry: leave out neighbours across a normal or depth edge "
                         "(normal_degrees; |P_Q - P_P| > 2 |d| + one pixel's world size)");
}
ParamSpec normal_degrees_param() {
  return ParamSpec::Float("normal_degrees", 20, 0, 180,
                          "rejection: a neighbour whose normal differs by more than this many degrees is left out");
}
ParamSpec smooth_radius_param() {
  return ParamSpec::Int("smooth_radius", 2, 0, 16,
                        "soft shadows: a pixel with both slope bounds 0 takes the widest bounds of the pixels "
                        "within this many pixels (2 = 5x5 window, the paper's); 0: off");
}
ParamSpec bounds_radius_param() {
  return ParamSpec::Int("bounds_radius", -1, -1, 16,
                        "every pixel's slope bounds widened to the widest of the pixels within this many pixels "
                        "that have bounds (a pixel's few samples see part of the occluders its filter reaches); 0: "
                        "its own; -1: smooth_radius for soft shadows, 0 for dof and gi (chosen on the generator's "
                        "scenes: soft_shadows 16 spp relMSE 0.00099 -> 0.00055, dof and gi worse when widened)");
}
ParamSpec fallback_param() {
  return ParamSpec::Enum("fallback", "aaf", {"aaf", "own"},
                         "pixels whose bounds have opposite signs (or one is 0): aaf = the axis-aligned rule for "
                         "that pixel (eta 0, sigma_x = sigma_y min|s| / (2 mu)); own = its own sample mean");
}
ParamSpec mu_param(bool fallback_only) {
  return ParamSpec::Float("mu", 1, 0.05, 20,
                          std::string("axis-aligned filter width factor (Mehta 2012): sigma_x = sigma_y min|s| / "
                                      "(2 mu); above 1 blurs less") +
                              (fallback_only ? " (the fallback pixels only)" : ""));
}
ParamSpec bins_param() {
  return ParamSpec::Int("bins", 16, 2, 128,
                        "bins over the filter centre b (step 1a) and over y2 (steps 1b, 2a), read with linear "
                        "interpolation between bin centres; the paper uses 16 (about 4 l)");
}

ParamSpec residual_k_param() {
  return ParamSpec::Float("residual_k", -1, -1, 1e3,
                          "the result's residual against each pixel's own samples (its flat colour), averaged over "
                          "each pixel's window, added back with the James-Stein weight 1 - residual_k x its noise / its "
                          "square (kernels/residual_shrink.h): where a wide window misplaces a shadow edge or a "
                          "defocused one, the pixels' own samples pull it back, noise does not; 0 = off; -1 = 3 for "
                          "dof, 0 for gi, 3 for soft shadows too but 1 where the step back follows (chosen on the "
                          "generator's scenes: soft shadows at 16 spp 0.00055 -> 0.00038 against the input's 0.00051 "
                          "with 3; with the step back after it, 1: 0.000277 -> 0.000259 at 16 spp, 0.0000562 -> "
                          "0.0000489 at 64; on gi, whose own samples are one-bounce paths, it cost 5-7% at 1-4 spp)");
}
ParamSpec step_back_param() {
  return ParamSpec::Enum("step_back", "auto", {"auto", "strata", "samples", "off"},
                         "after the filter, blend toward each pixel's own estimate where the filter is not estimated "
                         "to beat it (Stein's unbiased risk over a window, kernels/risk_blend.h), with the variance of"
                         " that estimate from the pixel's samples: strata = from two chequerboard halves of its "
                         "strata, samples = their spread as if independent; off = keep the filter's result; auto = "
                         "strata for soft shadows (on the generator's scene 1.5-2.1x the true variance at 4-64 spp: it"
                         " errs high, the safe side), off for depth of field and gi (the dof generator shifts all of a"
                         " pixel's strata by one jitter, so its halves agree too well: 0.2x the truth at 16 spp, 0.08x"
                         " at 64; gi 0.74x at 4 spp; a variance that errs low brings the noise back); needs 2 samples "
                         "a pixel");
}
ParamSpec lens_light_param() {
  return ParamSpec::Enum("lens_light", "pixel", {"pixel", "sample"},
                         "soft shadows through a lens (a soft_shadows+dof light field): the light each sample takes "
                         "into the lens stage: pixel = its pixel's filtered light (the paper's appendix: F(x, u, y) ~ "
                         "F(x, y)); sample = that plus the sample's own departure from its pixel's mean light (a pixel"
                         " whose lens points meet two surfaces, a silhouette, keeps each one's light; the departures "
                         "cancel where the texture is the same). With the closing step back the two are within 6% "
                         "(pixel ahead on 7 of 9 renders)");
}
ParamSpec step_back_radius_param() {
  return ParamSpec::Int("step_back_radius", 3, 1, 16,
                        "half width of the step back's window (step_back; 3 chosen on the generator's soft "
                        "shadows at 4-64 spp, 128 and 64 px wide: within 3% of the best of 1-4 at every spp)");
}

ParamSpec residual_radius_param() {
  return ParamSpec::Int("residual_radius", 0, 0, 4,
                        "half width of the residual's window (residual_k); 0 = by samples: 2 for up to 4 samples a "
                        "pixel, 1 from 9 (more own samples are less noisy, and a narrower window follows a sharp "
                        "penumbra: chosen on the generator's soft shadows and dof, soft shadows at 64 spp 0.00021 "
                        "-> 0.00011)");
}

Options::StepBack step_back_for(const Options& o, LightFieldEffect effect) {
  if (o.step_back != Options::StepBack::ByEffect) return o.step_back;
  return effect == LightFieldEffect::SoftShadows ? Options::StepBack::Strata : Options::StepBack::Off;
}

double residual_k_for(const Options& o, LightFieldEffect effect, int spp) {
  if (o.residual_k >= 0) return o.residual_k;
  if (effect == LightFieldEffect::Gi) return 0.0;
  return step_back_for(o, effect) != Options::StepBack::Off && spp > 1 ? 1.0 : 3.0;
}

int residual_radius_for(const Options& o, int l) {
  if (o.residual_radius > 0) return o.residual_radius;
  return l <= 2 ? 2 : 1;
}

Options options_from(const ParamSet& params) {
  Options o;
  if (params.has("max_width")) o.max_width = int(params.get_int("max_width"));
  if (params.has("reject")) o.reject = params.get_bool("reject");
  if (params.has("normal_degrees")) o.normal_degrees = float(params.get_float("normal_degrees"));
  if (params.has("smooth_radius")) o.smooth_radius = int(params.get_int("smooth_radius"));
  if (params.has("bounds_radius")) o.bounds_radius = int(params.get_int("bounds_radius"));
  if (params.has("fallback")) o.fallback_aaf = params.get_enum("fallback") == "aaf";
  if (params.has("mu")) o.mu = float(params.get_float("mu"));
  if (params.has("residual_k")) o.residual_k = params.get_float("residual_k");
  if (params.has("residual_radius")) o.residual_radius = int(params.get_int("residual_radius"));
  if (params.has("step_back")) {
    const std::string sb = params.get_enum("step_back");
    using S = Options::StepBack;
    o.step_back = sb == "strata" ? S::Strata : sb == "samples" ? S::Samples : sb == "off" ? S::Off : S::ByEffect;
  }
  if (params.has("step_back_radius")) o.step_back_radius = int(params.get_int("step_back_radius"));
  if (params.has("bins")) o.bins = int(params.get_int("bins"));
  if (params.has("lens_light")) o.combined_per_pixel = params.get_enum("lens_light") != "sample";
  return o;
}

std::shared_ptr<const LightField> decoded_lightfield(const Frame& frame, const std::string& filter) {
  if (!frame.deep)
    throw Error(Errc::MissingPass, "filter '" + filter +
                                       "' needs a light-field deep EXR (README: the light-field convention); '" +
                                       frame.path + "' is a flat image");
  if (!is_lightfield(*frame.deep))
    throw Error(Errc::MissingPass, "filter '" + filter +
                                       "' needs a light-field deep EXR (README: the light-field convention); '" +
                                       frame.path + "' is a deep EXR without the mcrecon:lightfield attribute");
  std::shared_ptr<const LightField> decoded =
      frame.lightfield ? frame.lightfield : std::make_shared<const LightField>(decode_lightfield(*frame.deep, frame.path));
  if (decoded->width != frame.width || decoded->height != frame.height)
    throw Error(Errc::SizeMismatch, "'" + frame.path + "': the light field is " + std::to_string(decoded->width) +
                                        "x" + std::to_string(decoded->height) + ", the frame " +
                                        std::to_string(frame.width) + "x" + std::to_string(frame.height));
  return decoded;
}

namespace {

std::shared_ptr<const LightField> demodulated(std::shared_ptr<const LightField> decoded) {
  if (!decoded->has_modulation()) return decoded;
  auto out = std::make_shared<LightField>(*decoded);
  LightField& lf = *out;
  {
    const std::size_t spp = std::size_t(lf.spp());
    std::vector<float>* v[3] = {&lf.r, &lf.g, &lf.b};
    const std::vector<float>* m[3] = {&lf.mod_r, &lf.mod_g, &lf.mod_b};
    for (std::size_t p = 0; p < lf.pixels(); ++p)
      for (int c = 0; c < 3; ++c) {
        const float mod = (*m[c])[p];
        for (std::size_t k = p * spp; k < (p + 1) * spp; ++k) (*v[c])[k] = mod > 0 ? (*v[c])[k] / mod : 0.0f;
      }
  }
  return out;
}

}  // namespace

std::shared_ptr<const LightField> lightfield_input(const Frame& frame, const std::string& filter) {
  return demodulated(decoded_lightfield(frame, filter));
}

void remodulate(const LightField& lf, const Roi& roi, Image& out) {
  if (!lf.has_modulation()) return;
  for (int y = roi.y0; y < roi.y1; ++y)
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      float* o = out.pixel(x, y);
      o[0] *= lf.mod_r[p], o[1] *= lf.mod_g[p], o[2] *= lf.mod_b[p];
    }
}

namespace {

// The step back (sb, unless Off or one sample a pixel): out blended toward `own` where the filter
// is not estimated to beat it, with the variance of lf's samples; a note "<who>: step back ...".
void step_back(const LightField& lf, const Image& own, const std::string& who, const std::string& what,
               Options::StepBack sb, const Options& o, const Roi& roi, int nthreads, Image& out,
               std::vector<std::string>& notes) {
  if (sb == Options::StepBack::Off || lf.spp() < 2) return;
  const bool strata = sb == Options::StepBack::Strata;
  const Image var = estimate_variance(lf, strata ? VarianceFrom::Strata : VarianceFrom::Samples, roi, nthreads);
  const double a = blend_by_risk(own, var, roi, o.step_back_radius, nthreads, out);
  notes.push_back(who + ": step back toward each pixel's own samples" + what + " (" + (strata ? "strata" : "samples") +
                  " variance): mean weight of the filter's result " + rounded_text(a, 3));
}

// One effect's filtering of `decoded` (samples as the file holds them, or one stage of a combined
// light field) into out inside roi: demodulate, core, multiply back, residual against `own` (the
// pixels' own estimates), step back toward them. Returns the notes, each starting with `who`.
std::vector<std::string> run_stage(const std::shared_ptr<const LightField>& decoded, const Image& own,
                                   const std::string& who, const Options& o, const Roi& roi, int nthreads, Image& out,
                                   Core core, bool sheared) {
  const std::shared_ptr<const LightField> input = demodulated(decoded);
  const LightField& lf = *input;
  Counts c;
  core(lf, o, roi, nthreads, out, &c);
  remodulate(lf, roi, out);
  std::vector<std::string> notes = {counts_note(who, c, sheared)};
  if (const double k = residual_k_for(o, lf.effect, lf.spp()); k > 0) {
    ResidualSettings rs;
    rs.k = k;
    rs.radius = residual_radius_for(o, lf.l);
    std::vector<float> scratch;
    const std::size_t taken =
        add_back_residual(rs, own, nullptr, {out.data(), std::size_t(out.channels()), 1}, roi, scratch, nthreads);
    notes.push_back(who + ": " + std::to_string(taken) + " pixels took back over half of what the filter missed "
                    "against their own samples (residual_k)");
  }
  step_back(*decoded, own, who, "", step_back_for(o, lf.effect), o, roi, nthreads, out, notes);
  return notes;
}

// Every pixel's own estimate (own_mean, the light field's own weights), an RGB image.
Image own_means(const LightField& lf, int nthreads) {
  Image img(lf.width, lf.height, 3);
  const WeightY wy(lf);
  parallel_rows(0, lf.height, nthreads, [&](int y) {
    for (int x = 0; x < lf.width; ++x) own_mean(lf, wy, std::size_t(y) * std::size_t(lf.width) + std::size_t(x), img.pixel(x, y));
  });
  return img;
}

constexpr float kTextureFloor = 1e-4f;  // below it a sample's texture says nothing of its light

// Soft shadows and depth of field together, the appendix of Yan et al. 2015. Stage 1, the light:
// every sample's value over its texture, F, filtered as soft shadows over the region stage 2 reads
// (E, per pixel). Stage 2, the lens: every sample's texture times a light, filtered as depth of
// field. The appendix's light is E (F(x, u, y) ~ F(x, y): lens_light=pixel, the default); with
// lens_light=sample it is E + F - mean(F), the pixel's mean weighted as the lens stage weighs its
// samples: where the texture is the same over a pixel the departures cancel in its estimate,
// where its lens points meet two surfaces (a silhouette) each keeps its own light. Without the
// closing step back the appendix's rule was twice the input's relMSE at 64 spp (rings around the
// sphere of a plain-ground version of the scene); with it the two are within 6%. A sample whose
// texture is under kTextureFloor (black) takes its pixel's mean light of the other samples in that
// channel (0 where none has any).
std::vector<std::string> run_combined(const std::shared_ptr<const LightField>& decoded, const Image& flat,
                                      const std::string& filter, const Options& o, const Roi& roi, int nthreads,
                                      Image& out, Core core, bool sheared) {
  const LightField& all = *decoded;
  const LightField& lens = *all.lens;
  const std::size_t spp = std::size_t(all.spp());
  auto light = std::make_shared<LightField>(all);
  light->lens = nullptr;
  {
    std::vector<float>* dst[3] = {&light->r, &light->g, &light->b};
    const std::vector<float>* tex[3] = {&lens.r, &lens.g, &lens.b};
    parallel_rows(0, all.height, nthreads, [&](int y) {
      for (int x = 0; x < all.width; ++x) {
        const std::size_t p = std::size_t(y) * std::size_t(all.width) + std::size_t(x);
        for (int c = 0; c < 3; ++c) {
          std::vector<float>& v = *dst[c];
          const std::vector<float>& t = *tex[c];
          double sum = 0;
          std::size_t n = 0;
          for (std::size_t k = p * spp; k < (p + 1) * spp; ++k)
            if (t[k] >= kTextureFloor) v[k] /= t[k], sum += v[k], ++n;
          const float mean = n ? float(sum / double(n)) : 0.0f;
          for (std::size_t k = p * spp; k < (p + 1) * spp; ++k)
            if (!(t[k] >= kTextureFloor)) v[k] = mean;
        }
      }
    });
  }
  // Stage 2 reads its neighbours up to max_width / 2 along each axis, aaf twice over.
  const int reach = 2 * (std::max(0, o.max_width / 2) + 2);
  const Roi wide = roi.grown(reach, all.width, all.height);
  Image lit = own_means(*light, nthreads);
  std::vector<std::string> notes =
      run_stage(light, Image(lit), filter + " (light)", o, wide, nthreads, lit, core, sheared);
  auto on_lens = std::make_shared<LightField>(lens);
  {
    const bool per_sample = !o.combined_per_pixel;
    std::vector<float>* dst[3] = {&on_lens->r, &on_lens->g, &on_lens->b};
    const std::vector<float>* src[3] = {&light->r, &light->g, &light->b};
    const WeightY wu(lens);
    parallel_rows(0, all.height, nthreads, [&](int y) {
      for (int x = 0; x < all.width; ++x) {
        const std::size_t p = std::size_t(y) * std::size_t(all.width) + std::size_t(x);
        const float* e = lit.pixel(x, y);
        for (int c = 0; c < 3; ++c) {
          double mean = 0, ws = 0;
          if (per_sample) {
            for (std::size_t k = p * spp; k < (p + 1) * spp; ++k) {
              const double w = double(wu(lens.y1[k])) * double(wu(lens.y2[k]));
              mean += w * (*src[c])[k], ws += w;
            }
            mean = ws > 0 ? mean / ws : 0.0;
          }
          for (std::size_t k = p * spp; k < (p + 1) * spp; ++k)
            (*dst[c])[k] *= per_sample ? float((*src[c])[k] - mean + e[c]) : e[c];
        }
      }
    });
  }
  const Image own = own_means(*on_lens, nthreads);
  for (std::string& n : run_stage(on_lens, own, filter + " (lens)", o, roi, nthreads, out, core, sheared))
    notes.push_back(std::move(n));
  // The two stages together against the frame's own estimates (the soft shadows' rule: the
  // strata of the lens meet shuffled strata of the light, so their halves see independent light).
  step_back(all, flat, filter, ", both stages", step_back_for(o, LightFieldEffect::SoftShadows), o, roi, nthreads, out,
            notes);
  return notes;
}

}  // namespace

std::vector<std::string> run_on_frame(const Frame& frame, const std::string& filter, const Options& o, const Roi& roi,
                                      int nthreads, Image& out, Core core, bool sheared) {
  const std::shared_ptr<const LightField> decoded = decoded_lightfield(frame, filter);
  const std::size_t nonfinite = decoded->nonfinite_replaced;
  std::vector<std::string> notes =
      decoded->combined()
          ? run_combined(decoded, frame.image(Role::Colour), filter, o, roi, nthreads, out, core, sheared)
          : run_stage(decoded, frame.image(Role::Colour), filter, o, roi, nthreads, out, core, sheared);
  if (nonfinite) notes.push_back(filter + ": " + std::to_string(nonfinite) + " non-finite sample values replaced by their pixel's mean");
  return notes;
}

}  // namespace mcr::lf
