#include "report/scaling.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <memory>

#include "image/deep.h"
#include "image/lightfield.h"
#include "util/error.h"
#include "util/memory_usage.h"

namespace mcr {

namespace {

// The source coordinate of a mirrored tiling: 0..n-1, then n-1..0, then 0.. again.
int mirror(int x, int n) {
  const int period = 2 * n, m = x % period;
  return m < n ? m : period - 1 - m;
}

Image tile_image(const Image& src, int width, int height) {
  Image out(width, height, src.channels());
  const std::size_t bytes = sizeof(float) * std::size_t(src.channels());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      std::memcpy(out.pixel(x, y), src.pixel(mirror(x, src.width()), mirror(y, src.height())), bytes);
  return out;
}

std::shared_ptr<const DeepSamples> tile_deep(const DeepSamples& src, int width, int height) {
  auto out = std::make_shared<DeepSamples>();
  out->width = width;
  out->height = height;
  out->channel_names = src.channel_names;
  out->attributes = src.attributes;
  out->offsets.assign(std::size_t(width) * std::size_t(height) + 1, 0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(width) + std::size_t(x);
      out->offsets[p + 1] = out->offsets[p] + src.samples(mirror(x, src.width), mirror(y, src.height));
    }
  out->values.assign(src.values.size(), std::vector<float>(out->total_samples()));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(width) + std::size_t(x);
      const std::uint64_t from = src.first(mirror(x, src.width), mirror(y, src.height));
      for (std::size_t c = 0; c < src.values.size(); ++c)
        std::copy_n(src.values[c].begin() + std::ptrdiff_t(from), out->offsets[p + 1] - out->offsets[p],
                    out->values[c].begin() + std::ptrdiff_t(out->offsets[p]));
    }
  return out;
}

// Per-pixel arrays of n values each, tiled.
void tile_array(const std::vector<float>& src, std::vector<float>& dst, int sw, int sh, int width, int height,
                std::size_t n) {
  if (src.empty()) {
    dst.clear();
    return;
  }
  dst.resize(std::size_t(width) * std::size_t(height) * n);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t s = (std::size_t(mirror(y, sh)) * std::size_t(sw) + std::size_t(mirror(x, sw))) * n;
      std::copy_n(src.begin() + std::ptrdiff_t(s), n,
                  dst.begin() + std::ptrdiff_t((std::size_t(y) * std::size_t(width) + std::size_t(x)) * n));
    }
}

std::shared_ptr<const LightField> tile_lightfield(const LightField& src, int width, int height) {
  auto out = std::make_shared<LightField>();
  LightField& lf = *out;
  lf.effect = src.effect;
  lf.width = width;
  lf.height = height;
  lf.l = src.l;
  lf.y_range = src.y_range;
  lf.sigma_y = src.sigma_y;
  const int sw = src.width, sh = src.height;
  const std::size_t spp = std::size_t(src.spp());
  for (auto [from, to] : {std::pair{&src.r, &lf.r}, {&src.g, &lf.g}, {&src.b, &lf.b}, {&src.y1, &lf.y1}, {&src.y2, &lf.y2}})
    tile_array(*from, *to, sw, sh, width, height, spp);
  for (auto [from, to] : {std::pair{&src.smin, &lf.smin}, {&src.smax, &lf.smax}, {&src.e1x, &lf.e1x},
                          {&src.e1y, &lf.e1y}, {&src.e2x, &lf.e2x}, {&src.e2y, &lf.e2y}, {&src.depth, &lf.depth},
                          {&src.px, &lf.px}, {&src.py, &lf.py}, {&src.pz, &lf.pz}, {&src.nx, &lf.nx},
                          {&src.ny, &lf.ny}, {&src.nz, &lf.nz}, {&src.w1x, &lf.w1x}, {&src.w1y, &lf.w1y},
                          {&src.w1z, &lf.w1z}, {&src.w2x, &lf.w2x}, {&src.w2y, &lf.w2y}, {&src.w2z, &lf.w2z},
                          {&src.mod_r, &lf.mod_r}, {&src.mod_g, &lf.mod_g}, {&src.mod_b, &lf.mod_b}})
    tile_array(*from, *to, sw, sh, width, height, 1);
  return out;
}

}  // namespace

Frame mirrored_tiling(const Frame& src, int width, int height) {
  Frame out = src.header(width, height);
  out.path += " (tiled to " + std::to_string(width) + "x" + std::to_string(height) + ")";
  for (const Pass& p : src.passes) out.passes.push_back(with_pixels(p, tile_image(p.image, width, height)));
  if (src.lightfield) {
    // The light-field filters read the decoded light field; the deep buffer only says what the
    // file was (its attributes), so it is not copied sample by sample.
    out.lightfield = tile_lightfield(*src.lightfield, width, height);
    auto stub = std::make_shared<DeepSamples>();
    stub->width = width;
    stub->height = height;
    stub->channel_names = src.deep->channel_names;
    stub->attributes = src.deep->attributes;
    out.deep = stub;
  } else if (src.deep) {
    out.deep = tile_deep(*src.deep, width, height);
  }
  return out;
}

ScalingFit fit_scaling(const std::vector<ScalingRow>& rows) {
  ScalingFit fit;
  if (rows.empty()) return fit;
  fit.filter = rows.front().filter;
  fit.input = rows.front().input;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  const ScalingRow* largest = &rows.front();
  for (const ScalingRow& r : rows) {
    const double px = double(r.width) * r.height;
    if (px > double(largest->width) * largest->height) largest = &r;
    if (r.seconds <= 0) continue;
    const double x = std::log(px), y = std::log(r.seconds);
    sx += x; sy += y; sxx += x * x; sxy += x * y;
    ++n;
  }
  if (n >= 2 && n * sxx - sx * sx > 0) fit.slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double mp = double(largest->width) * largest->height / 1e6;
  fit.seconds_per_megapixel = largest->seconds / mp;
  if (largest->peak_memory_mb >= 0) fit.peak_memory_mb_per_megapixel = largest->peak_memory_mb / mp;
  return fit;
}

std::vector<ScalingRow> measure_scaling(Filter& filter, const Frame& src, const std::string& input,
                                        const std::vector<int>& sizes, int nthreads, int repeat,
                                        const std::function<void(const std::string&)>& progress) {
  std::vector<ScalingRow> rows;
  ExecOptions exec;
  exec.nthreads = nthreads;
  for (int size : sizes) {
    ScalingRow row{filter.info().name, input, size, size, 0, -1};
    {
      const Frame big = mirrored_tiling(src, size, size);
      for (int k = 0; k < std::max(1, repeat); ++k) {
        filter.reset();
        const bool peak_reset = reset_peak_resident();
        const double before = resident_mb();
        const auto t0 = std::chrono::steady_clock::now();
        Image out = filter.execute(big, exec);
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const double peak = peak_reset ? peak_resident_mb() - before : -1;
        if (k == 0 || s < row.seconds) row.seconds = s;
        if (peak_reset) row.peak_memory_mb = std::max(row.peak_memory_mb, peak);
      }
    }
    rows.push_back(row);
    if (progress) {
      char line[160];
      std::snprintf(line, sizeof line, "scaling %s %dx%d: %.3f s, %.0f MB", row.filter.c_str(), size, size, row.seconds,
                    row.peak_memory_mb);
      progress(line);
    }
  }
  return rows;
}

}  // namespace mcr
