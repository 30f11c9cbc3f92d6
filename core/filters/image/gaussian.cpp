#include "filters/image/gaussian.h"

#include <algorithm>
#include <cmath>

#include "kernels/cross_bilateral.h"
#include "kernels/foveation.h"
#include "kernels/planes.h"
#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

namespace {

// d[i] += g s[i]: the inner loop of both 1D passes, also built for the wider
// vector units. No FMA contraction, so that every element rounds the same way
// whichever build runs and wherever the vector loop's peel and tail fall (a
// region then gives exactly the pixels of the whole frame).
MCR_ALWAYS_INLINE void madd_body(float* __restrict d, const float* __restrict s, float g, int n) {
  for (int i = 0; i < n; ++i) d[i] += g * s[i];
}
MCR_ISA_VERSIONS(void, madd, (float* __restrict d, const float* __restrict s, float g, int n), (d, s, g, n))

}  // namespace

const FilterInfo& GaussianFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "gaussian";
    i.summary = "Simple Blur: Gaussian blur of standard deviation sigma, optionally foveated";
    i.reference = "Immonen 2017, sections 3.2 and 5.3 (Simple Blur), foveation fig. 5.1";
    i.params = with_common_params(with_foveation(
        {ParamSpec::Float("sigma", 1.0, 0.0, 21.0,
                          "standard deviation in pixels; the window radius is ceil(3 sigma) (0 = no blur)")},
        {"sigma"}));
    i.required = {Role::Colour};
    i.nonfinite_policy =
        "a pixel with any non-finite RGB value gets weight 0 in every window (weights renormalised over the rest); "
        "a window with no finite pixel gives 0. Colour beyond [2^-20, 2^100] is scaled by an exact power of two "
        "while summing, so sums never overflow and tiny values keep their precision; results are clamped to the "
        "float range";
    return i;
  }();
  return info;
}

Roi GaussianFilter::reads(const Roi& roi, int width, int height) const {
  int r = gaussian_radius(params_.get_float("sigma"));
  if (params_.get_bool("foveated")) r = std::max(r, gaussian_radius(params_.get_float("sigma_outer")));
  return roi.grown(r, width, height);
}

void GaussianFilter::check_params() { check_foveation_params(params_, info().name); }

void GaussianFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  const Foveation fov(params_, frame.width, frame.height);
  if (fov.varies("sigma")) run_per_pixel(colour, roi, out, nthreads);
  else run_separable(colour, fov.inner("sigma"), roi, out, nthreads);
}

// Constant sigma: a horizontal then a vertical 1D pass. Each pass carries the
// weight sum as a fourth channel, so non-finite pixels (weight 0) and the clipped
// borders are renormalised exactly as the 2D kernel would be.
void GaussianFilter::run_separable(const Image& colour, double sigma, const Roi& roi, Image& out, int nthreads) {
  const int r = gaussian_radius(sigma);
  std::vector<float> g(std::size_t(r) + 1, 1.0f);
  for (int k = 1; k <= r; ++k) g[std::size_t(k)] = float(std::exp(-double(k) * k / (2.0 * sigma * sigma)));

  const Roi box = roi.grown(r, colour.width(), colour.height());
  planar_colour(colour, box, 0.0, nthreads, cp_);
  const ColourPlanes& cp = cp_;
  const int bw = box.width(), bh = box.height(), rw = roi.width(), ox = roi.x0 - box.x0;
  const std::size_t hn = std::size_t(bh) * std::size_t(rw);
  std::vector<float>* hz = hz_;
  for (int c = 0; c < 4; ++c) hz[c].assign(hn, 0.0f);

  parallel_rows(0, bh, nthreads, [&](int y) {
    const float* src[4] = {cp.c[0].data(), cp.c[1].data(), cp.c[2].data(), cp.ok.data()};
    const std::size_t row = cp.pb.index(box.x0, box.y0 + y);
    for (int k = -r; k <= r; ++k) {
      const float gk = g[std::size_t(std::abs(k))];
      const int xs = std::max(0, -(ox + k)), xe = std::min(rw, bw - ox - k);
      const int sh = ox + k;
      for (int c = 0; c < 4; ++c) {
        if (xe > xs) madd(hz[c].data() + std::size_t(y) * rw + xs, src[c] + row + std::ptrdiff_t(xs + sh), gk, xe - xs);
      }
    }
  });

  const PlaneBox rb(roi);
  std::vector<float>* res = res_;
  for (int c = 0; c < 3; ++c) rb.prepare(res[c]);
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    std::vector<float> acc(std::size_t(rw) * 4, 0.0f);
    const int yb = y - box.y0;
    for (int k = -r; k <= r; ++k) {
      const int yy = yb + k;
      if (yy < 0 || yy >= bh) continue;
      const float gk = g[std::size_t(std::abs(k))];
      for (int c = 0; c < 4; ++c) madd(acc.data() + std::size_t(c) * rw, hz[c].data() + std::size_t(yy) * rw, gk, rw);
    }
    const std::size_t row = rb.index(roi.x0, y);
    const float* w = acc.data() + 3 * std::size_t(rw);
    for (int c = 0; c < 3; ++c) {
      const float* a = acc.data() + std::size_t(c) * rw;
      float* o = res[c].data() + row;
      for (int x = 0; x < rw; ++x) o[x] = w[x] > 0.0f ? a[x] / w[x] : 0.0f;  // no finite pixel: 0
    }
  });
  const float* planes[3] = {res[0].data(), res[1].data(), res[2].data()};
  store_colour(planes, PlaneBox(roi), cp.scale, roi, out, nthreads);
}

// Spatially varying sigma: every pixel p its own Gaussian exp(-d^2 / (2 sigma(p)^2))
// over its own window |dx|, |dy| <= ceil(3 sigma(p)), renormalised.
void GaussianFilter::run_per_pixel(const Image& colour, const Roi& roi, Image& out, int nthreads) {
  const int w = colour.width(), h = colour.height();
  const Foveation fov(params_, w, h);
  const FoveatedValue sigma = fov.param("sigma");
  std::vector<int> row_max(std::size_t(roi.height()), 0);
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    int m = 0;
    for (int x = roi.x0; x < roi.x1; ++x) m = std::max(m, gaussian_radius(sigma.at(fov.blend_at(x, y))));
    row_max[std::size_t(y - roi.y0)] = m;
  });
  const int rmax = *std::max_element(row_max.begin(), row_max.end());

  const Roi box = roi.grown(rmax, w, h);
  planar_colour(colour, box, 0.0, nthreads, cp_);
  const ColourPlanes& cp = cp_;
  const PlaneBox& pb = cp.pb;
  std::vector<float>& s = s_;
  std::vector<float>& rad = rad_;
  pb.prepare(s);
  pb.prepare(rad);
  parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
    for (int x = box.x0; x < box.x1; ++x) {
      const double sg = sigma.at(fov.blend_at(x, y));
      rad[pb.index(x, y)] = float(gaussian_radius(sg));
      s[pb.index(x, y)] = sg > 0 ? float(std::min(1e30, 1.0 / (2.0 * sg * sg))) : 0.0f;
    }
  });
  std::vector<float>* res = res_;
  for (int c = 0; c < 3; ++c) pb.prepare(res[c]);

  CrossPass pass;
  pass.pb = pb;
  for (int c = 0; c < 3; ++c) pass.colour[c] = cp.c[c].data();
  pass.colour_ok = cp.ok.data();
  pass.valid = cp.ok.data();
  pass.s = s.data();
  pass.radius = rad.data();
  pass.set_dense_taps(rmax);
  for (int c = 0; c < 3; ++c) pass.out[c] = res[c].data();
  cross_filter(pass, roi, nthreads);
  const float* planes[3] = {res[0].data(), res[1].data(), res[2].data()};
  store_colour(planes, pb, cp.scale, roi, out, nthreads);
}

}  // namespace mcr
