#include "io/half_buffers.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "metrics/metrics.h"
#include "util/error.h"

namespace mcr {

namespace {

// A pixel is a spike when one sample's squared deviation from the pixel's mean is more than this
// share of all its samples' (in any channel): a rare path, which stratification does not make
// less variable (.h).
constexpr double kSpikeShare = 0.5;

// (A - B)^2 n1 n2 / n^2 for the first n1 = n / 2 of s[0, n) against the rest: in expectation the
// variance of their mean where the two halves are independent (n >= 2).
double halves_estimate(const float* s, std::size_t n) {
  const std::size_t n1 = n / 2, n2 = n - n1;
  double a = 0, b = 0;
  for (std::size_t i = 0; i < n1; ++i) a += s[i];
  for (std::size_t i = n1; i < n; ++i) b += s[i];
  const double d = a / double(n1) - b / double(n2);
  return d * d * double(n1) * double(n2) / (double(n) * double(n));
}

// Passes Blender writes from a pixel's first sample only (with sample_offset > 0 its Depth is
// 1e10 and its Position 0): the first half's are the whole render's. Geometry at one hit is
// not averaged across an edge either; the second-hit passes are single-hit too.
bool written_on_first_sample(Role r) {
  return r == Role::Depth || r == Role::Position || r == Role::Motion || r == Role::SecondPosition ||
         r == Role::SecondNormal;
}

}  // namespace

Frame combine_halves(Frame first, const Frame& second) {
  if (first.width != second.width || first.height != second.height)
    throw Error(Errc::SizeMismatch, "half buffers of different sizes: '" + first.path + "' is " + std::to_string(first.width) +
                                        "x" + std::to_string(first.height) + ", '" + second.path + "' is " +
                                        std::to_string(second.width) + "x" + std::to_string(second.height));
  const Image& b = second.image(Role::Colour);
  Pass& colour = const_cast<Pass&>(first.get(Role::Colour));
  Image& a = colour.image;
  if (a.channels() < 3 || b.channels() < 3)
    throw Error(Errc::MissingPass, "half buffers need an RGB colour pass: '" + first.path + "', '" + second.path + "'");
  Pass var;
  var.role = Role::Variance;
  var.name = "half buffers";
  var.source = first.path + " + " + second.path;
  var.channels = {"variance.R", "variance.G", "variance.B"};
  var.image = Image(first.width, first.height, 3);
  const int shared = std::min(a.channels(), b.channels());
  for (int y = 0; y < first.height; ++y)
    for (int x = 0; x < first.width; ++x) {
      float* p = a.pixel(x, y);
      const float* q = b.pixel(x, y);
      float* v = var.image.pixel(x, y);
      for (int c = 0; c < shared; ++c) {  // RGB and alpha, accumulated alike; the variance of RGB
        if (c < 3) {
          const double d = double(p[c]) - double(q[c]);
          v[c] = float(std::min(d * d / 4.0, 3.0e38));  // beyond the float range: the largest float
        }
        p[c] = float(0.5 * double(p[c]) + 0.5 * double(q[c]));
      }
    }
  first.put(std::move(var));
  // The feature passes: a renderer accumulates most over the samples, so each half holds half
  // the samples' average and their mean is the whole render's (an 8-spp albedo, normal or light
  // pass is noisier than the 16-spp one, and every feature filter weighed its neighbours by it).
  for (Pass& p : first.passes) {
    if (p.role == Role::Colour || p.role == Role::Variance || written_on_first_sample(p.role)) continue;
    const Pass* q = nullptr;
    for (const Pass& c : second.passes)
      if (c.role == p.role && c.name == p.name && c.image.channels() == p.image.channels()) q = &c;
    if (!q) continue;
    const bool sum = p.role == Role::SampleCount;
    float* d = p.image.data();
    const float* o = q->image.data();
    for (std::size_t i = 0, n = p.image.storage().size(); i < n; ++i) {
      if (!std::isfinite(o[i])) continue;  // one half's value where the other has none
      if (!std::isfinite(d[i])) {
        d[i] = o[i];
        continue;
      }
      d[i] = float(std::min(std::max(sum ? double(d[i]) + o[i] : 0.5 * d[i] + 0.5 * o[i], -3.0e38), 3.0e38));
    }
  }
  return first;
}

std::optional<Pass> sample_halves_variance(const DeepSamples& deep, const Pass& colour) {
  if (colour.channels.size() < 3) return std::nullopt;
  int ch[3];
  for (int c = 0; c < 3; ++c) {
    ch[c] = deep.channel(colour.channels[std::size_t(c)]);
    if (ch[c] < 0) return std::nullopt;
  }
  Pass var;
  var.role = Role::Variance;
  var.name = "sample halves";
  var.source = colour.source;
  var.channels = {"variance.R", "variance.G", "variance.B"};
  var.image = Image(deep.width, deep.height, 3);
  // Over the pixels whose variance is not one sample's, R, G, B weighed as relMSE weighs them:
  // the halves' own estimates as the variance of a mean of n samples (a) and the whole's (b).
  double a = 0, b = 0;
  std::vector<std::uint8_t> corrected(std::size_t(deep.width) * std::size_t(deep.height), 0);
  std::vector<float> finite;
  for (int y = 0; y < deep.height; ++y)
    for (int x = 0; x < deep.width; ++x) {
      const std::uint64_t first = deep.first(x, y), n_all = deep.samples(x, y);
      float* v = var.image.pixel(x, y);
      double pa = 0, pb = 0;
      bool spike = false, rate = true;
      for (int c = 0; c < 3; ++c) {
        finite.clear();
        const std::vector<float>& s = deep.values[std::size_t(ch[c])];
        for (std::uint64_t i = first; i < first + n_all; ++i)
          if (std::isfinite(s[i])) finite.push_back(s[i]);
        const std::size_t n = finite.size(), n1 = n / 2, n2 = n - n1;
        if (n1 == 0) {
          v[c] = std::numeric_limits<float>::quiet_NaN();
          rate = false;
          continue;
        }
        const double whole = halves_estimate(finite.data(), n);
        v[c] = float(std::min(whole, 3.0e38));
        double mean = 0;
        for (float f : finite) mean += f;
        mean /= double(n);
        double sum2 = 0, max2 = 0;
        for (float f : finite) {
          const double d2 = (double(f) - mean) * (double(f) - mean);
          sum2 += d2;
          max2 = std::max(max2, d2);
        }
        spike = spike || max2 > kSpikeShare * sum2;
        if (n1 < 2) {
          rate = false;
          continue;
        }
        const double w = 1.0 / (mean * mean + kRelMseEps);
        pa += w * (halves_estimate(finite.data(), n1) * double(n1) + halves_estimate(finite.data() + n1, n2) * double(n2)) /
              double(n);
        pb += w * whole;
      }
      if (spike) continue;
      corrected[std::size_t(y) * std::size_t(deep.width) + std::size_t(x)] = 1;
      if (rate && std::isfinite(pa) && std::isfinite(pb)) {
        a += pa;
        b += pb;
      }
    }
  if (!(b > 0) || !std::isfinite(a)) return var;
  // Var(mean of n) ~ n^-alpha: the halves' estimates over the whole's read 2^alpha (2 for
  // independent samples); the whole's estimate over its true variance is 2^alpha - 1 (.h).
  const double ratio = std::min(std::max(a / b, 2.0), 4.0);
  for (int y = 0; y < deep.height; ++y)
    for (int x = 0; x < deep.width; ++x) {
      if (!corrected[std::size_t(y) * std::size_t(deep.width) + std::size_t(x)]) continue;
      float* v = var.image.pixel(x, y);
      for (int c = 0; c < 3; ++c) v[c] = float(double(v[c]) / (ratio - 1.0));
    }
  return var;
}

}  // namespace mcr
