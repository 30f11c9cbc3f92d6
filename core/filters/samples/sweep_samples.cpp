#include "filters/samples/sweep_samples.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "util/error.h"

namespace mcr::sweep {

double Camera::coc(double z, int width_px) const {
  const double aperture = lens_mm * 1e-3 / fstop;
  const double defocus = std::isinf(z) ? 1.0 / focus_distance : std::fabs(z - focus_distance) / (z * focus_distance);
  return aperture * defocus * (lens_mm / sensor_width_mm) * width_px;
}

void Camera::fill_from(const DeepSamples& deep, const std::string& path) {
  struct Field {
    double* value;
    const char* name;
  } fields[] = {{&lens_mm, "mcrecon:lens_mm"},
                {&fstop, "mcrecon:fstop"},
                {&focus_distance, "mcrecon:focus_distance"},
                {&sensor_width_mm, "mcrecon:sensor_width_mm"}};
  for (const Field& f : fields) {
    if (*f.value > 0) continue;
    auto it = deep.attributes.find(f.name);
    if (it == deep.attributes.end()) continue;
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end == it->second.c_str() || *end != '\0' || !(v > 0) || !std::isfinite(v))
      throw Error(Errc::BadParameterValue, "'" + path + "': header attribute " + f.name + " is '" + it->second +
                                               "', not a positive number");
    *f.value = v;
  }
}

bool clamp_to_pixel(const SampleSet& set, int x, int y, double k, float out[3]) {
  const std::size_t p = std::size_t(y) * std::size_t(set.width) + std::size_t(x);
  const std::uint64_t a = set.offsets[p], b = set.offsets[p + 1];
  if (b - a < 2 || !(k > 0)) return false;
  double sq = 0, sq2 = 0, m[3] = {0, 0, 0};
  for (std::uint64_t i = a; i < b; ++i) {
    const StoredSample& s = set.samples[std::size_t(i)];
    sq += s.q;
    sq2 += double(s.q) * s.q;
    for (int c = 0; c < 3; ++c) m[c] += double(s.q) * s.rgb[c];
  }
  if (!(sq > 0)) return false;
  for (double& v : m) v /= sq;
  const double n = double(b - a);
  bool moved = false;
  for (int c = 0; c < 3; ++c) {
    double var = 0;
    for (std::uint64_t i = a; i < b; ++i) {
      const StoredSample& s = set.samples[std::size_t(i)];
      const double d = s.rgb[c] - m[c];
      var += double(s.q) * s.q * d * d;
    }
    // Variance of the weighted mean, with the n/(n-1) correction for the estimated mean.
    const double se = std::sqrt(var / (sq * sq) * n / (n - 1));
    const double lo = m[c] - std::sqrt(k) * se, hi = m[c] + std::sqrt(k) * se;
    const float before = out[c];
    out[c] = float(std::clamp(double(out[c]), lo, hi));
    moved = moved || out[c] != before;
  }
  (void)sq2;
  return moved;
}

bool is_background(float z) { return !(z > 0) || !(z < 1e9f); }

namespace {

int need(const DeepSamples& deep, const char* name, const std::string& path, const std::string& why) {
  const int c = deep.channel(name);
  if (c < 0)
    throw Error(Errc::MissingPass, "filter 'sweep' needs the per-sample channel '" + std::string(name) + "'" +
                                       (why.empty() ? "" : " (" + why + ")") + ", absent in '" + path + "'");
  return c;
}

// Sample k of n in a pixel, when the file gives no position: the R2 sequence (evenly spread,
// deterministic).
inline float spread(int k, double a) {
  const double v = 0.5 + a * k;
  return float(v - std::floor(v));
}

}  // namespace

SampleSet gather(const DeepSamples& deep, Diameter dsrc, const Camera& cam, const std::string& path) {
  const int cr = need(deep, "R", path, ""), cg = need(deep, "G", path, ""), cb = need(deep, "B", path, "");
  const int cz = need(deep, "Z", path, "");
  const int ca = deep.channel("A"), cdx = deep.channel("dx"), cdy = deep.channel("dy");
  int cblur = -1, cmx = -1, cmy = -1;
  if (dsrc == Diameter::Blur) cblur = need(deep, "blur", path, "diameter=blur");
  if (dsrc == Diameter::Motion || dsrc == Diameter::CocMotion) {
    cmx = need(deep, "mx", path, "motion length for the diameter");
    cmy = need(deep, "my", path, "motion length for the diameter");
  }
  if ((dsrc == Diameter::Coc || dsrc == Diameter::CocMotion) && !cam.known())
    throw Error(Errc::MissingPass, "filter 'sweep' needs the camera for the circle of confusion: lens_mm, fstop, "
                                   "focus_distance, sensor_width_mm (parameters, or mcrecon:* attributes), absent in '" +
                                       path + "'");
  const auto& V = deep.values;
  SampleSet set;
  set.width = deep.width;
  set.height = deep.height;
  const std::size_t np = std::size_t(deep.width) * std::size_t(deep.height);
  set.offsets.assign(np + 1, 0);
  set.samples.reserve(deep.total_samples());
  const double coc_inf = dsrc == Diameter::Coc || dsrc == Diameter::CocMotion ? cam.coc(std::numeric_limits<double>::infinity(), deep.width) : 1.0;
  for (std::size_t p = 0; p < np; ++p) {
    const int px = int(p % std::size_t(deep.width)), py = int(p / std::size_t(deep.width));
    const std::uint64_t first = deep.offsets[p], n = deep.offsets[p + 1] - first;
    const std::size_t start = set.samples.size();
    for (std::uint64_t k = 0; k < n; ++k) {
      const std::uint64_t i = first + k;
      StoredSample s;
      s.rgb[0] = V[std::size_t(cr)][i];
      s.rgb[1] = V[std::size_t(cg)][i];
      s.rgb[2] = V[std::size_t(cb)][i];
      const float a = ca >= 0 ? V[std::size_t(ca)][i] : 1.0f;
      if (!(std::isfinite(s.rgb[0]) && std::isfinite(s.rgb[1]) && std::isfinite(s.rgb[2])) || !(a > 0) ||
          !std::isfinite(a)) {
        ++set.dropped;
        continue;
      }
      float dx = cdx >= 0 ? V[std::size_t(cdx)][i] : spread(int(k), 0.7548776662466927);
      float dy = cdy >= 0 ? V[std::size_t(cdy)][i] : spread(int(k), 0.5698402909980532);
      if (!(dx >= 0 && dx < 1)) dx = std::isfinite(dx) ? dx - std::floor(dx) : 0.5f;
      if (!(dy >= 0 && dy < 1)) dy = std::isfinite(dy) ? dy - std::floor(dy) : 0.5f;
      s.x = float(px) + dx;
      s.y = float(py) + dy;
      const float z = V[std::size_t(cz)][i];
      const bool bg = is_background(z);
      set.background += bg;
      s.z = bg ? std::numeric_limits<float>::infinity() : z;
      double d = 1.0;
      switch (dsrc) {
        case Diameter::One: break;
        case Diameter::Blur: d = V[std::size_t(cblur)][i]; break;
        case Diameter::Coc: d = bg ? coc_inf : cam.coc(z, deep.width); break;
        case Diameter::Motion:
        case Diameter::CocMotion: {
          const double mx = V[std::size_t(cmx)][i], my = V[std::size_t(cmy)][i];
          const double m = std::isfinite(mx) && std::isfinite(my) ? std::hypot(mx, my) : 0.0;
          d = dsrc == Diameter::Motion ? m : std::max(m, bg ? coc_inf : cam.coc(z, deep.width));
          break;
        }
      }
      s.d = std::isfinite(d) ? float(std::min(d, 1e6)) : 1.0f;
      s.q = a;
      set.samples.push_back(s);
    }
    // q = coverage / samples kept in this pixel: one pixel's weights at one scale sum to 1.
    const std::size_t kept = set.samples.size() - start;
    for (std::size_t j = start; j < set.samples.size(); ++j) set.samples[j].q /= float(kept);
    set.offsets[p + 1] = set.samples.size();
  }
  return set;
}

}  // namespace mcr::sweep
