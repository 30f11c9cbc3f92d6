#include "sparse/expanded_grid.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"

namespace mcr {

ExpandedGrid::ExpandedGrid(int width, int height, const ExpandedGridParams& p) : width_(width), height_(height) {
  if (!(p.density > 0 && p.density <= 1)) throw Error(Errc::ParameterOutOfRange, "density must be in (0, 1]");
  cx_ = p.gaze_x * width;
  cy_ = p.gaze_y * height;
  r0_ = std::max(0.0, p.fovea_radius) * std::hypot(double(width), double(height));
  // The farthest image corner from the gaze: the expanded grid must reach it.
  const double rmax = std::max({std::hypot(cx_, cy_), std::hypot(width - cx_, cy_), std::hypot(cx_, height - cy_),
                                std::hypot(width - cx_, height - cy_)}) + 1.0;
  r0_ = std::min(r0_, rmax);
  // Unexpanded radius giving the requested number of samples: bisection on the
  // exact count of grid points that land in the image (monotone in the radius).
  const double target = p.density * double(width) * height;
  double lo = r0_, hi = rmax;
  set_radius(hi, rmax);
  if (count() > target) {
    for (int i = 0; i < 40 && hi - lo > 0.01; ++i) {
      const double mid = 0.5 * (lo + hi);
      set_radius(mid, rmax);
      (double(count()) < target ? lo : hi) = mid;
    }
    set_radius(hi, rmax);
  }
}

void ExpandedGrid::set_radius(double ru, double rmax) {
  ru_ = ru;
  k_ = ru_ - r0_ > 1e-9 ? ((rmax - r0_) / (ru_ - r0_) - 1.0) / (ru_ - r0_) : 0.0;
}

std::size_t ExpandedGrid::count() const {
  const auto m = mask();
  return std::size_t(std::count(m.begin(), m.end(), std::uint8_t(1)));
}

double ExpandedGrid::expand(double d) const {
  if (d <= r0_) return d;
  const double t = d - r0_;
  return r0_ + t * (1.0 + k_ * t);
}

double ExpandedGrid::contract(double e) const {
  if (e <= r0_ || k_ == 0) return e;
  // Solve k t^2 + t - (e - r0) = 0 for t >= 0.
  const double s = e - r0_;
  return r0_ + (-1.0 + std::sqrt(1.0 + 4.0 * k_ * s)) / (2.0 * k_);
}

std::vector<std::uint8_t> ExpandedGrid::mask() const {
  std::vector<std::uint8_t> m(std::size_t(width_) * height_, 0);
  const int R = int(std::ceil(ru_));
  const int gx = int(std::floor(cx_)), gy = int(std::floor(cy_));
  for (int j = -R; j <= R; ++j)
    for (int i = -R; i <= R; ++i) {
      // Unexpanded grid points sit on the pixel centres around the gaze pixel.
      const double ux = gx + 0.5 + i - cx_, uy = gy + 0.5 + j - cy_;
      const double d = std::hypot(ux, uy);
      if (d > ru_) continue;
      const double scale = d > 0 ? expand(d) / d : 1.0;
      const int x = int(std::floor(cx_ + ux * scale)), y = int(std::floor(cy_ + uy * scale));
      if (x >= 0 && y >= 0 && x < width_ && y < height_) m[std::size_t(y) * width_ + x] = 1;
    }
  return m;
}

Frame sparsify(const Frame& frame, const std::vector<std::uint8_t>& mask) {
  if (mask.size() != std::size_t(frame.width) * frame.height)
    throw Error(Errc::SizeMismatch, "sparsify: mask does not match the frame");
  Frame out = frame;
  out.passes.erase(std::remove_if(out.passes.begin(), out.passes.end(),
                                  [](const Pass& p) { return p.role == Role::SampleCount; }),
                   out.passes.end());
  for (auto* list : {&out.passes, &out.extra})
    for (Pass& p : *list) {
      if (p.role == Role::Alpha && list == &out.passes) continue;  // coverage is not a sample
      const int nc = p.image.channels();
      for (std::size_t i = 0; i < mask.size(); ++i)
        if (!mask[i]) std::fill(p.image.data() + i * nc, p.image.data() + (i + 1) * nc, 0.0f);
    }
  Pass count;
  count.role = Role::SampleCount;
  count.name = "sample_count";
  count.source = "sparsify";
  count.channels = {"sample_count.X"};
  count.image = Image(frame.width, frame.height, 1);
  for (std::size_t i = 0; i < mask.size(); ++i) count.image.data()[i] = mask[i] ? 1.0f : 0.0f;
  out.passes.push_back(std::move(count));
  return out;
}

}  // namespace mcr
