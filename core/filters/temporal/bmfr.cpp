#include "filters/temporal/bmfr.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <ctime>

#include "kernels/residual_shrink.h"
#include "prepare/demodulation.h"
#include "prepare/history_guards.h"
#include "prepare/surface_classes.h"
#include "util/avx2_shuffles.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/isa.h"

namespace mcr {

namespace {

double cpu_now_ms() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

const std::array<std::array<float, 2>, 16>& BmfrFilter::grid_offsets() {
  // A fixed sequence of 16 random displacements, uniform over the block (drawn once).
  static const std::array<std::array<float, 2>, 16> offsets = {{{0.00f, 0.00f}, {0.53f, 0.27f}, {0.19f, 0.81f},
                                                                {0.72f, 0.62f}, {0.38f, 0.09f}, {0.91f, 0.44f},
                                                                {0.06f, 0.56f}, {0.64f, 0.94f}, {0.27f, 0.35f},
                                                                {0.83f, 0.13f}, {0.45f, 0.71f}, {0.13f, 0.19f},
                                                                {0.97f, 0.86f}, {0.58f, 0.50f}, {0.31f, 0.98f},
                                                                {0.77f, 0.31f}}};
  return offsets;
}

const FilterInfo& BmfrFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "bmfr";
    i.summary = "Blockwise multi-order feature regression: temporal accumulation, per-block QR fit, TAA";
    i.reference = "Koskela et al., Blockwise Multi-Order Feature Regression for real-time path tracing reconstruction, ACM TOG 2019";
    // Demodulation is bmfr's own (fused into phase I, remodulated before TAA): it takes
    // every preparation step but that one.
    i.steps.demodulate = false;
    i.steps.step_back = true;  // on a still (a frame without history) only: step_back_applies()
    i.params = with_preparation_params({
        ParamSpec::Int("block_size", 0, 0, 128,
                       "side of the square regression blocks in pixels (8..128); 0 = auto: 32 (the paper's) when the "
                       "shorter image side is >= 360 pixels, 16 below"),
        ParamSpec::Float("epsilon", 0.01, 0.0, 10.0,
                         "stochastic regularisation: uniform noise in [-epsilon, epsilon] added to the fitted features"),
        ParamSpec::Float("alpha1", 0.2, 0.01, 1.0, "phase I: weight floor of the new noisy sample (cumulative average until then)"),
        ParamSpec::Float("alpha2", 0.1, 0.01, 1.0, "phase III: weight floor of the new fitted frame"),
        ParamSpec::Float("sample_limit_k", 3.0, 0.0, 1e3,
                         "phase I: a new sample's luminance is cut to its neighbours' mean + this many standard deviations "
                         "(prepare/sample_limits.h) unless its own history backs it (sample_limit_history); 0 = off"),
        ParamSpec::Int("sample_limit_radius", 2, 1, 8, "half width of the sample limit's window"),
        ParamSpec::Float("sample_limit_history", 4.0, 1.0, 1e6,
                         "a sample up to this many times its history's luminance passes the sample limit"),
        ParamSpec::Float("mirror_taa_alpha", 0.3, 0.01, 1.0,
                         "TAA: weight floor of the current frame on mirror-like pixels (Glossy Color > 10x Diffuse Color)"),
        ParamSpec::Float("mirror_alpha", 1.0, 0.0, 1.0,
                         "weight floor of the new sample on mirror-like pixels (Glossy Color > 10x Diffuse Color) in phases "
                         "I and III; their phase I history is also cut to the brightest of the current 3x3 neighbourhood"),
        ParamSpec::Enum("features", "default", {"default", "first_order", "with_albedo", "with_depth"},
                        "feature set: default [1,n,w,w^2] (10), first_order [1,n,w] (7), with_albedo (+albedo, 13), "
                        "with_depth (+depth, 11); each but with_albedo + the albedo luminance (albedo_luminance)"),
        ParamSpec::Bool("albedo_luminance", true,
                        "fit also against the albedo's luminance (one more column; when an albedo pass exists and "
                        "features is not with_albedo): a surface with a specular layer (glossy tiles, a varnished "
                        "checker floor) keeps its texture after the demodulation (its specular light divided by the "
                        "albedo), which the smooth features blur across texture edges"),
        ParamSpec::Bool("offsets", true, "displace the block grid every frame by a fixed 16-entry random sequence"),
        ParamSpec::Bool("taa", true, "temporal anti-aliasing (reprojected history clipped to the 3x3 neighbourhood, see taa_clip) at the end"),
        ParamSpec::Float("taa_alpha", 0.2, 0.01, 1.0, "TAA: weight of the current frame"),
        ParamSpec::Enum("taa_clip", "ycocg_variance", {"ycocg_variance", "rgb_minmax"},
                        "TAA history clipping box: ycocg_variance = 3x3 min/max intersected with mean +- taa_gamma "
                        "standard deviations in YCoCg (Karis 2014, Salvi 2016); rgb_minmax = 3x3 min/max in RGB"),
        ParamSpec::Float("taa_gamma", 0.5, 0.1, 10.0,
                         "TAA: half-width of the variance box in standard deviations (0.5: chosen on the anim and metal "
                         "samples; 1 ghosted the moving highlights)"),
        ParamSpec::Enum("taa_history", "catmull_rom", {"bilinear", "catmull_rom"},
                        "TAA: history lookup (catmull_rom: sharper, Karis 2014; bilinear blurs a moving image a little "
                        "more every frame)"),
        ParamSpec::Float("residual_k", 3.0, 0.0, 1e3,
                         "detail: the fit's residual against phase I's accumulation, averaged over each pixel's window, "
                         "is added back before TAA with the James-Stein weight 1 - residual_k x its noise / its square "
                         "(a hard shadow on a flat wall, which no feature explains, comes back; noise about a right fit "
                         "does not; 3 with residual_radius 2: chosen on the metal and anim samples); 0 = off "
                         "(kernels/residual_shrink.h)"),
        ParamSpec::Int("residual_radius", 2, 1, 4, "detail: half width of the residual's window"),
        ParamSpec::Bool("fit_clamp", true,
                        "clamp the fitted illumination to [min(0, block min), max(0, block max)] of the block's "
                        "accumulated input (the paper clamps only at 0 implicitly; guards ill-conditioned blocks)"),
        ParamSpec::Int("seed", 0, 0, 2147483647, "seed of the regularisation noise"),
        ParamSpec::Bool("albedo_demodulation", true,
                        "fit illumination = colour / max(albedo, albedo_floor) and multiply back before TAA (when an albedo "
                        "pass exists); pixels whose albedo exceeds 1 (it holds light) are left out of the fit, mirror-like "
                        "ones are not divided"),
        ParamSpec::Float("albedo_floor", kDefaultAlbedoFloor, 1e-6, 1.0,
                         "albedo_demodulation raises the albedo to at least this"),
        ParamSpec::Enum("position_test", "relative", {"relative", "absolute"},
                        "history discard by world distance: relative = in pixel footprints, absolute = world units"),
        ParamSpec::Float("position_threshold", 3.0, 0.0, 1e9, "history tap kept when its world distance is at most this"),
        ParamSpec::Float("normal_threshold", 0.9, -1.0, 1.0, "history tap kept when the cosine between normals is at least this"),
        ParamSpec::Float("cut_fraction", 0.9, 0.0, 1.0,
                         "camera cut: history restarts when more than this fraction of pixels lose every tap"),
    }, i.steps);
    i.params.push_back(alpha_param());
    // Its phase I sample limit does the firefly step's job, on the accumulated signal and at
    // a fraction of its cost (separable sums, not a two-pass 7x7 window per pixel).
    for (ParamSpec& p : i.params)
      if (p.name == "firefly_k") p.default_value = 0.0;
    i.required = {Role::Colour, Role::Normal, Role::Position};
    i.optional = {Role::Albedo, Role::Motion, Role::Depth};
    i.temporal = true;
    i.nonfinite_policy =
        "NaN/Inf colour: the pixel keeps its reprojected history (or is invalid without one) and is left out of the fit; "
        "NaN/Inf position or normal: no history for that pixel, left out of the fit, its features read as mid-range; "
        "NaN/Inf albedo reads as 1; NaN/Inf motion means no history; a block with no valid pixel keeps the history "
        "(0 without one); outputs are clamped to the float range";
    return i;
  }();
  return info;
}

PassNeeds BmfrFilter::own_needs() const {
  PassNeeds n = Filter::own_needs();
  const std::string& features = params_.get_enum("features");
  if (features == "with_albedo") n.require(Role::Albedo, "features=with_albedo");
  if (features == "with_depth") n.require(Role::Depth, "features=with_depth");
  return n;
}

std::vector<std::string> BmfrFilter::own_unused() const {
  std::vector<std::string> u = Filter::own_unused();
  const bool taa = params_.get_bool("taa");
  for (const char* name : {"taa_alpha", "taa_clip", "taa_gamma", "taa_history"}) unused_when(!taa, name, "with taa=false", u);
  unused_when(taa && params_.get_enum("taa_clip") != "ycocg_variance", "taa_gamma", "with taa_clip=rgb_minmax", u);
  unused_when(!params_.get_bool("albedo_demodulation"), "albedo_floor", "with albedo_demodulation=false", u);
  unused_when(params_.get_enum("features") == "with_albedo", "albedo_luminance", "with features=with_albedo", u);
  for (const char* name : {"sample_limit_radius", "sample_limit_history"})
    unused_when(!(params_.get_float("sample_limit_k") > 0), name, "with sample_limit_k=0", u);
  unused_when(!(params_.get_float("residual_k") > 0), "residual_radius", "with residual_k=0", u);
  return u;
}

void BmfrFilter::check_params() {
  const std::int64_t b = params_.get_int("block_size");
  if (b != 0 && b < 8) throw Error(Errc::InvalidArgument, "filter 'bmfr': block_size must be 0 (auto) or 8..128, got " + std::to_string(b));
  AccumulationParams p;
  p.alpha = params_.get_float("alpha1");
  p.reprojection.relative_position = params_.get_enum("position_test") == "relative";
  p.reprojection.position_threshold = params_.get_float("position_threshold");
  p.reprojection.normal_cos = params_.get_float("normal_threshold");
  p.reprojection.cut_fraction = params_.get_float("cut_fraction");
  phase1_.set_params(p);
}

void BmfrFilter::reset_history() {
  phase1_.reset();
  phase3_.reset();
  taa_w_ = taa_h_ = 0;
  frame_index_ = 0;
  last_cut_ = false;
  had_history_ = false;
}

int BmfrFilter::block_side(std::int64_t param, int w, int h) {
  if (param > 0) return int(param);
  return std::min(w, h) >= 360 ? 32 : 16;
}

namespace {
void ensure_image(Image& im, int w, int h, int ch) {
  if (im.width() != w || im.height() != h || im.channels() != ch) im = Image(w, h, ch);
}

// Phase III's remodulation of one row into the planar result: r = clamp(s * a) (a = 1
// without albedo), infinities to +-max, NaN kept. Returns the first pixel not done; the
// AVX2 build does 8 pixels at a time (the same operations), the caller the rest.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MCR_BMFR_AVX2 1

__attribute__((target("avx2"))) int remodulate_row_avx2(const float* s, const float* a, int w, float* r0, float* r1,
                                                        float* r2) {
  const __m256 lo = _mm256_set1_ps(-std::numeric_limits<float>::max()), hi = _mm256_set1_ps(std::numeric_limits<float>::max());
  int x = 0;
  for (; x + 8 <= w; x += 8) {
    __m256 v[3];
    load_rgb8(s + std::size_t(x) * 3, v[0], v[1], v[2]);
    if (a) {
      __m256 m[3];
      load_rgb8(a + std::size_t(x) * 3, m[0], m[1], m[2]);
      for (int c = 0; c < 3; ++c) v[c] = _mm256_mul_ps(v[c], m[c]);
    }
    // std::min(std::max(v, lo), hi): max_ps(lo, v) and min_ps(hi, t) keep a NaN v.
    _mm256_storeu_ps(r0 + x, _mm256_min_ps(hi, _mm256_max_ps(lo, v[0])));
    _mm256_storeu_ps(r1 + x, _mm256_min_ps(hi, _mm256_max_ps(lo, v[1])));
    _mm256_storeu_ps(r2 + x, _mm256_min_ps(hi, _mm256_max_ps(lo, v[2])));
  }
  return x;
}

#endif

}  // namespace

void BmfrFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  const int w = frame.width, h = frame.height;
  stage_ms_.fill(0.0);
  stage_cpu_ms_.fill(0.0);
  auto t0 = std::chrono::steady_clock::now();
  double c0 = cpu_now_ms();

  const std::size_t n = std::size_t(w) * h;
  classify_surfaces(frame, nthreads, classes_);
  if (!classes_.colour_passes && frame_index_ == 0)
    note("bmfr: no Diffuse and Glossy Color passes: mirror-like surfaces are not told apart (their history is "
         "reprojected with the surface)");
  if (classes_.light_in_albedo)
    note("bmfr: " + std::to_string(classes_.light_in_albedo) + " pixels whose albedo exceeds 1 (it holds light) kept "
         "their own accumulated value, out of the fit");
  if (classes_.mirror)
    note("bmfr: " + std::to_string(classes_.mirror) + " mirror-like pixels (Glossy Color > " +
         rounded_text(kMirrorRatio, 3) + "x Diffuse Color): not demodulated, out of the fit, history weight at least "
         "mirror_alpha and no brighter than the 3x3 neighbourhood");
  if (classes_.background)
    note("bmfr: " + std::to_string(classes_.background) + " background pixels (normal 0: the world, which Blender "
         "gives no motion) keep no phase I history brighter than their 3x3 neighbourhood");
  const Pass* ap = frame.find(Role::Albedo);
  const bool demod = params_.get_bool("albedo_demodulation") && ap;
  if (params_.get_bool("albedo_demodulation") && !ap) note("no albedo pass: the colour is fitted without demodulation");
  // Demodulation fused into phase I: row y of the illumination is made right before
  // phase I reads it.
  std::function<void(int)> demod_row;
  if (demod) {
    ensure_image(illum_, w, h, 3);
    ensure_image(albedo_, w, h, 3);
    const float lo = float(params_.get_float("albedo_floor"));
    const Image& ai = ap->image;
    // No ceiling: a pixel whose albedo holds light is divided by it (its light explained)
    // and left out of the fit below. A mirror is not divided at all.
    demod_row = [&, lo](int y) {
      demodulate_row(ai.pixel(0, y), ai.channels(), colour.pixel(0, y), w, lo, albedo_.pixel(0, y), illum_.pixel(0, y),
                     std::numeric_limits<float>::infinity());
      if (!classes_.mirror) return;
      const std::uint8_t* f = classes_.flags.data() + std::size_t(y) * std::size_t(w);
      for (int x = 0; x < w; ++x)
        if (f[x] & SurfaceClasses::kMirror)
          for (int c = 0; c < 3; ++c) {
            albedo_.at(x, y, c) = 1.0f;
            illum_.at(x, y, c) = colour.at(x, y, c);
          }
    };
  }

  // Phase I (reprojection fused with the accumulation), with its guards
  // (temporal/accumulation.h): the sample limit needs the new illumination whole first
  // (its windows), so the demodulation then runs ahead.
  HistoryGuardSettings gs;
  gs.limit_k = params_.get_float("sample_limit_k");
  gs.limit_radius = int(params_.get_int("sample_limit_radius"));
  gs.history_factor = params_.get_float("sample_limit_history");
  gs.mirror_alpha = params_.get_float("mirror_alpha");
  const bool ahead = demod && (gs.limit_k > 0 || classes_.mirror);
  if (ahead) parallel_rows(0, h, nthreads, demod_row);
  const AccumulationGuards guards = history_guards_.build(demod ? illum_ : colour, classes_, gs, nthreads);
  phase1_.set_guards(guards);
  const Image& acc1 = demod ? (ahead ? phase1_.accumulate(frame, illum_, nthreads)
                                           : phase1_.accumulate(frame, illum_, demod_row, nthreads))
                            : phase1_.accumulate(frame, colour, nthreads);
  phase1_.clear_guards();
  const Reprojection& rep = phase1_.last_reprojection();
  last_cut_ = rep.cut;
  had_history_ = rep.has_history && !rep.cut;
  if (rep.cut) note("camera cut: " + std::to_string(rep.discarded) + " of " + std::to_string(n) + " pixels lost their history; restarted");
  if (!rep.has_history || rep.cut) {
    phase3_.reset();
    taa_w_ = taa_h_ = 0;
  }
  stage_ms_[kAccumulate] = ms_since(t0);
  stage_cpu_ms_[kAccumulate] = cpu_now_ms() - c0;

  // Phase II.
  t0 = std::chrono::steady_clock::now();
  c0 = cpu_now_ms();
  ensure_image(fitted_, w, h, 3);
  const std::vector<float>& counts = phase1_.sample_count();
  if (classes_.any()) {
    // Pixels whose albedo holds light, and mirrors, are left out of the fit (it would
    // spread their light over the block) and keep their own accumulated illumination.
    fit_valid_.resize(n);
    for (std::size_t i = 0; i < n; ++i) fit_valid_[i] = (classes_.flags[i] & SurfaceClasses::kOutOfFit) ? 0.0f : counts[i];
  }
  fit_blocks(frame, acc1, classes_.any() ? fit_valid_ : counts, fitted_, nthreads);
  if (classes_.any())
    parallel_rows(0, h, nthreads, [&](int y) {
      for (std::size_t i = std::size_t(y) * std::size_t(w), e = i + std::size_t(w); i < e; ++i)
        if (fit_valid_[i] == 0.0f && counts[i] > 0.0f) std::copy(acc1.data() + 3 * i, acc1.data() + 3 * i + 3, fitted_.data() + 3 * i);
    });
  stage_ms_[kFit] = ms_since(t0);
  stage_cpu_ms_[kFit] = cpu_now_ms() - c0;

  // Phase III: second accumulation on phase I's reprojection (its discard decisions) and
  // the remodulation, one pass, into the planar result; without TAA and the detail stage
  // straight to `out` as well (the colour is no longer read: `out` may be the colour buffer).
  t0 = std::chrono::steady_clock::now();
  c0 = cpu_now_ms();
  const bool use_taa = params_.get_bool("taa");
  const bool detail = params_.get_float("residual_k") > 0;
  const bool hist = use_taa && taa_w_ == w && taa_h_ == h && taa_hist_.size() == 3 * n && rep.has_history && !rep.cut;
  const double alpha2 = params_.get_float("alpha2");
  res_.resize(3 * n);
  AccumulationGuards phase3_guards;  // mirrors keep a short history here too
  phase3_guards.alpha_floor = guards.alpha_floor;
  phase3_guards.history_cap = guards.history_cap;
  phase3_.begin(rep, fitted_);
  parallel_rows(0, h, nthreads, [&](int y) {
    phase3_.row(y, rep, fitted_, alpha2, phase3_guards);
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    const float* s = phase3_.pending().data() + rb * 3;
    const float* a = demod ? albedo_.data() + rb * 3 : nullptr;
    float* r0 = res_.data() + rb;
    float* r1 = r0 + n;
    float* r2 = r1 + n;
    constexpr float M = std::numeric_limits<float>::max();
    int x0 = 0;
#ifdef MCR_BMFR_AVX2
    if (isa_at_least(Isa::Avx2)) x0 = remodulate_row_avx2(s, a, w, r0, r1, r2);
#endif
    // Infinities become +-max, NaN stays (std::min/max keep their first argument).
    if (a)
      for (int x = x0; x < w; ++x) {
        const std::size_t i = std::size_t(x) * 3;
        r0[x] = std::min(std::max(s[i] * a[i], -M), M);
        r1[x] = std::min(std::max(s[i + 1] * a[i + 1], -M), M);
        r2[x] = std::min(std::max(s[i + 2] * a[i + 2], -M), M);
      }
    else
      for (int x = x0; x < w; ++x) {
        const std::size_t i = std::size_t(x) * 3;
        r0[x] = std::min(std::max(s[i], -M), M);
        r1[x] = std::min(std::max(s[i + 1], -M), M);
        r2[x] = std::min(std::max(s[i + 2], -M), M);
      }
    if (!use_taa && !detail && y >= roi.y0 && y < roi.y1) {
      float* o = out.data() + rb * 3;
      for (int x = roi.x0; x < roi.x1; ++x) {
        o[std::size_t(x) * 3] = r0[x];
        o[std::size_t(x) * 3 + 1] = r1[x];
        o[std::size_t(x) * 3 + 2] = r2[x];
      }
    }
  });
  phase3_.finish();
  stage_ms_[kPost] = ms_since(t0);
  stage_cpu_ms_[kPost] = cpu_now_ms() - c0;

  // The detail the fit missed, before TAA: its temporal blend then smooths what noise comes
  // back with it (after TAA, the anim sample's SSIM fell 0.865 -> 0.849).
  t0 = std::chrono::steady_clock::now();
  c0 = cpu_now_ms();
  if (detail) {
    ResidualSettings rs;
    rs.k = params_.get_float("residual_k");
    rs.radius = int(params_.get_int("residual_radius"));
    const std::size_t taken =
        add_back_residual(rs, acc1, demod ? &albedo_ : nullptr, {res_.data(), 1, n}, Roi::all(w, h), residual_scratch_,
                          nthreads);  // the whole frame: the next frame's TAA history
    note("bmfr: detail the fit missed added back at " + std::to_string(taken) + " pixels (over half their window's "
         "residual against the accumulated frames)");
    if (!use_taa) write_planar_roi(res_.data(), n, w, roi, out, nthreads);
  }
  stage_ms_[kDetail] = ms_since(t0);
  stage_cpu_ms_[kDetail] = cpu_now_ms() - c0;

  t0 = std::chrono::steady_clock::now();
  c0 = cpu_now_ms();
  if (use_taa) {
    taa(rep, hist, roi, out, nthreads);
  } else {
    taa_w_ = taa_h_ = 0;
  }
  stage_ms_[kTaa] = ms_since(t0);
  stage_cpu_ms_[kTaa] = cpu_now_ms() - c0;
  ++frame_index_;
}

}  // namespace mcr
