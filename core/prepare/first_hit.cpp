#include "prepare/first_hit.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "util/parallel.h"

namespace mcr {

namespace {

// Blender's 1e10; a non-finite depth is not one (the filters' own policy reads it).
bool no_surface(float depth) { return std::isfinite(depth) && depth >= kNoSurfaceDepth; }

// A pixel met no surface by any depth pass's first sample.
bool first_missed(const Frame& frame, int x, int y) {
  for (const Pass& p : frame.passes)
    if (p.role == Role::Depth && p.image.channels() >= 1 && no_surface(p.image.at(x, y, 0))) return true;
  return false;
}

}  // namespace

FirstHitMap first_hit_map(const Frame& frame, const Roi& work_in, int nthreads) {
  const Pass* normal = frame.find(Role::Normal, Prefer::Geometry);
  const bool depth = std::any_of(frame.passes.begin(), frame.passes.end(), [](const Pass& p) { return p.role == Role::Depth; });
  const int w = frame.width, h = frame.height;
  const Roi work = work_in.clipped(w, h);
  if (!normal || normal->image.channels() < 3 || !depth || work.empty()) return {};
  FirstHitMap map;
  map.state.assign(std::size_t(w) * std::size_t(h), kFirstHitMissed);
  std::vector<std::size_t> rows(std::size_t(h), 0);
  const Roi around = work.grown(kFirstHitRadius, w, h);
  parallel_rows(around.y0, around.y1, nthreads, [&](int y) {
    for (int x = around.x0; x < around.x1; ++x) {
      unsigned char& s = map.state[std::size_t(y) * std::size_t(w) + std::size_t(x)];
      if (!first_missed(frame, x, y)) {
        s = kFirstHitMet;
        continue;
      }
      const float* n = normal->image.pixel(x, y);
      const float len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];  // 0: the sky, no sample met anything
      if (work.contains(x, y) && len2 > 1e-4f && std::isfinite(len2)) {
        s = kFirstHitHole;
        ++rows[std::size_t(y)];
      }
    }
  });
  map.holes = std::accumulate(rows.begin(), rows.end(), std::size_t(0));
  if (map.holes == 0) return {};
  return map;
}

std::size_t fill_first_hit_holes(Frame& frame, const FirstHitMap& map, int nthreads) {
  if (map.holes == 0) return 0;
  const int w = frame.width, h = frame.height;
  std::vector<Pass*> filled;
  for (Pass& p : frame.passes)
    if (p.role == Role::Position || p.role == Role::Depth) filled.push_back(&p);
  const auto met = [&](int x, int y) { return map.state[std::size_t(y) * std::size_t(w) + std::size_t(x)] == kFirstHitMet; };
  // A hole reads only pixels that met a surface, which are never written: no copy of the passes.
  std::vector<std::size_t> rows(std::size_t(h), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    std::vector<std::pair<int, int>> ring;
    for (int x = 0; x < w; ++x) {
      if (map.state[std::size_t(y) * std::size_t(w) + std::size_t(x)] != kFirstHitHole) continue;
      // The nearest square ring holding a pixel whose first sample met a surface.
      for (int r = 1; r <= kFirstHitRadius && ring.empty(); ++r)
        for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
          for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx)
            if (std::max(std::abs(xx - x), std::abs(yy - y)) == r && met(xx, yy)) ring.emplace_back(xx, yy);
      if (ring.empty()) continue;
      for (Pass* p : filled) {
        if (p->role == Role::Depth && !no_surface(p->image.at(x, y, 0))) continue;  // an averaged depth stays
        for (int c = 0; c < p->image.channels(); ++c) {
          double sum = 0.0;
          for (const auto& [xx, yy] : ring) sum += double(p->image.at(xx, yy, c));
          p->image.at(x, y, c) = float(sum / double(ring.size()));
        }
      }
      ring.clear();
      ++rows[std::size_t(y)];
    }
  });
  return std::accumulate(rows.begin(), rows.end(), std::size_t(0));
}

}  // namespace mcr
