#include "prepare/exposure.h"

#include <algorithm>
#include <cmath>

#include "util/parallel.h"

namespace mcr {

namespace {

constexpr double kMaxFloat = 3.402823466e38;
constexpr double kRangeExp = 120.0;  // within float's normal range (2^-126 .. 2^128) with room

float clamped(double v) { return float(std::min(std::max(v, -kMaxFloat), kMaxFloat)); }

// Every value of rows [0, h) times k, non-finite ones kept (a finite k times inf is inf; NaN
// stays NaN): the filter's own non-finite policy then sees what it would have.
void scale_channels(Image& im, int channels, double k, int nthreads) {
  const int ch = im.channels(), n = std::min(channels, ch);
  parallel_rows(0, im.height(), nthreads, [&](int y) {
    float* p = im.pixel(0, y);
    for (int x = 0; x < im.width(); ++x, p += ch)
      for (int c = 0; c < n; ++c)
        if (std::isfinite(p[c])) p[c] = clamped(double(p[c]) * k);
  });
}

}  // namespace

void ExposureLevel::add(const Image& colour, const Roi& rows_in, int nthreads) {
  const Roi rows = rows_in.clipped(colour.width(), colour.height());
  if (rows.empty() || colour.channels() < 3) return;
  struct Row {
    double sum = 0, count = 0, least = kMaxFloat, most = 0;
  };
  std::vector<Row> row(std::size_t(rows.height()));
  parallel_rows(rows.y0, rows.y1, nthreads, [&](int y) {
    Row r;
    for (int x = rows.x0; x < rows.x1; ++x) {
      const float* p = colour.pixel(x, y);
      if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) continue;
      const double a[3] = {std::fabs(double(p[0])), std::fabs(double(p[1])), std::fabs(double(p[2]))};
      r.sum += 0.2126 * a[0] + 0.7152 * a[1] + 0.0722 * a[2];
      r.count += 1;
      for (double v : a) {
        if (v > 0) r.least = std::min(r.least, v);
        r.most = std::max(r.most, v);
      }
    }
    row[std::size_t(y - rows.y0)] = r;
  });
  for (const Row& r : row) {
    sum += r.sum;
    count += r.count;
    least = std::min(least, r.least);
    most = std::max(most, r.most);
  }
}

double exposure_scale(const ExposureLevel& e) {
  const double level = e.level();
  if (!(level > 0) || !std::isfinite(level)) return 1.0;
  // A power of two: scaling and scaling back are exact (a kept input comes back bit for bit).
  int m = 0;
  if (level < kExposureLow) m = int(std::ceil(std::log2(kExposureLow / level)));
  if (level > kExposureHigh) m = -int(std::ceil(std::log2(level / kExposureHigh)));
  // Every finite value stays within [2^-kRangeExp, 2^kRangeExp] (or where it was): a frame
  // that spans the float range (1e-30 beside 1e30) is not pushed out of it.
  if (m > 0 && e.most > 0) m = std::max(0, std::min(m, int(std::floor(kRangeExp - std::log2(e.most)))));
  if (m < 0 && e.least < kMaxFloat) m = std::min(0, std::max(m, int(std::ceil(-kRangeExp - std::log2(e.least)))));
  return std::ldexp(1.0, m);
}

bool scales_with_exposure(Role r) {
  switch (r) {
    case Role::Colour:
    case Role::Variance:
    case Role::DiffuseDirect:
    case Role::DiffuseIndirect:
    case Role::GlossyDirect:
    case Role::GlossyIndirect:
    case Role::TransmissionDirect:
    case Role::TransmissionIndirect:
    case Role::Emission:
    case Role::Environment:
      return true;
    default:
      return false;
  }
}

void scale_exposure(Frame& frame, double k, int nthreads) {
  if (k == 1.0) return;
  for (Pass& p : frame.passes) {
    if (!scales_with_exposure(p.role)) continue;
    if (p.role == Role::Variance)
      scale_channels(p.image, 3, k * k, nthreads);
    else
      scale_channels(p.image, 3, k, nthreads);  // RGB: the colour's alpha is coverage, not light
  }
}

void unscale_exposure(Image& rgb, const Roi& roi_in, double k, int nthreads) {
  const Roi roi = roi_in.clipped(rgb.width(), rgb.height());
  if (k == 1.0 || roi.empty()) return;
  const double inv = 1.0 / k;
  const int ch = rgb.channels(), n = std::min(3, ch);
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    float* p = rgb.pixel(roi.x0, y);
    for (int x = roi.x0; x < roi.x1; ++x, p += ch)
      for (int c = 0; c < n; ++c)
        if (std::isfinite(p[c])) p[c] = clamped(double(p[c]) * inv);
  });
}

ParamSpec exposure_param() {
  return ParamSpec::Enum("exposure", "auto", {"auto", "off"},
                         "auto = a render whose mean luminance lies outside [0.18, 1] (the exposure the filters' "
                         "constants were set at: the sample scenes lie at 0.20-0.56) is filtered scaled into it by a "
                         "power of two and its result scaled back, so a render 1/100 as bright is filtered as it would "
                         "be at 0.18-0.36 (a render inside the band is filtered as it is); off = as it is");
}

}  // namespace mcr
