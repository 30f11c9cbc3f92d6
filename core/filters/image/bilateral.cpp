#include "filters/image/bilateral.h"

#include "kernels/foveation.h"

namespace mcr {

namespace {

// Defaults chosen on the tune scenes (room, glossy; 1 to 64 spp): colour differences in
// units of the estimated noise (4 standard deviations: a noisy render is averaged hard, a
// clean one barely), and a tighter albedo weight (0.05) that keeps the textures the
// noise-relative colour weight lets through at 64 spp.
ParamTable with_noise_defaults(ParamTable t) {
  for (ParamSpec& s : t) {
    if (s.name == "colour_weight") s.default_value = std::string("noise");
    if (s.name == "colour_sigma") {
      s.default_value = 4.0;
      s.help += " (default 4 with colour_weight=noise: in noise standard deviations)";
    }
    if (s.name == "albedo_sigma") s.default_value = 0.05;
  }
  return t;
}

}  // namespace

const FilterInfo& BilateralFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "bilateral";
    i.summary = "Cross-bilateral filter: spatial Gaussian times colour, normal, position, albedo and depth weights";
    i.reference = "Immonen 2017, sections 3.4 and 5.3 (Cross-Bilateral); Tomasi & Manduchi 1998; Eisemann & Durand 2004";
    i.params = with_common_params(with_noise_defaults(cross_bilateral_fit_params()));
    edge_keeping_step_back(i.params);
    i.required = {Role::Colour};
    i.optional = {Role::Normal, Role::Position, Role::Albedo, Role::Depth};
    i.nonfinite_policy =
        "a neighbour whose colour or any used feature has a non-finite value gets weight 0; a pixel whose own colour "
        "is non-finite skips the colour weight, and one whose own feature f is non-finite skips f, and is then the "
        "weighted mean of its usable neighbours; a window with no usable sample keeps the pixel's colour if finite, "
        "else gives 0. Feature differences that overflow give weight 0 (never NaN); colour beyond [2^-20, 2^100] is "
        "scaled by an exact power of two while summing, so sums never overflow and tiny values keep their precision. "
        "order=1: the fit uses the same usable neighbours and weights (in double); a pixel whose own feature is not "
        "finite, or whose system is singular, gets the order-0 result; the fit is clamped to the range of the window's "
        "colours, so it never overshoots";
    return i;
  }();
  return info;
}

void BilateralFilter::check_params() { check_foveation_params(params_, info().name); }

Roi BilateralFilter::reads(const Roi& roi, int width, int height) const {
  return roi.grown(cross_bilateral_fit_reach(params_), width, height);
}

std::vector<std::string> BilateralFilter::own_unused() const {
  std::vector<std::string> u = Filter::own_unused();
  unused_when(params_.get_int("order") == 0, "ridge", "with order=0", u);
  return u;
}

void BilateralFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  cross_bilateral_fit(frame, colour, params_, info().name, roi, out, nthreads, [this](std::string s) { note(std::move(s)); },
                      scratch_, exposure_scale());
}

}  // namespace mcr
