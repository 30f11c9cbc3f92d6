#include "prepare/sample_limits.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "image/luminance.h"
#include "util/parallel.h"

namespace mcr {

namespace {

constexpr float kY0 = 0.2126f, kY1 = 0.7152f, kY2 = 0.0722f;

// The window's sums without its centre, added pixel by pixel in double (the few pixels
// whose own value dwarfs their window's sums).
void direct(const Image& rgb, int x, int y, int radius, double& s, double& s2, double& n) {
  s = s2 = n = 0;
  for (int qy = std::max(0, y - radius); qy <= std::min(rgb.height() - 1, y + radius); ++qy)
    for (int qx = std::max(0, x - radius); qx <= std::min(rgb.width() - 1, x + radius); ++qx) {
      const float* q = rgb.pixel(qx, qy);
      if ((qx == x && qy == y) || !finite3(q)) continue;
      const double v = luminance(q);
      s += v;
      s2 += v * v;
      n += 1.0;
    }
}

}  // namespace

// Float planes, each window summed directly (a row pass of 2r+1 taps, then a column pass):
// no running sums, so a firefly of 1e30 cannot leave its rounding behind in the pixels
// after it. Float is enough for a bound: the variance's rounding (1e-6 of E[Y^2]) matters
// only where sd < 0.01 mu / k, where the 0.01 |mu| floor decides anyway.
void firefly_limits(const Image& rgb, int radius, double k, int nthreads, std::vector<float>& limit, double k_fresh,
                    std::vector<float>* fresh) {
  const int w = rgb.width(), h = rgb.height();
  const std::size_t n = std::size_t(w) * std::size_t(h);
  limit.resize(n);
  if (fresh) fresh->resize(n);
  // Kept by the calling thread between frames (references: a thread_local named inside
  // the workers would be each worker's own). Planes: Y (0 where not finite), finite (1/0),
  // and the row sums of Y, Y^2, finite.
  thread_local std::vector<float> kept;
  std::vector<float>& buf = kept;
  buf.resize(5 * n);
  float* ly = buf.data();
  float* lf = ly + n;
  float* rs = lf + n;
  float* rq = rs + n;
  float* rc = rq + n;
  parallel_rows(0, h, nthreads, [&](int y) {
    const float* p = rgb.pixel(0, y);
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    for (int x = 0; x < w; ++x) {
      const float* q = p + std::size_t(x) * 3;
      const float v = kY0 * q[0] + kY1 * q[1] + kY2 * q[2];
      const bool ok = v - v == 0.0f;
      ly[rb + std::size_t(x)] = ok ? v : 0.0f;
      lf[rb + std::size_t(x)] = ok ? 1.0f : 0.0f;
    }
    for (int x = 0; x < w; ++x) {
      float s = 0, q = 0, c = 0;
      for (int t = std::max(0, x - radius), e = std::min(w - 1, x + radius); t <= e; ++t) {
        const float v = ly[rb + std::size_t(t)];
        s += v;
        q += v * v;
        c += lf[rb + std::size_t(t)];
      }
      rs[rb + std::size_t(x)] = s;
      rq[rb + std::size_t(x)] = q;
      rc[rb + std::size_t(x)] = c;
    }
  });
  const float kf = float(k), kff = float(k_fresh);
  constexpr float kMax = std::numeric_limits<float>::max(), kInfF = std::numeric_limits<float>::infinity();
  parallel_rows(0, h, nthreads, [&](int y) {
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    const int y0 = std::max(0, y - radius), y1 = std::min(h - 1, y + radius);
    float* out = limit.data() + rb;
    float* outf = fresh ? fresh->data() + rb : nullptr;
    // The window sums without the centre, and the bound, in float (vectorised) ...
    for (int x = 0; x < w; ++x) {
      float s = 0, q = 0, c = 0;
      for (int t = y0; t <= y1; ++t) {
        const std::size_t j = std::size_t(t) * std::size_t(w) + std::size_t(x);
        s += rs[j];
        q += rq[j];
        c += rc[j];
      }
      const float v = ly[rb + std::size_t(x)], f = lf[rb + std::size_t(x)];
      s -= v;
      q -= v * v;
      c -= f;
      const float mu = s / std::max(c, 1.0f);
      const float sd = std::sqrt(std::max(q / std::max(c, 1.0f) - mu * mu, 0.0f));
      const float bound = mu + std::max(kf * sd, 0.01f * std::fabs(mu));
      out[x] = c < 2.5f ? kInfF : std::min(bound, kMax);  // an overflowed bound reads as the largest float
      if (outf) outf[x] = c < 2.5f ? kInfF : std::min(mu + std::max(kff * sd, 0.01f * std::fabs(mu)), kMax);
    }
    // ... then, rarely, a centre that dwarfs its window (its removal leaves only rounding)
    // or a Y^2 that overflowed: summed again pixel by pixel in double.
    for (int x = 0; x < w; ++x) {
      const float v = ly[rb + std::size_t(x)];
      float s = 0, q = 0;
      for (int t = y0; t <= y1; ++t) {
        s += rs[std::size_t(t) * std::size_t(w) + std::size_t(x)];
        q += rq[std::size_t(t) * std::size_t(w) + std::size_t(x)];
      }
      if (!(std::fabs(v) * 1e-4f > std::fabs(s - v) || !(q <= kMax) || v * v * 1e-4f > q - v * v)) continue;
      double ds, dq, dc;
      direct(rgb, x, y, radius, ds, dq, dc);
      if (dc < 2.5) {
        out[x] = kInfF;
        if (outf) outf[x] = kInfF;
        continue;
      }
      const double mu = ds / dc;
      const double sd = std::sqrt(std::max(dq / dc - mu * mu, 0.0));
      auto bound = [&](double kk) {
        const double b = mu + std::max(kk * sd, 0.01 * std::fabs(mu));
        return std::isfinite(b) ? float(std::min(b, double(kMax))) : kMax;
      };
      out[x] = bound(k);
      if (outf) outf[x] = bound(k_fresh);
    }
  });
}

void neighbourhood_caps(const Image& rgb, const std::vector<std::uint8_t>& flags, std::uint8_t mask, int nthreads,
                        std::vector<float>& cap) {
  const int w = rgb.width(), h = rgb.height();
  const std::size_t n = std::size_t(w) * std::size_t(h);
  cap.resize(n);
  // Separable: the 3-wide row maxima of the finite luminance (-inf where none), then the
  // 3-tall maxima of those, in float (a cap, not a sum).
  thread_local std::vector<float> kept;
  std::vector<float>& rowmax = kept;
  rowmax.resize(n);
  constexpr float kNone = -std::numeric_limits<float>::infinity();
  parallel_rows(0, h, nthreads, [&](int y) {
    const float* p = rgb.pixel(0, y);
    float* r = rowmax.data() + std::size_t(y) * std::size_t(w);
    float prev = kNone, cur = kNone;
    auto lum = [&](int x) {
      const float* q = p + std::size_t(x) * 3;
      const float v = kY0 * q[0] + kY1 * q[1] + kY2 * q[2];
      return (v - v == 0.0f) ? v : kNone;
    };
    if (w > 0) cur = lum(0);
    for (int x = 0; x < w; ++x) {
      const float next = x + 1 < w ? lum(x + 1) : kNone;
      r[x] = std::max(std::max(prev, cur), next);
      prev = cur;
      cur = next;
    }
  });
  parallel_rows(0, h, nthreads, [&](int y) {
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    const float* up = rowmax.data() + std::size_t(std::max(0, y - 1)) * std::size_t(w);
    const float* mid = rowmax.data() + rb;
    const float* down = rowmax.data() + std::size_t(std::min(h - 1, y + 1)) * std::size_t(w);
    for (int x = 0; x < w; ++x) {
      const float m = std::max(std::max(up[x], mid[x]), down[x]);
      cap[rb + std::size_t(x)] = (flags[rb + std::size_t(x)] & mask) && m > kNone ? m : std::numeric_limits<float>::infinity();
    }
  });
}

}  // namespace mcr
