#include "kernels/cross_bilateral_fit.h"

#include <algorithm>
#include <cmath>

#include "kernels/cross_bilateral.h"
#include "kernels/feature_guides.h"
#include "kernels/feature_regression.h"
#include "kernels/foveation.h"
#include "kernels/noise_relative_colour.h"
#include "kernels/planes.h"
#include "util/parallel.h"

namespace mcr {

ParamTable cross_bilateral_fit_params() {
  ParamTable t = {
      ParamSpec::Float("spatial_sigma", 2.0, 0.0, 21.0,
                       "standard deviation of the spatial Gaussian in pixels (0 = no filtering)"),
      ParamSpec::Int("radius", 0, 0, 64,
                     "window half width in pixels; 0 = ceil(3 spatial_sigma) at each pixel (follows foveation)"),
  };
  for (ParamSpec& s : feature_params()) t.push_back(s);
  t.push_back(colour_weight_param());
  t.push_back(ParamSpec::Int("order", 0, 0, 1,
                             "0 = weighted mean (the thesis' cross-bilateral); 1 = weighted first-order regression on "
                             "the feature passes over the same weights, the colour weight taken on the order-0 result "
                             "(Moon et al. 2014, Bitterli et al. 2016): edge mixes and texture ramps are fitted, not "
                             "averaged; slower (double-precision fit per pixel: about 2 s per megapixel at radius 6 on 2 cores)"));
  t.push_back(ParamSpec::Float("ridge", 0.1, 0.0, 1e6,
                               "order=1: ridge on the slopes, per unit of weight (features scaled by their own "
                               "1/(sqrt(2) sigma)); larger = closer to a weighted mean (with the colour weight still on "
                               "the order-0 result): about 1 for very noisy renders (room, dof at 16 spp), 0.005 for "
                               "cleaner ones (glossy)"));
  std::vector<std::string> fov = {"spatial_sigma"};
  for (const std::string& n : feature_sigma_names()) fov.push_back(n);
  return with_foveation(t, fov);
}

namespace {

// The window half width for a spatial sigma: the fixed `radius` when given, else 3 sigma.
int window_radius(int fixed, double sigma) { return sigma > 0 ? (fixed > 0 ? fixed : gaussian_radius(sigma)) : 0; }

}  // namespace

int cross_bilateral_fit_reach(const ParamSet& params) {
  const int fixed = int(params.get_int("radius"));
  int r = window_radius(fixed, params.get_float("spatial_sigma"));
  if (params.get_bool("foveated")) r = std::max(r, window_radius(fixed, params.get_float("spatial_sigma_outer")));
  if (params.get_int("order") == 1) r *= 2;
  if (params.get_enum("colour_weight") == "noise") r += 3;
  return r;
}

void cross_bilateral_fit(const Frame& frame, const Image& colour, const ParamSet& params, const std::string& owner,
                         const Roi& roi, Image& out, int nthreads, const std::function<void(std::string)>& note,
                         CrossBilateralScratch& s, double colour_units) {
  const int w = frame.width, h = frame.height;
  const Foveation fov(params, w, h);
  const int fixed = int(params.get_int("radius"));
  auto radius_at = [&](double sigma) { return window_radius(fixed, sigma); };

  const FoveatedValue spatial = fov.param("spatial_sigma");
  int rmax = 0, rmin = 1 << 30;
  if (spatial.varies) {
    std::vector<int> row_min(std::size_t(roi.height())), row_max(std::size_t(roi.height()));
    parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
      int lo = 1 << 30, hi = 0;
      for (int x = roi.x0; x < roi.x1; ++x) {
        const int r = radius_at(spatial.at(fov.blend_at(x, y)));
        lo = std::min(lo, r);
        hi = std::max(hi, r);
      }
      row_min[std::size_t(y - roi.y0)] = lo;
      row_max[std::size_t(y - roi.y0)] = hi;
    });
    rmin = *std::min_element(row_min.begin(), row_min.end());
    rmax = *std::max_element(row_max.begin(), row_max.end());
  } else {
    rmax = rmin = radius_at(spatial.inner);
  }

  // order=1 takes its colour weight on the order-0 result of every pixel of its window.
  const bool first_order = params.get_int("order") == 1;
  const Roi box = roi.grown(first_order ? 2 * rmax : rmax, w, h);
  planar_colour(colour, box, 0.0, nthreads, s.cp);
  const ColourPlanes& cp = s.cp;
  const PlaneBox& pb = cp.pb;
  gather_guides(frame, params, fov, owner, pb, note, nthreads, s.guides);
  const Guides& guides = s.guides;
  const std::size_t n = pb.size();
  std::vector<float>& valid = s.valid;
  valid.resize(n);
  parallel_rows(0, box.height(), nthreads, [&](int y) {
    for (std::size_t i = std::size_t(y) * pb.stride, e = i + std::size_t(pb.stride); i < e; ++i)
      valid[i] = cp.ok[i] * guides.ok[i];  // pads: 0 * 0
  });

  // Spatial coefficient 1/(2 sigma^2) and window radius, per pixel where foveation varies them.
  auto coef = [](double sg) { return sg > 0 ? float(std::min(1e30, 1.0 / (2.0 * sg * sg))) : 0.0f; };
  std::vector<float>& sc = s.spatial;
  std::vector<float>& rad = s.radius;
  sc.clear();
  rad.clear();
  if (spatial.varies) {
    pb.prepare(sc);
    if (rmin != rmax) pb.prepare(rad);
    parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
      for (int x = box.x0; x < box.x1; ++x) {
        const double sg = spatial.at(fov.blend_at(x, y));
        sc[pb.index(x, y)] = coef(sg);
        if (!rad.empty()) rad[pb.index(x, y)] = float(radius_at(sg));
      }
    });
  }

  std::vector<float>* res = s.res;
  for (int c = 0; c < 3; ++c) pb.prepare(res[c]);
  CrossPass pass;
  pass.pb = pb;
  for (int c = 0; c < 3; ++c) pass.colour[c] = cp.c[c].data();
  pass.colour_ok = cp.ok.data();
  pass.valid = valid.data();
  set_colour_weight(pass, guides, params, frame, colour, nthreads, s.noise_a);
  // The colour planes are scaled; an absolute sigma is in the render's units.
  const double units = params.get_enum("colour_weight") == "noise" ? 1.0 : colour_units;
  pass.colour_amul = float(1.0 / (double(cp.scale) * units));
  for (const Guides::Guide& g : guides.list) pass.guides.push_back(&g);
  pass.s = sc.empty() ? nullptr : sc.data();
  pass.s_const = coef(spatial.inner);
  pass.radius = rad.empty() ? nullptr : rad.data();
  pass.set_dense_taps(rmax);
  for (int c = 0; c < 3; ++c) pass.out[c] = res[c].data();
  cross_filter(pass, first_order ? roi.grown(rmax, w, h) : roi, nthreads);
  const float* planes[3] = {res[0].data(), res[1].data(), res[2].data()};
  if (first_order) {
    RegressionPass rp;
    rp.pb = pb;
    for (int c = 0; c < 3; ++c) {
      rp.colour[c] = cp.c[c].data();
      rp.guide[c] = res[c].data();
      rp.fallback[c] = res[c].data();
      pb.prepare(s.reg[c]);
      rp.out[c] = s.reg[c].data();
      planes[c] = s.reg[c].data();
    }
    rp.valid = valid.data();
    rp.colour_weight = pass.colour_weight;
    rp.colour_a = pass.colour_a;
    rp.colour_a_const = pass.colour_a_const;
    rp.colour_amul = pass.colour_amul;
    rp.features = pass.guides;
    rp.feature_ok = guides.ok.data();
    rp.s = pass.s;
    rp.s_const = pass.s_const;
    rp.radius = pass.radius;
    rp.rmax = rmax;
    rp.ridge = params.get_float("ridge");
    feature_regression(rp, roi, nthreads);
  }
  store_colour(planes, pb, cp.scale, roi, out, nthreads);
}

}  // namespace mcr
