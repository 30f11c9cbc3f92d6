#include "report/report_math.h"

#include <cmath>

namespace mcr {

double worth_x_samples(const std::vector<std::pair<int, double>>& levels, int input_spp, double relmse) {
  if (levels.empty() || input_spp <= 0 || !(relmse > 0) || !std::isfinite(relmse)) return -1;
  if (levels.size() == 1) return levels[0].second / relmse * levels[0].first / input_spp;
  const double y = std::log(relmse);
  std::size_t i = 0;  // the segment: the first whose far end is at or below relmse, else the last
  while (i + 2 < levels.size() && std::log(levels[i + 1].second) > y) ++i;
  const double x0 = std::log(double(levels[i].first)), x1 = std::log(double(levels[i + 1].first));
  const double y0 = std::log(levels[i].second), y1 = std::log(levels[i + 1].second);
  if (!(y1 < y0)) return -1;
  return std::exp(x0 + (y - y0) * (x1 - x0) / (y1 - y0)) / input_spp;
}

std::vector<bool> pareto_front(const std::vector<std::pair<double, double>>& points, bool lower_is_better) {
  std::vector<bool> front(points.size(), true);
  for (std::size_t a = 0; a < points.size(); ++a)
    for (std::size_t b = 0; b < points.size() && front[a]; ++b) {
      if (a == b) continue;
      const double ta = points[a].first, tb = points[b].first;
      const double ea = lower_is_better ? points[a].second : -points[a].second;
      const double eb = lower_is_better ? points[b].second : -points[b].second;
      if (tb <= ta && eb <= ea && (tb < ta || eb < ea)) front[a] = false;
    }
  return front;
}

}  // namespace mcr
