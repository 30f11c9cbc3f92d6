#include "prepare/pull_push.h"

#include <algorithm>
#include <cmath>

#include "util/parallel.h"

namespace mcr {

namespace {

struct Level {
  Image value;               // premultiplied by nothing: plain weighted mean
  std::vector<float> weight; // in [0,1]
};

}  // namespace

void pull_push_fill(Image& image, const std::vector<float>& weights, int nthreads) {
  const int nc = image.channels();
  std::vector<Level> levels(1);
  levels[0].value = image;
  levels[0].weight = weights;
  for (std::size_t i = 0; i < image.pixel_count(); ++i) {
    const float* p = image.data() + i * nc;
    bool finite = true;
    for (int c = 0; c < nc; ++c) finite = finite && std::isfinite(p[c]);
    float& w = levels[0].weight[i];
    w = finite ? std::clamp(w, 0.0f, 1.0f) : 0.0f;
    if (w == 0.0f) std::fill(levels[0].value.data() + i * nc, levels[0].value.data() + (i + 1) * nc, 0.0f);
  }
  // Pull: 2x2 weighted means; a coarse weight saturates at 1 once any full sample is below.
  while (levels.back().value.width() > 1 || levels.back().value.height() > 1) {
    const Level& f = levels.back();
    const int fw = f.value.width(), fh = f.value.height();
    const int cw = (fw + 1) / 2, ch = (fh + 1) / 2;
    Level c{Image(cw, ch, nc), std::vector<float>(std::size_t(cw) * ch, 0.0f)};
    parallel_rows(0, ch, nthreads, [&](int y) {
      std::vector<double> sum(static_cast<std::size_t>(nc));
      for (int x = 0; x < cw; ++x) {
        std::fill(sum.begin(), sum.end(), 0.0);
        double wsum = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int fx = 2 * x + dx, fy = 2 * y + dy;
            if (fx >= fw || fy >= fh) continue;
            const float w = f.weight[std::size_t(fy) * fw + fx];
            if (w <= 0) continue;
            wsum += w;
            for (int k = 0; k < nc; ++k) sum[std::size_t(k)] += double(w) * f.value.at(fx, fy, k);
          }
        c.weight[std::size_t(y) * cw + x] = float(std::min(1.0, wsum));
        for (int k = 0; k < nc; ++k) c.value.at(x, y, k) = wsum > 0 ? float(sum[std::size_t(k)] / wsum) : 0.0f;
      }
    });
    levels.push_back(std::move(c));
  }
  // Push: each level blends its own estimate with the bilinear upsampling of the coarser one.
  for (int l = int(levels.size()) - 2; l >= 0; --l) {
    Level& f = levels[std::size_t(l)];
    const Level& c = levels[std::size_t(l) + 1];
    const int fw = f.value.width(), fh = f.value.height(), cw = c.value.width(), chh = c.value.height();
    parallel_rows(0, fh, nthreads, [&](int y) {
      const float cy = std::clamp((y + 0.5f) * 0.5f - 0.5f, 0.0f, float(chh - 1));
      const int y0 = int(cy), y1 = std::min(y0 + 1, chh - 1);
      const float ty = cy - y0;
      for (int x = 0; x < fw; ++x) {
        const float cx = std::clamp((x + 0.5f) * 0.5f - 0.5f, 0.0f, float(cw - 1));
        const int x0 = int(cx), x1 = std::min(x0 + 1, cw - 1);
        const float tx = cx - x0;
        float& w = f.weight[std::size_t(y) * fw + x];
        for (int k = 0; k < nc; ++k) {
          const float up = (1 - ty) * ((1 - tx) * c.value.at(x0, y0, k) + tx * c.value.at(x1, y0, k)) +
                           ty * ((1 - tx) * c.value.at(x0, y1, k) + tx * c.value.at(x1, y1, k));
          float& v = f.value.at(x, y, k);
          v = w * v + (1 - w) * up;
        }
        w = 1.0f;
      }
    });
  }
  image = std::move(levels[0].value);
}

}  // namespace mcr
