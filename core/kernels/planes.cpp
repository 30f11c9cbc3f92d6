#include "kernels/planes.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

std::vector<float> PlaneBox::plane(float fill) const {
  std::vector<float> p;
  prepare(p, fill);
  return p;
}

void PlaneBox::prepare(std::vector<float>& v) const {
  if (v.size() != size()) {
    v.assign(size(), 0.0f);
    return;
  }
  const int w = box.width();
  for (int y = box.y0; y < box.y1; ++y) {
    float* row = v.data() + index(box.x0, y);
    std::fill(row - kPlanePad, row, 0.0f);
    std::fill(row + w, row + w + kPlanePad, 0.0f);
  }
}

void PlaneBox::prepare(std::vector<float>& v, float fill) const {
  prepare(v);
  for (int y = box.y0; y < box.y1; ++y) std::fill_n(v.begin() + std::ptrdiff_t(index(box.x0, y)), box.width(), fill);
}

// One row of n pixels of a 3-channel image into three planes, branch-free so that
// it vectorises: a pixel with a non-finite channel (|v| <= FLT_MAX fails for NaN
// and inf) becomes 0 with ok 0; finite channels are clamped to [-lim, lim].
// Returns the largest |value| written, as its bit pattern (an unsigned max
// vectorises where a float max would need -ffast-math).
MCR_ALWAYS_INLINE std::uint32_t split_rgb3_body(const float* __restrict v, int n, float lim, float* __restrict c0,
                                                float* __restrict c1, float* __restrict c2, float* __restrict ok) {
  std::uint32_t mb = 0;
  for (int x = 0; x < n; ++x) {
    const float r = v[3 * x], g = v[3 * x + 1], b = v[3 * x + 2];
    const bool f = std::fabs(r) <= FLT_MAX && std::fabs(g) <= FLT_MAX && std::fabs(b) <= FLT_MAX;
    const float a0 = f ? std::min(std::max(r, -lim), lim) : 0.0f;
    const float a1 = f ? std::min(std::max(g, -lim), lim) : 0.0f;
    const float a2 = f ? std::min(std::max(b, -lim), lim) : 0.0f;
    c0[x] = a0;
    c1[x] = a1;
    c2[x] = a2;
    ok[x] = f ? 1.0f : 0.0f;
    std::uint32_t b0, b1, b2;
    std::memcpy(&b0, &a0, 4);
    std::memcpy(&b1, &a1, 4);
    std::memcpy(&b2, &a2, 4);
    mb = std::max(mb, std::max(b0 & 0x7fffffffu, std::max(b1 & 0x7fffffffu, b2 & 0x7fffffffu)));
  }
  return mb;
}
MCR_ISA_VERSIONS(std::uint32_t, split_rgb3,
                 (const float* __restrict v, int n, float lim, float* __restrict c0, float* __restrict c1,
                  float* __restrict c2, float* __restrict ok),
                 (v, n, lim, c0, c1, c2, ok))

// The same for any channel count (the first `planes` channels, the last one
// repeated when the image has fewer), not vectorised.
std::uint32_t split_any(const float* v, int ch, int n, int planes, float lim, float* const* c, float* ok) {
  std::uint32_t mb = 0;
  for (int x = 0; x < n; ++x, v += ch) {
    bool f = true;
    for (int k = 0; k < planes; ++k) f = f && std::isfinite(v[std::min(k, ch - 1)]);
    for (int k = 0; k < planes; ++k) {
      const float a = f ? std::min(std::max(v[std::min(k, ch - 1)], -lim), lim) : 0.0f;
      c[k][x] = a;
      std::uint32_t b;
      std::memcpy(&b, &a, 4);
      mb = std::max(mb, b & 0x7fffffffu);
    }
    ok[x] = f ? 1.0f : 0.0f;
  }
  return mb;
}

namespace {

MCR_ALWAYS_INLINE void scale_row_body(float* __restrict v, int n, float s) {
  for (int x = 0; x < n; ++x) v[x] *= s;
}
MCR_ISA_VERSIONS(void, scale_row, (float* __restrict v, int n, float s), (v, n, s))

}  // namespace

void planar_colour(const Image& colour, const Roi& box, double clamp, int nthreads, ColourPlanes& p) {
  p.pb = PlaneBox(box);
  p.scale = 1.0f;
  for (auto& c : p.c) p.pb.prepare(c);
  p.pb.prepare(p.ok);
  const float lim = clamp > 0 ? float(std::min(clamp, double(FLT_MAX))) : FLT_MAX;
  std::vector<std::uint32_t> row_max(std::size_t(std::max(0, box.height())), 0);
  parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
    const std::size_t i0 = p.pb.index(box.x0, y);
    float* c[3] = {p.c[0].data() + i0, p.c[1].data() + i0, p.c[2].data() + i0};
    const float* v = colour.pixel(box.x0, y);
    row_max[std::size_t(y - box.y0)] =
        colour.channels() == 3 ? split_rgb3(v, box.width(), lim, c[0], c[1], c[2], p.ok.data() + i0)
                               : split_any(v, colour.channels(), box.width(), 3, lim, c, p.ok.data() + i0);
  });
  std::uint32_t mb = row_max.empty() ? 0 : *std::max_element(row_max.begin(), row_max.end());
  float m;
  std::memcpy(&m, &mb, 4);
  // Scale only out of [2^-20, 2^100]: huge values down so no sum overflows, tiny
  // ones up (at most 2^64) so their products stay clear of the denormals.
  if (m > 0.0f && (m > std::ldexp(1.0f, 100) || m < std::ldexp(1.0f, -20))) {
    int e = 0;
    std::frexp(m, &e);  // 2^(e-1) <= m < 2^e
    p.scale = std::ldexp(1.0f, std::min(64, 100 - e));
    parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
      for (auto& c : p.c) scale_row(c.data() + p.pb.index(box.x0, y), box.width(), p.scale);
    });
  }
}

namespace {

MCR_ALWAYS_INLINE void merge_rgb3_body(const float* __restrict c0, const float* __restrict c1,
                                       const float* __restrict c2, int n, float inv, float* __restrict o) {
  for (int x = 0; x < n; ++x) {
    o[3 * x + 0] = std::min(std::max(c0[x] * inv, -FLT_MAX), FLT_MAX);
    o[3 * x + 1] = std::min(std::max(c1[x] * inv, -FLT_MAX), FLT_MAX);
    o[3 * x + 2] = std::min(std::max(c2[x] * inv, -FLT_MAX), FLT_MAX);
  }
}
MCR_ISA_VERSIONS(void, merge_rgb3,
                 (const float* __restrict c0, const float* __restrict c1, const float* __restrict c2, int n, float inv,
                  float* __restrict o),
                 (c0, c1, c2, n, inv, o))

}  // namespace

void store_colour(const float* const planes[3], const PlaneBox& pb, float scale, const Roi& roi, Image& out,
                  int nthreads) {
  const float inv = 1.0f / scale;  // a power of two: exact, and the clamp catches any overflow
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    const std::size_t i0 = pb.index(roi.x0, y);
    merge_rgb3(planes[0] + i0, planes[1] + i0, planes[2] + i0, roi.width(), inv, out.pixel(roi.x0, y));
  });
}

}  // namespace mcr
