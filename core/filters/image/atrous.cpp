#include "filters/image/atrous.h"

#include <algorithm>
#include <cmath>

#include "kernels/cross_bilateral.h"
#include "kernels/feature_guides.h"
#include "kernels/foveation.h"
#include "kernels/noise_relative_colour.h"
#include "kernels/planes.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

namespace {

// Defaults chosen on the tune scenes (room, glossy; 1 to 64 spp): colour differences in
// units of the estimated noise (4 standard deviations in the first pass, then decaying),
// and a tighter albedo weight (0.05) that keeps the textures at 64 spp.
ParamTable atrous_params() {
  FeatureDefaults d;
  d.sigma[0] = 4.0;   // colour
  d.sigma[3] = 0.05;  // albedo
  ParamTable t = {
      ParamSpec::Int("kernel_size", 5, 3, 9,
                     "generating kernel size k_g: 3 = [1 2 1]/4, 5 = [1 4 6 4 1]/16 (B3 spline, Dammertz), "
                     "9 = [1 8 28 56 70 56 28 8 1]/256 (the 5-tap kernel convolved with itself); 3, 5 or 9"),
      ParamSpec::Int("iterations", 5, 1, 10,
                     "passes; pass i spaces the taps 2^(i-1) pixels apart (effective size k_g 2^(i-1))"),
  };
  for (ParamSpec& s : feature_params(d)) t.push_back(s);
  for (ParamSpec& s : t)
    if (s.name == "colour_sigma") s.help += " (default 4 with colour_weight=noise: in noise standard deviations)";
  ParamSpec cw = colour_weight_param();
  cw.default_value = std::string("noise");
  t.push_back(cw);
  t.push_back(ParamSpec::Float("colour_sigma_decay", 0.5, 0.05, 1.0,
                               "pass i uses colour_sigma * decay^(i-1): 0.5 halves it every pass as in Dammertz et al. "
                               "(sigma_rt 2^-i), 1 keeps it constant"));
  return with_common_params(with_foveation(t, feature_sigma_names()));
}

}  // namespace

std::vector<float> AtrousFilter::generating_kernel(int kg) {
  switch (kg) {
    case 3: return {0.25f, 0.5f, 0.25f};
    case 5: return {1 / 16.f, 4 / 16.f, 6 / 16.f, 4 / 16.f, 1 / 16.f};
    case 9: return {1 / 256.f, 8 / 256.f, 28 / 256.f, 56 / 256.f, 70 / 256.f, 56 / 256.f, 28 / 256.f, 8 / 256.f, 1 / 256.f};
  }
  throw Error(Errc::Internal, "atrous: no generating kernel of size " + std::to_string(kg));
}

const FilterInfo& AtrousFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "atrous";
    i.summary = "Edge-avoiding A-Trous wavelet filter: iterated cross-bilateral passes with a dilated 3/5/9-tap kernel";
    i.reference = "Dammertz, Sewtz, Hanika, Lensch 2010 (HPG); Immonen 2017, sections 3.3, 4.1, 5.3, 5.4";
    i.params = atrous_params();
    edge_keeping_step_back(i.params);
    i.required = {Role::Colour};
    i.optional = {Role::Normal, Role::Position, Role::Albedo, Role::Depth};
    i.nonfinite_policy =
        "a neighbour whose colour or any used feature has a non-finite value gets weight 0 in every pass; a pixel "
        "whose own colour is non-finite skips the colour weight, one whose own feature f is non-finite skips f; a "
        "pixel whose taps all have weight 0 keeps its colour if finite, else gives 0 and stays unusable as a "
        "neighbour in the next pass. Feature differences that overflow give weight 0 (never NaN); colour beyond "
        "[2^-20, 2^100] is scaled by an exact power of two while summing, so sums never overflow and tiny values "
        "keep their precision";
    return i;
  }();
  return info;
}

void AtrousFilter::check_params() {
  const std::int64_t kg = params_.get_int("kernel_size");
  if (kg != 3 && kg != 5 && kg != 9)
    throw Error(Errc::ParameterOutOfRange,
                "parameter 'kernel_size' of filter 'atrous' must be 3, 5 or 9, got " + std::to_string(kg));
  check_foveation_params(params_, info().name);
}

int AtrousFilter::own_reach() const {
  const int half = int(params_.get_int("kernel_size")) / 2, iterations = int(params_.get_int("iterations"));
  int reach = 0;
  for (int i = 0; i < iterations && reach < (1 << 20); ++i) reach += half * (1 << i);
  return reach + 4;  // colour_weight=noise: the 3x3 variance and its 3x3 smoothing
}

void AtrousFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  const int w = frame.width, h = frame.height;
  const int kg = int(params_.get_int("kernel_size"));
  const int iterations = int(params_.get_int("iterations"));
  const double decay = params_.get_float("colour_sigma_decay");
  const std::vector<float> h1 = generating_kernel(kg);
  const int half = kg / 2;

  // Pass i reaches half * 2^(i-1); pass i must cover roi grown by what the later passes reach.
  std::vector<int> grow(std::size_t(iterations) + 1, 0);  // grow[i] = reach of passes i+1..n
  for (int i = iterations - 1; i >= 0; --i) grow[std::size_t(i)] = std::min(1 << 20, grow[std::size_t(i) + 1] + half * (1 << i));
  const Roi box = roi.grown(grow[0], w, h);

  const Foveation fov(params_, w, h);
  planar_colour(colour, box, 0.0, nthreads, cp_);
  ColourPlanes& cp = cp_;
  const PlaneBox& pb = cp.pb;
  gather_guides(frame, params_, fov, info().name, pb, [this](std::string s) { note(std::move(s)); }, nthreads, guides_);
  const Guides& guides = guides_;

  // Ping-pong between the colour planes and next_; pixels outside the region a
  // pass writes are never read by the later passes (their regions shrink).
  for (auto& p : next_) pb.prepare(p);
  pb.prepare(next_ok_);
  pb.prepare(valid_);
  pb.prepare(next_valid_);
  std::vector<float>* cur = cp.c;
  std::vector<float>* cur_ok = &cp.ok;
  std::vector<float>* nxt = next_;
  std::vector<float>* nxt_ok = &next_ok_;

  CrossPass pass;
  pass.pb = pb;
  set_colour_weight(pass, guides, params_, frame, colour, nthreads, noise_a_);
  const double absolute_units = params_.get_enum("colour_weight") == "noise" ? 1.0 : exposure_scale();
  for (const Guides::Guide& g : guides.list) pass.guides.push_back(&g);
  // Neighbours must hold data (colour) and finite features: valid = ok * guides.ok,
  // here for the first pass, then written by each pass with its result.
  std::vector<float>* valid = &valid_;
  std::vector<float>* nxt_valid = &next_valid_;
  parallel_rows(0, box.height(), nthreads, [&](int y) {
    const std::size_t a = std::size_t(y) * pb.stride, b = a + pb.stride;
    for (std::size_t k = a; k < b; ++k) (*valid)[k] = cp.ok[k] * guides.ok[k];
  });
  pass.valid_mask = guides.ok.data();
  for (int i = 1; i <= iterations; ++i) {
    const int step = 1 << (i - 1);
    const Roi region = roi.grown(grow[std::size_t(i)], w, h);
    for (int c = 0; c < 3; ++c) {
      pass.colour[c] = cur[c].data();
      pass.out[c] = nxt[c].data();
    }
    pass.colour_ok = cur_ok->data();
    pass.out_ok = nxt_ok->data();
    pass.valid = valid->data();
    pass.out_valid = i < iterations ? nxt_valid->data() : nullptr;
    // sigma_i = colour_sigma decay^(i-1): a_i = a / decay^(i-1), / scale for the scaled colour
    // (and an absolute sigma, in the render's units, / the exposure step's factor).
    pass.colour_amul = float(std::min(1e30, std::pow(decay, -double(i - 1)) / double(cp.scale) / absolute_units));
    pass.off.clear();
    pass.h.clear();
    for (int k = -half; k <= half; ++k) {
      pass.off.push_back(k * step);
      pass.h.push_back(h1[std::size_t(k + half)]);
    }
    cross_filter(pass, region, nthreads);
    std::swap(cur, nxt);
    std::swap(cur_ok, nxt_ok);
    std::swap(valid, nxt_valid);
  }
  const float* planes[3] = {cur[0].data(), cur[1].data(), cur[2].data()};
  store_colour(planes, pb, cp.scale, roi, out, nthreads);
}

}  // namespace mcr
