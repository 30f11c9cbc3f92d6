#include "filters/samples/sweep_kernel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace mcr::sweep {

namespace {

constexpr int kMaxScales = 8;

// 1/s^2 inside the s x s square around the pixel centre, else 0 (Appendix A's box()^2). The
// square is half-open, [-s/2, s/2): the paper's |x| < s/2 but for a measure-zero edge, so that
// an odd integer width holds whole pixels, whatever the samples' positions inside them (what
// lets the filter sum the layered path per source pixel).
inline float box(const Sample& s, float width) {
  const float r = 0.5f * width;
  return (s.dx >= -r && s.dx < r && s.dy >= -r && s.dy < r) ? 1.0f / (width * width) : 0.0f;
}

inline bool finish(double w, const double c[3], float out[3]) {
  if (!(w > 0)) {
    out[0] = out[1] = out[2] = 0;
    return false;
  }
  // The mean of finite floats can round past the float range in double: clamp before the cast.
  constexpr double kMax = std::numeric_limits<float>::max();
  for (int i = 0; i < 3; ++i) out[i] = float(std::clamp(c[i] / w, -kMax, kMax));
  return true;
}

// Depth as an unsigned key that orders like the float (depths are >= 0 or +inf here).
inline std::uint32_t depth_key(float z) {
  std::uint32_t u;
  std::memcpy(&u, &z, sizeof u);
  return u;
}

}  // namespace

Scales Scales::even(int count, float widest) {
  Scales s;
  count = std::clamp(count, 1, kMaxScales);
  if (count == 1) {
    s.widths = {widest};
    return s;
  }
  for (int k = 0; k < count; ++k) s.widths.push_back(1.0f + (widest - 1.0f) * float(k) / float(count - 1));
  return s;
}

Assign assign(float d, const Scales& s, bool blend) {
  const int K = s.size();
  Assign a;
  if (K == 1 || !(d == d)) return a;
  if (!blend) {
    for (int k = K - 1; k > 0; --k)
      if (d > s.widths[std::size_t(k)]) {
        a.k = k;
        break;
      }
    return a;
  }
  int k = 0;
  while (k + 1 < K - 1 && s.widths[std::size_t(k + 1)] <= d) ++k;
  const float lo = s.widths[std::size_t(k)], hi = s.widths[std::size_t(k + 1)];
  const float t = std::clamp((d - lo) / (hi - lo), 0.0f, 1.0f);
  if (t >= 1.0f) {
    a.k = k + 1;
  } else {
    a.k = k;
    a.t = t;
  }
  return a;
}

bool splat(const Sample* s, int n, bool variable, float widest, float out[3]) {
  double w = 0, c[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const float d = variable ? std::clamp(std::isfinite(s[i].d) ? s[i].d : 1.0f, 1.0f, std::max(1.0f, widest)) : 1.0f;
    const double wi = double(s[i].q) * box(s[i], d);
    if (wi == 0) continue;
    w += wi;
    for (int ch = 0; ch < 3; ++ch) c[ch] += wi * s[i].rgb[ch];
  }
  return finish(w, c, out);
}

bool sweep(Sample* s, int n, const Options& o, float out[3], bool* sorted) {
  const Scales& sc = o.scales;
  const int K = sc.size();
  std::vector<Assign> as(static_cast<std::size_t>(n));
  bool one_scale = true;
  for (int i = 0; i < n; ++i) {
    as[std::size_t(i)] = assign(s[i].d, sc, o.blend);
    one_scale = one_scale && as[std::size_t(i)].t == 0 && as[std::size_t(i)].k == as[0].k;
  }
  double w = 0, c[3] = {0, 0, 0};
  if (sorted) *sorted = !one_scale;
  if (one_scale) {
    // No other scale ever gains coverage: every weight is the box weight of this scale.
    const float width = n ? sc.widths[std::size_t(as[0].k)] : 1.0f;
    for (int i = 0; i < n; ++i) {
      double wi = double(s[i].q) * box(s[i], width);
      if (wi == 0) continue;
      if (o.power != 1) wi = std::pow(wi, double(o.power));
      w += wi;
      for (int ch = 0; ch < 3; ++ch) c[ch] += wi * s[i].rgb[ch];
    }
    return finish(w, c, out);
  }
  // Front to back: a key of depth and index, sorted as integers (ties keep array order).
  std::vector<std::uint64_t> order(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[std::size_t(i)] = (std::uint64_t(depth_key(s[i].z)) << 32) | std::uint32_t(i);
  std::sort(order.begin(), order.end());
  double cov[kMaxScales] = {0};
  for (std::uint64_t key : order) {
    const Sample& si = s[key & 0xffffffffu];
    const Assign a = as[key & 0xffffffffu];
    double bw[kMaxScales];
    bool any = false;
    for (int j = 0; j < K; ++j) {
      bw[j] = double(si.q) * box(si, sc.widths[std::size_t(j)]);
      any = any || bw[j] != 0;
    }
    if (!any) continue;
    double wi = 0;
    // Appendix A's order: the wider share first, its coverage updated before the narrower.
    auto part = [&](int k, double frac) {
      double others = 0, borrowed = 0;
      for (int j = 0; j < K; ++j)
        if (j != k) {
          others += cov[j];
          borrowed += bw[j] * cov[j];
        }
      const double free = std::max(0.0, 1.0 - others);
      wi += frac * (bw[k] * free + borrowed);
      cov[k] += frac * bw[k] * free;
    };
    if (a.t > 0) part(a.k + 1, a.t);
    if (a.t < 1) part(a.k, 1.0 - a.t);
    if (o.power != 1 && wi > 0) wi = std::pow(wi, double(o.power));
    w += wi;
    for (int ch = 0; ch < 3; ++ch) c[ch] += wi * si.rgb[ch];
  }
  return finish(w, c, out);
}

int layer_of(float z, float d, const Options& o, float focus) {
  const int K = o.scales.size();
  const int k = assign(d, o.scales, false).k;
  return z < focus ? (K - 1 - k) : (K - 1 + k);
}

void LayerSums::add(const Sample& si, int layer, int m, double power) {
  Acc& a = acc[std::size_t(layer * K + m)];
  const double qp = power == 1 ? double(si.q) : std::pow(double(si.q), power);
  a.q += si.q;
  a.qp += qp;
  for (int ch = 0; ch < 3; ++ch) a.c[ch] += qp * si.rgb[ch];
}

void LayerSums::add(const LayerSums& o, int m_at_least) {
  for (int layer = 0; layer < L; ++layer)
    for (int m = 0; m < K; ++m) {
      const Acc& from = o.acc[std::size_t(layer * K + m)];
      Acc& to = acc[std::size_t(layer * K + std::max(m, m_at_least))];
      to.q += from.q;
      to.qp += from.qp;
      for (int ch = 0; ch < 3; ++ch) to.c[ch] += from.c[ch];
    }
}

bool combine_layers(const LayerSums& acc, const Options& o, float out[3]) {
  const Scales& sc = o.scales;
  const int K = sc.size(), L = 2 * K - 1;
  const double p = o.power;
  double w = 0, c[3] = {0, 0, 0}, cov[kMaxScales] = {0};
  for (int layer = 0; layer < L; ++layer) {
    const int k = layer < K ? (K - 1 - layer) : (layer - (K - 1));
    double others = 0;
    for (int j = 0; j < K; ++j)
      if (j != k) others += cov[j];
    const double free = std::max(0.0, 1.0 - others);
    double gained = 0;
    for (int m = 0; m < K; ++m) {
      const LayerSums::Acc& a = acc.acc[std::size_t(layer * K + m)];
      if (a.q == 0 && a.qp == 0) continue;
      // Box weight per unit q of a sample whose narrowest box is m: 1/s_j^2 for j >= m.
      auto b = [&](int j) { return j >= m ? 1.0 / (double(sc.widths[std::size_t(j)]) * sc.widths[std::size_t(j)]) : 0.0; };
      double g = b(k) * free;
      for (int j = 0; j < K; ++j)
        if (j != k) g += b(j) * cov[j];
      const double gp = p == 1 ? g : std::pow(g, p);
      w += gp * a.qp;
      for (int ch = 0; ch < 3; ++ch) c[ch] += gp * a.c[ch];
      gained += b(k) * a.q;
    }
    cov[k] += free * gained;
  }
  return finish(w, c, out);
}

bool layered(const Sample* s, int n, const Options& o, float focus, float out[3]) {
  const Scales& sc = o.scales;
  const int K = sc.size();
  LayerSums acc(K);
  for (int i = 0; i < n; ++i) {
    const Sample& si = s[i];
    int m = 0;
    while (m < K && box(si, sc.widths[std::size_t(m)]) == 0) ++m;
    if (m == K) continue;  // outside the widest box
    acc.add(si, layer_of(si.z, si.d, o, focus), m, o.power);
  }
  return combine_layers(acc, o, out);
}

}  // namespace mcr::sweep
