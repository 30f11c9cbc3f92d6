#pragma once
// The oracle of bmfr_taa_test.cpp: BMFR's TAA (temporal_antialias) one pixel at a time,
// in double, written from the description of the stage (Karis 2014 as used by Koskela et
// al. 2019, the YCoCg variance box of Salvi 2016), not from its code: the history is
// looked up where the motion puts the pixel (Catmull-Rom over the 4x4 taps around it,
// clamped to the frame, or bilinear over the taps inside the frame), clipped to the
// current frame's 3x3 neighbourhood box and blended with the current frame by taa_alpha;
// a pixel without history, or with a non-finite blend, keeps the current value.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "filters/temporal/bmfr_taa.h"

namespace mcr::testutil {

// A planar RGB frame, as the stage reads and writes it.
struct Planar {
  int w = 0, h = 0;
  std::vector<float> v;
  Planar(int w_, int h_, float fill = 0.0f) : w(w_), h(h_), v(3 * std::size_t(w_) * std::size_t(h_), fill) {}
  float& at(int c, int x, int y) {
    return v[(std::size_t(c) * std::size_t(h) + std::size_t(y)) * std::size_t(w) + std::size_t(x)];
  }
  float at(int c, int x, int y) const {
    return v[(std::size_t(c) * std::size_t(h) + std::size_t(y)) * std::size_t(w) + std::size_t(x)];
  }
};

struct Rgb {
  double c[3];
};

inline Rgb to_ycocg(const Rgb& p) {
  const double r = p.c[0], g = p.c[1], b = p.c[2];
  return {{r / 4 + g / 2 + b / 4, r / 2 - b / 2, -r / 4 + g / 2 - b / 4}};
}
inline Rgb from_ycocg(const Rgb& p) {
  const double y = p.c[0], co = p.c[1], cg = p.c[2];
  return {{y + co - cg, y + cg, y - co - cg}};
}

inline Rgb pixel(const Planar& f, int x, int y) { return {{f.at(0, x, y), f.at(1, x, y), f.at(2, x, y)}}; }

// The clipping box of pixel (x, y) in the clipping space: the 3x3 neighbourhood (border
// pixels repeated) min/max; for YCoCg intersected with mean +- gamma sd, each bound
// moved out to hold the pixel itself.
struct Box {
  Rgb lo, hi;
};
inline Box clip_box(const Planar& cur, int x, int y, bool ycocg, double gamma) {
  Box b;
  double sum[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
  for (int c = 0; c < 3; ++c) {
    b.lo.c[c] = std::numeric_limits<double>::infinity();
    b.hi.c[c] = -b.lo.c[c];
  }
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      Rgb q = pixel(cur, std::clamp(x + dx, 0, cur.w - 1), std::clamp(y + dy, 0, cur.h - 1));
      if (ycocg) q = to_ycocg(q);
      for (int c = 0; c < 3; ++c) {
        b.lo.c[c] = std::min(b.lo.c[c], q.c[c]);
        b.hi.c[c] = std::max(b.hi.c[c], q.c[c]);
        sum[c] += q.c[c];
        sq[c] += q.c[c] * q.c[c];
      }
    }
  if (ycocg) {
    const Rgb centre = to_ycocg(pixel(cur, x, y));
    for (int c = 0; c < 3; ++c) {
      const double mean = sum[c] / 9, sd = gamma * std::sqrt(std::max(0.0, sq[c] / 9 - mean * mean));
      b.lo.c[c] = std::max(b.lo.c[c], std::min(mean - sd, centre.c[c]));
      b.hi.c[c] = std::min(b.hi.c[c], std::max(mean + sd, centre.c[c]));
    }
  }
  return b;
}

// Catmull-Rom (Keys' cubic, a = -1/2) weight of a tap at distance d.
inline double catmull_rom(double d) {
  d = std::fabs(d);
  if (d < 1) return 1.5 * d * d * d - 2.5 * d * d + 1;
  if (d < 2) return -0.5 * d * d * d + 2.5 * d * d - 4 * d + 2;
  return 0;
}

// The history at the previous-frame position of pixel i; false: none.
inline bool history_sample(const Planar& hist, const Reprojection& rep, std::size_t i, bool cubic, Rgb& out) {
  const int w = hist.w, h = hist.h;
  const double px = rep.prev_x[i], py = rep.prev_y[i];
  if (!rep.inside[i]) return false;
  const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
  out = {{0, 0, 0}};
  if (cubic) {  // the 4x4 taps around the position, clamped to the frame; none outside it
    if (px < -0.5 || py < -0.5 || px > w - 0.5 || py > h - 0.5) return false;
    for (int ty = y0 - 1; ty <= y0 + 2; ++ty)
      for (int tx = x0 - 1; tx <= x0 + 2; ++tx) {
        const double wt = catmull_rom(px - tx) * catmull_rom(py - ty);
        const Rgb q = pixel(hist, std::clamp(tx, 0, w - 1), std::clamp(ty, 0, h - 1));
        for (int c = 0; c < 3; ++c) out.c[c] += wt * q.c[c];
      }
    return true;
  }
  double sum = 0;  // bilinear over the taps inside the frame, renormalised
  for (int k = 0; k < 4; ++k) {
    if (!(rep.inside[i] & (1u << k))) continue;
    const int tx = x0 + (k & 1), ty = y0 + (k >> 1);
    const double wt = (1 - std::fabs(px - tx)) * (1 - std::fabs(py - ty));
    if (wt <= 0) continue;
    sum += wt;
    const Rgb q = pixel(hist, tx, ty);
    for (int c = 0; c < 3; ++c) out.c[c] += wt * q.c[c];
  }
  if (sum <= 1e-6) return false;
  for (int c = 0; c < 3; ++c) out.c[c] /= sum;
  return true;
}

struct OracleStats {
  int no_history = 0, inside_box = 0, clipped = 0;
};

inline Planar oracle(const TaaSettings& s, const Reprojection& rep, const Planar& cur, const Planar& hist,
                     OracleStats* stats = nullptr) {
  Planar out(cur.w, cur.h);
  OracleStats st;
  for (int y = 0; y < cur.h; ++y)
    for (int x = 0; x < cur.w; ++x) {
      const std::size_t i = std::size_t(y) * std::size_t(cur.w) + std::size_t(x);
      const Rgb c = pixel(cur, x, y);
      Rgb hv, res = c;
      if (history_sample(hist, rep, i, s.catmull_rom, hv)) {
        const Box b = clip_box(cur, x, y, s.ycocg, s.gamma);
        Rgb q = s.ycocg ? to_ycocg(hv) : hv;
        bool outside = false;
        for (int k = 0; k < 3; ++k) outside |= q.c[k] < b.lo.c[k] || q.c[k] > b.hi.c[k];
        if (s.ycocg) {
          // Towards the box centre until inside along every axis that is not flat.
          double ratio = 1;
          const double e0 = (b.hi.c[0] - b.lo.c[0]) / 2, c0 = (b.hi.c[0] + b.lo.c[0]) / 2;
          for (int k = 0; k < 3; ++k) {
            const double centre = (b.hi.c[k] + b.lo.c[k]) / 2, extent = (b.hi.c[k] - b.lo.c[k]) / 2;
            if (extent > 1e-5 * (std::fabs(c0) + e0)) ratio = std::max(ratio, std::fabs(q.c[k] - centre) / extent);
          }
          for (int k = 0; k < 3; ++k) {
            const double centre = (b.hi.c[k] + b.lo.c[k]) / 2;
            q.c[k] = centre + (q.c[k] - centre) / ratio;
          }
        }
        for (int k = 0; k < 3; ++k) q.c[k] = std::clamp(q.c[k], b.lo.c[k], b.hi.c[k]);
        const Rgb k = s.ycocg ? from_ycocg(q) : q;
        bool finite = true;
        for (int ch = 0; ch < 3; ++ch) {
          res.c[ch] = k.c[ch] + s.alpha * (c.c[ch] - k.c[ch]);
          finite &= std::fabs(res.c[ch]) <= std::numeric_limits<float>::max();
        }
        if (!finite) res = c;
        ++(outside ? st.clipped : st.inside_box);
      } else {
        ++st.no_history;
      }
      for (int ch = 0; ch < 3; ++ch) out.at(ch, x, y) = float(res.c[ch]);
    }
  if (stats) *stats = st;
  return out;
}

}  // namespace mcr::testutil
