#pragma once
// Light fields built in memory for the light-field filter tests (sheared4d, sheared, aaf): the
// arrays sized here (not through LightField::resize or decode), uniform jittered samples in a
// shuffled order, and the closed form of a field of one slope.
//
// Convention (image/lightfield.h): a sample at x' with y' is what pixel x sees at
// y = y' - (x - x') / s. A field constant along those lines is f(X, y) = G(y + X / s) (X in x
// units): G(y' + X'/s) = G((y' - (X - X')/s) + X/s). With w_y a Gaussian of sigma_y, the pixel's
// value h(X) = integral of G(y + X/s) w_y(y) dy / integral of w_y: for G(v) = sin(k v),
// h = exp(-k^2 sigma_y^2 / 2) sin(k X / s).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <vector>

#include "image/image.h"
#include "image/lightfield.h"

namespace mcr::testutil {

inline LightField make_lightfield(LightFieldEffect effect, int w, int h, int l, float y_range, float sigma_y,
                                  bool geometry) {
  LightField lf;
  lf.effect = effect;
  lf.width = w;
  lf.height = h;
  lf.l = l;
  lf.y_range = y_range;
  lf.sigma_y = sigma_y;
  const std::size_t n = std::size_t(w) * std::size_t(h), s = n * std::size_t(l * l);
  for (auto* v : {&lf.r, &lf.g, &lf.b, &lf.y1, &lf.y2}) v->assign(s, 0.0f);
  for (auto* v : {&lf.smin, &lf.smax, &lf.depth}) v->assign(n, 0.0f);
  lf.e1x.assign(n, 1.0f);
  lf.e1y.assign(n, 0.0f);
  lf.e2x.assign(n, 0.0f);
  lf.e2y.assign(n, 1.0f);
  if (geometry) {
    for (auto* v : {&lf.px, &lf.py, &lf.pz, &lf.nx, &lf.ny}) v->assign(n, 0.0f);
    lf.nz.assign(n, 1.0f);
  }
  return lf;
}

// Uniform jittered sampling (Yan 2015 sec. 5): pixel p's l*l samples share one random offset
// on the l x l grid over [-L, L]^2; stored in a shuffled order (filters must not assume one).
inline void jitter_samples(LightField& lf, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const int l = lf.l;
  const float L = lf.y_range, cell = 2 * L / float(l);
  std::vector<int> order(std::size_t(l * l));
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    const float o1 = u(rng), o2 = u(rng);
    for (int i = 0; i < l * l; ++i) order[std::size_t(i)] = i;
    std::shuffle(order.begin(), order.end(), rng);
    for (int i = 0; i < l * l; ++i) {
      const int a = order[std::size_t(i)] % l, b = order[std::size_t(i)] / l;
      const std::size_t k = p * std::size_t(l * l) + std::size_t(i);
      lf.y1[k] = -L + (float(a) + o1) * cell;
      lf.y2[k] = -L + (float(b) + o2) * cell;
    }
  }
}

inline void set_axes(LightField& lf, float e1x, float e1y, float e2x, float e2y) {
  std::fill(lf.e1x.begin(), lf.e1x.end(), e1x);
  std::fill(lf.e1y.begin(), lf.e1y.end(), e1y);
  std::fill(lf.e2x.begin(), lf.e2x.end(), e2x);
  std::fill(lf.e2y.begin(), lf.e2y.end(), e2y);
}

inline void set_slopes(LightField& lf, float smin, float smax) {
  std::fill(lf.smin.begin(), lf.smin.end(), smin);
  std::fill(lf.smax.begin(), lf.smax.end(), smax);
}

// Pixel p's centre in x units: X = [e1 e2]^-1 (x + 0.5, y + 0.5) (its own axes).
inline void x_units(const LightField& lf, std::size_t p, double* X1, double* X2) {
  const double sx = double(p % std::size_t(lf.width)) + 0.5, sy = double(p / std::size_t(lf.width)) + 0.5;
  const double a = lf.e1x[p], b = lf.e2x[p], c = lf.e1y[p], d = lf.e2y[p];
  const double det = a * d - b * c;
  *X1 = (d * sx - b * sy) / det;
  *X2 = (-c * sx + a * sy) / det;
}

// Every sample's colour from fn(X1, X2, y1, y2) (the same in R, G, B times 1, 0.8, 0.6).
inline void fill_values(LightField& lf, const std::function<double(double, double, double, double)>& fn) {
  const std::size_t spp = std::size_t(lf.spp());
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double X1, X2;
    x_units(lf, p, &X1, &X2);
    for (std::size_t k = p * spp; k < (p + 1) * spp; ++k) {
      const double v = fn(X1, X2, lf.y1[k], lf.y2[k]);
      lf.r[k] = float(v);
      lf.g[k] = float(0.8 * v);
      lf.b[k] = float(0.6 * v);
    }
  }
}

// The plain (unweighted) per-pixel mean of the samples.
inline Image plain_mean(const LightField& lf) {
  Image out(lf.width, lf.height, 3);
  const std::size_t spp = std::size_t(lf.spp());
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double s[3] = {0, 0, 0};
    for (std::size_t k = p * spp; k < (p + 1) * spp; ++k) {
      s[0] += lf.r[k];
      s[1] += lf.g[k];
      s[2] += lf.b[k];
    }
    for (int c = 0; c < 3; ++c) out.data()[p * 3 + std::size_t(c)] = float(s[c] / double(spp));
  }
  return out;
}

// RMS over channel 0 of the pixels at least `margin` from the border.
inline double rms_diff(const Image& a, const Image& b, int margin = 0) {
  double s = 0;
  std::size_t n = 0;
  for (int y = margin; y < a.height() - margin; ++y)
    for (int x = margin; x < a.width() - margin; ++x) {
      const double d = double(a.at(x, y, 0)) - double(b.at(x, y, 0));
      s += d * d;
      ++n;
    }
  return n ? std::sqrt(s / double(n)) : 0.0;
}

inline bool same_bits(const Image& a, const Image& b) {
  return a.storage().size() == b.storage().size() &&
         std::equal(a.storage().begin(), a.storage().end(), b.storage().begin(),
                    [](float u, float v) { return std::memcmp(&u, &v, sizeof u) == 0; });
}

}  // namespace mcr::testutil
