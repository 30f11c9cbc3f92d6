// The converged image of a scene: per pixel the weighted mean of many stratified samples
// (Gaussian light / aperture weights; plain mean for gi), pixel by pixel so that a 32x32
// reference never holds more than one pixel's samples.
#include <atomic>
#include <mutex>

#include "generator.h"
#include "util/parallel.h"

namespace mcr::lfgen {

std::vector<float> render_reference(const LightFieldGenerator& gen, int l, unsigned long long seed, int nthreads,
                                    const RowProgress& progress) {
  check_samples_per_axis(l);
  const int w = gen.width(), h = gen.height();
  std::vector<float> rgb(std::size_t(w) * std::size_t(h) * 3, 0.f);
  std::atomic<int> rows{0};
  std::mutex report;
  parallel_rows(0, h, nthreads, [&](int y) {
    PixelSamples ps;
    for (int x = 0; x < w; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
      double j1 = 0, j2 = 0;
      pixel_jitter(seed, 1, p, j1, j2);  // salt 1: not the jitter of the noisy samples
      ps.reset(l * l);
      gen.render_pixel(x, y, l, j1, j2, ps);
      Vec3 sum;
      double wsum = 0;
      for (std::size_t k = 0; k < ps.value.size(); ++k) {
        const double wk = gen.sample_weight(ps, k);
        sum += ps.value[k] * wk;
        wsum += wk;
      }
      const Vec3 mean = wsum > 0 ? sum / wsum : Vec3();
      rgb[3 * p] = float(mean.x);
      rgb[3 * p + 1] = float(mean.y);
      rgb[3 * p + 2] = float(mean.z);
    }
    const int done = ++rows;
    if (progress) {
      const std::lock_guard<std::mutex> hold(report);
      progress(done);
    }
  });
  return rgb;
}

}  // namespace mcr::lfgen
