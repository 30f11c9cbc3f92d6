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

std::vector<unsigned char> first_hit_holes(const Frame& frame, const Roi& work_in, int nthreads) {
  const Pass* normal = frame.find(Role::Normal, Prefer::Geometry);
  const bool depth = std::any_of(frame.passes.begin(), frame.passes.end(), [](const Pass& p) { return p.role == Role::Depth; });
  const Roi work = work_in.clipped(frame.width, frame.height);
  if (!normal || normal->image.channels() < 3 || !depth || work.empty()) return {};
  const int w = frame.width;
  std::vector<unsigned char> holes(std::size_t(w) * std::size_t(frame.height), 0);
  std::vector<std::size_t> rows(std::size_t(frame.height), 0);
  parallel_rows(work.y0, work.y1, nthreads, [&](int y) {
    for (int x = work.x0; x < work.x1; ++x) {
      const float* n = normal->image.pixel(x, y);
      const float len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
      if (len2 > 1e-4f && std::isfinite(len2) && first_missed(frame, x, y)) {
        holes[std::size_t(y) * std::size_t(w) + std::size_t(x)] = 1;
        ++rows[std::size_t(y)];
      }
    }
  });
  if (std::accumulate(rows.begin(), rows.end(), std::size_t(0)) == 0) return {};
  return holes;
}

std::size_t fill_first_hit_holes(Frame& frame, const std::vector<unsigned char>& holes, const Roi& work_in,
                                 int nthreads) {
  if (holes.empty()) return 0;
  const int w = frame.width, h = frame.height;
  const Roi work = work_in.clipped(w, h);
  // Which pixels met a surface first, read before any is filled (the fill reads the input only).
  std::vector<unsigned char> met(std::size_t(w) * std::size_t(h), 0);
  const Roi around = work.grown(kFirstHitRadius, w, h);
  parallel_rows(around.y0, around.y1, nthreads, [&](int y) {
    for (int x = around.x0; x < around.x1; ++x) met[std::size_t(y) * std::size_t(w) + std::size_t(x)] = !first_missed(frame, x, y);
  });
  std::vector<Pass*> filled;
  for (Pass& p : frame.passes)
    if (p.role == Role::Position || p.role == Role::Depth) filled.push_back(&p);
  std::vector<Image> source;  // the passes as read
  for (const Pass* p : filled) source.push_back(p->image);
  std::vector<std::size_t> rows(std::size_t(h), 0);
  parallel_rows(work.y0, work.y1, nthreads, [&](int y) {
    for (int x = work.x0; x < work.x1; ++x) {
      if (!holes[std::size_t(y) * std::size_t(w) + std::size_t(x)]) continue;
      // The nearest square ring holding a pixel whose first sample met a surface.
      for (int r = 1; r <= kFirstHitRadius; ++r) {
        int count = 0;
        const int x0 = std::max(0, x - r), x1 = std::min(w - 1, x + r), y0 = std::max(0, y - r), y1 = std::min(h - 1, y + r);
        for (int yy = y0; yy <= y1; ++yy)
          for (int xx = x0; xx <= x1; ++xx)
            count += (std::max(std::abs(xx - x), std::abs(yy - y)) == r) && met[std::size_t(yy) * std::size_t(w) + std::size_t(xx)];
        if (count == 0) continue;
        for (std::size_t k = 0; k < filled.size(); ++k) {
          const Image& s = source[k];
          for (int c = 0; c < s.channels(); ++c) {
            double sum = 0.0;
            for (int yy = y0; yy <= y1; ++yy)
              for (int xx = x0; xx <= x1; ++xx)
                if (std::max(std::abs(xx - x), std::abs(yy - y)) == r && met[std::size_t(yy) * std::size_t(w) + std::size_t(xx)])
                  sum += double(s.at(xx, yy, c));
            if (filled[k]->role == Role::Position || no_surface(s.at(x, y, 0)))  // an averaged depth stays
              filled[k]->image.at(x, y, c) = float(sum / count);
          }
        }
        ++rows[std::size_t(y)];
        break;
      }
    }
  });
  return std::accumulate(rows.begin(), rows.end(), std::size_t(0));
}

}  // namespace mcr
