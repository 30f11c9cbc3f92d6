#include "image/lightfield.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "util/error.h"

namespace mcr {

namespace {
const char* const kCombined = "soft_shadows+dof";
}  // namespace

const char* effect_name(LightFieldEffect e) {
  switch (e) {
    case LightFieldEffect::SoftShadows: return "soft_shadows";
    case LightFieldEffect::Dof: return "dof";
    case LightFieldEffect::Gi: return "gi";
  }
  return "?";
}

void LightField::resize(int w, int h, int l_, bool geometry) {
  width = w;
  height = h;
  l = l_;
  const std::size_t n = samples(), p = pixels();
  for (auto* v : {&r, &g, &b, &y1, &y2}) v->assign(n, 0.f);
  for (auto* v : {&smin, &smax, &e1x, &e1y, &e2x, &e2y, &depth}) v->assign(p, 0.f);
  for (auto* v : {&px, &py, &pz, &nx, &ny, &nz, &w1x, &w1y, &w1z, &w2x, &w2y, &w2z}) v->assign(geometry ? p : 0, 0.f);
}

std::string lightfield_kind(const LightField& lf) {
  return lf.combined() ? std::string(kCombined) : std::string(effect_name(lf.effect));
}

bool is_lightfield(const DeepSamples& deep) { return deep.attributes.count("mcrecon:lightfield") != 0; }

float lightfield_y_weight(LightFieldEffect effect, float sigma_y, float y_range, float y) {
  if (effect == LightFieldEffect::Gi) return std::fabs(y) <= y_range ? 1.f : 0.f;
  return std::exp(-0.5f * (y / sigma_y) * (y / sigma_y));
}

float lightfield_sample_weight(const LightField& lf, std::size_t k) {
  const float w = lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y1[k]) *
                  lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y2[k]);
  return lf.combined() ? w * lightfield_sample_weight(*lf.lens, k) : w;
}

namespace {

const char* const kSampleChannels[] = {"R", "G", "B", "lf.y1", "lf.y2"};
const char* const kPixelChannels[] = {"lf.smin", "lf.smax", "lf.e1x", "lf.e1y", "lf.e2x", "lf.e2y", "Z"};
const char* const kGeometryChannels[] = {"P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z"};
const char* const kAxisChannels[] = {"lf.w1x", "lf.w1y", "lf.w1z", "lf.w2x", "lf.w2y", "lf.w2z"};
const char* const kModChannels[] = {"lf.modR", "lf.modG", "lf.modB"};
const char* const kLensSampleChannels[] = {"lf.kR", "lf.kG", "lf.kB", "lf.u1", "lf.u2"};
const char* const kLensPixelChannels[] = {"lf.dmin", "lf.dmax"};

std::string at(int x, int y) { return "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")"; }

const std::string& attribute(const DeepSamples& deep, const std::string& name, const std::string& path) {
  auto it = deep.attributes.find(name);
  if (it == deep.attributes.end())
    throw Error(Errc::MissingPass, "'" + path + "': light-field header attribute '" + name +
                                       "' is missing (README: the light-field convention)");
  return it->second;
}

double number(const DeepSamples& deep, const std::string& name, const std::string& path, double lo, double hi) {
  const std::string& text = attribute(deep, name, path);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream os;
    os << "'" << path << "': light-field attribute " << name << " = '" << text << "' is not a number in [" << lo
       << ", " << hi << "]";
    throw Error(Errc::ReadFailed, os.str());
  }
  return v;
}

LightFieldEffect parse_effect(const DeepSamples& deep, const std::string& path, bool* combined) {
  const std::string& e = attribute(deep, "mcrecon:lightfield", path);
  *combined = e == kCombined;
  if (*combined) return LightFieldEffect::SoftShadows;
  for (LightFieldEffect k : {LightFieldEffect::SoftShadows, LightFieldEffect::Dof, LightFieldEffect::Gi})
    if (e == effect_name(k)) return k;
  throw Error(Errc::ReadFailed, "'" + path + "': mcrecon:lightfield = '" + e + "' is not an effect (soft_shadows, dof, gi, " +
                                    kCombined + ")");
}

int require_channel(const DeepSamples& deep, const char* name, const std::string& path, const char* what) {
  const int c = deep.channel(name);
  if (c < 0)
    throw Error(Errc::MissingPass, "'" + path + "': light field lacks the per-sample channel '" + name + "' (" +
                                       what + "; README: the light-field convention)");
  return c;
}

const char* channel_meaning(const std::string& name) {
  if (name == "lf.y1" || name == "lf.y2") return "the sample's coordinate on the light, lens or v-plane";
  if (name == "lf.u1" || name == "lf.u2") return "the sample's coordinate on the lens";
  if (name == "lf.kR" || name == "lf.kG" || name == "lf.kB") return "the texture at the sample's hit";
  if (name == "lf.smin" || name == "lf.smax") return "the pixel's slope bounds";
  if (name == "lf.dmin" || name == "lf.dmax") return "the pixel's lens slope bounds";
  if (name.rfind("lf.e", 0) == 0) return "the screen axes of the pixel's filter";
  if (name == "Z") return "the receiver's depth";
  return "the sample's value";
}

// Channel c's l*l values of the pixel at s0 into dst[p*spp ..]: a non-finite one takes the
// pixel's finite mean (0 if none), counted in repaired.
void read_values(const DeepSamples& deep, int c, std::uint64_t s0, std::size_t p, std::uint64_t spp,
                 std::vector<float>& dst, std::size_t& repaired) {
  double sum = 0;
  std::uint64_t n = 0;
  for (std::uint64_t k = 0; k < spp; ++k) {
    const float v = deep.values[c][s0 + k];
    if (std::isfinite(v)) sum += v, ++n;
  }
  const float mean = n ? float(sum / double(n)) : 0.f;
  for (std::uint64_t k = 0; k < spp; ++k) {
    const float v = deep.values[c][s0 + k];
    dst[p * spp + k] = std::isfinite(v) ? v : (++repaired, mean);
  }
}

// Channels a, b: the pixel's l*l coordinates into y1, y2, refused when non-finite or beyond range.
void read_coordinates(const DeepSamples& deep, int a, int b, std::uint64_t s0, std::size_t p, std::uint64_t spp,
                      float range, const char* names, const char* attr, const std::string& path, int x, int y,
                      std::vector<float>& y1, std::vector<float>& y2) {
  const float lim = range * (1 + 1e-4f);
  for (std::uint64_t k = 0; k < spp; ++k) {
    const float u = deep.values[a][s0 + k], v = deep.values[b][s0 + k];
    if (!std::isfinite(u) || !std::isfinite(v) || std::fabs(u) > lim || std::fabs(v) > lim) {
      std::ostringstream os;
      os << "'" << path << "': " << at(x, y) << " sample " << k << " has coordinate (" << names << ") = (" << u << ", "
         << v << "), outside [-" << range << ", " << range << "] (" << attr << ")";
      throw Error(Errc::ReadFailed, os.str());
    }
    y1[p * spp + k] = u;
    y2[p * spp + k] = v;
  }
}

// The lens half of a combined light field (LightField::lens), its samples in lf's order.
std::shared_ptr<const LightField> decode_lens(const DeepSamples& deep, const LightField& lf, const std::string& path,
                                              std::size_t& repaired) {
  auto lens = std::make_shared<LightField>();
  LightField& d = *lens;
  d.effect = LightFieldEffect::Dof;
  d.resize(lf.width, lf.height, lf.l, false);
  d.y_range = float(number(deep, "mcrecon:lf_u_range", path, 1e-6, 1e6));
  d.sigma_y = float(number(deep, "mcrecon:lf_sigma_u", path, 1e-6, 1e6));
  int sc[5], pc[2];
  for (int i = 0; i < 5; ++i) sc[i] = require_channel(deep, kLensSampleChannels[i], path, channel_meaning(kLensSampleChannels[i]));
  for (int i = 0; i < 2; ++i) pc[i] = require_channel(deep, kLensPixelChannels[i], path, channel_meaning(kLensPixelChannels[i]));
  const std::uint64_t spp = std::uint64_t(lf.spp());
  for (int y = 0; y < deep.height; ++y)
    for (int x = 0; x < deep.width; ++x) {
      const std::size_t p = std::size_t(y) * deep.width + x;
      const std::uint64_t s0 = deep.first(x, y);
      read_coordinates(deep, sc[3], sc[4], s0, p, spp, d.y_range, "lf.u1, lf.u2", "mcrecon:lf_u_range", path, x, y, d.y1, d.y2);
      read_values(deep, sc[0], s0, p, spp, d.r, repaired);
      read_values(deep, sc[1], s0, p, spp, d.g, repaired);
      read_values(deep, sc[2], s0, p, spp, d.b, repaired);
      const float lo = deep.values[pc[0]][s0], hi = deep.values[pc[1]][s0];
      if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) {
        std::ostringstream os;
        os << "'" << path << "': " << at(x, y) << " has lens slope bounds lf.dmin = " << lo << ", lf.dmax = " << hi
           << " (finite, dmin <= dmax)";
        throw Error(Errc::ReadFailed, os.str());
      }
      d.smin[p] = lo;
      d.smax[p] = hi;
      d.e1x[p] = 1;
      d.e2y[p] = 1;
      d.depth[p] = lf.depth[p];
    }
  return lens;
}

}  // namespace

LightField decode_lightfield(const DeepSamples& deep, const std::string& path, std::size_t* nonfinite_values) {
  LightField lf;
  bool combined = false;
  lf.effect = parse_effect(deep, path, &combined);
  const int l = int(number(deep, "mcrecon:lf_l", path, 1, 64));
  if (double(l) != number(deep, "mcrecon:lf_l", path, 1, 64))
    throw Error(Errc::ReadFailed, "'" + path + "': mcrecon:lf_l = '" + attribute(deep, "mcrecon:lf_l", path) +
                                      "' is not a whole number of samples per axis");
  lf.y_range = float(number(deep, "mcrecon:lf_y_range", path, 1e-6, 1e6));
  lf.sigma_y = float(number(deep, "mcrecon:lf_sigma_y", path, 1e-6, 1e6));
  if (deep.width <= 0 || deep.height <= 0 || deep.offsets.size() != std::size_t(deep.width) * deep.height + 1)
    throw Error(Errc::ReadFailed, "'" + path + "': the deep buffer holds no pixels");

  int sc[5], pc[7], gc[6];
  for (int i = 0; i < 5; ++i) sc[i] = require_channel(deep, kSampleChannels[i], path, channel_meaning(kSampleChannels[i]));
  for (int i = 0; i < 7; ++i) pc[i] = require_channel(deep, kPixelChannels[i], path, channel_meaning(kPixelChannels[i]));
  int present = 0;
  for (int i = 0; i < 6; ++i) present += (gc[i] = deep.channel(kGeometryChannels[i])) >= 0;
  if (present != 0 && present != 6)
    throw Error(Errc::MissingPass, "'" + path + "': light field has only some of P.X P.Y P.Z N.X N.Y N.Z (all six or none)");
  int ac[6], axes = 0;
  for (int i = 0; i < 6; ++i) axes += (ac[i] = deep.channel(kAxisChannels[i])) >= 0;
  if (axes != 0 && (axes != 6 || present != 6))
    throw Error(Errc::MissingPass, "'" + path + "': light field has " + std::to_string(axes) +
                                       " of the six world axis channels lf.w1x .. lf.w2z (all six, with P and N, or none)");
  const std::uint64_t spp = std::uint64_t(l) * std::uint64_t(l);
  if (deep.total_samples() != spp * std::uint64_t(deep.width) * std::uint64_t(deep.height)) {
    // Name the first pixel that breaks the rule: more use than a total.
    for (int y = 0; y < deep.height; ++y)
      for (int x = 0; x < deep.width; ++x)
        if (deep.samples(x, y) != spp)
          throw Error(Errc::ReadFailed, "'" + path + "': " + at(x, y) + " has " + std::to_string(deep.samples(x, y)) +
                                            " samples; mcrecon:lf_l = " + std::to_string(l) + " needs exactly " +
                                            std::to_string(spp) + " in every pixel");
  }
  int mc[3], mods = 0;
  for (int i = 0; i < 3; ++i) mods += (mc[i] = deep.channel(kModChannels[i])) >= 0;
  if (mods != 0 && mods != 3)
    throw Error(Errc::MissingPass, "'" + path + "': light field has " + std::to_string(mods) +
                                       " of the modulation channels lf.modR lf.modG lf.modB (all three or none)");
  lf.resize(deep.width, deep.height, l, present == 6);
  if (mods == 3)
    for (auto* v : {&lf.mod_r, &lf.mod_g, &lf.mod_b}) v->assign(lf.pixels(), 0.f);
  if (axes == 0)
    for (auto* v : {&lf.w1x, &lf.w1y, &lf.w1z, &lf.w2x, &lf.w2y, &lf.w2z}) v->clear();

  std::size_t repaired = 0;
  std::vector<float*> pixel_dst = {lf.smin.data(), lf.smax.data(), lf.e1x.data(), lf.e1y.data(),
                                   lf.e2x.data(),  lf.e2y.data(),  lf.depth.data()};
  std::vector<float*> geo_dst = {lf.px.data(), lf.py.data(), lf.pz.data(), lf.nx.data(), lf.ny.data(), lf.nz.data()};
  for (int y = 0; y < deep.height; ++y)
    for (int x = 0; x < deep.width; ++x) {
      const std::size_t p = std::size_t(y) * deep.width + x;
      const std::uint64_t s0 = deep.first(x, y);
      // Coordinates: a sample without a place on the light cannot be filtered; refused.
      read_coordinates(deep, sc[3], sc[4], s0, p, spp, lf.y_range, "lf.y1, lf.y2", "mcrecon:lf_y_range", path, x, y,
                       lf.y1, lf.y2);
      // Values: a non-finite one takes its pixel's finite mean (0 if none), counted.
      read_values(deep, sc[0], s0, p, spp, lf.r, repaired);
      read_values(deep, sc[1], s0, p, spp, lf.g, repaired);
      read_values(deep, sc[2], s0, p, spp, lf.b, repaired);
      // Per-pixel values are the first sample's; slopes and axes must be finite.
      for (int i = 0; i < 7; ++i) {
        const float v = deep.values[pc[i]][s0];
        if (!std::isfinite(v)) {
          if (i == 6) {  // a depth is only used for reports
            pixel_dst[i][p] = 0, ++repaired;
            continue;
          }
          throw Error(Errc::ReadFailed, "'" + path + "': " + at(x, y) + " has a non-finite " + kPixelChannels[i] +
                                            " (" + channel_meaning(kPixelChannels[i]) + ")");
        }
        pixel_dst[i][p] = v;
      }
      if (lf.smin[p] > lf.smax[p]) {
        std::ostringstream os;
        os << "'" << path << "': " << at(x, y) << " has lf.smin = " << lf.smin[p] << " above lf.smax = " << lf.smax[p];
        throw Error(Errc::ReadFailed, os.str());
      }
      if (present == 6) {
        for (int i = 0; i < 6; ++i) {
          const float v = deep.values[gc[i]][s0];
          geo_dst[i][p] = std::isfinite(v) ? v : (++repaired, 0.f);
        }
      }
      if (mods == 3) {
        float* mod_dst[3] = {lf.mod_r.data(), lf.mod_g.data(), lf.mod_b.data()};
        for (int i = 0; i < 3; ++i) {
          const float v = deep.values[mc[i]][s0];
          if (!std::isfinite(v) || v < 0) {
            std::ostringstream os;
            os << "'" << path << "': " << at(x, y) << " has " << kModChannels[i] << " = " << v
               << " (the modulation must be finite and not negative)";
            throw Error(Errc::ReadFailed, os.str());
          }
          mod_dst[i][p] = v;
        }
      }
      if (axes == 6) {
        float* axis_dst[6] = {lf.w1x.data(), lf.w1y.data(), lf.w1z.data(), lf.w2x.data(), lf.w2y.data(), lf.w2z.data()};
        for (int i = 0; i < 6; ++i) {
          const float v = deep.values[ac[i]][s0];
          if (!std::isfinite(v))
            throw Error(Errc::ReadFailed, "'" + path + "': " + at(x, y) + " has a non-finite " + kAxisChannels[i] +
                                              " (the world axes of the pixel's filter)");
          axis_dst[i][p] = v;
        }
      }
    }
  if (combined) lf.lens = decode_lens(deep, lf, path, repaired);
  lf.nonfinite_replaced = repaired;
  if (nonfinite_values) *nonfinite_values = repaired;
  return lf;
}

bool lightfield_converged(const LightField& lf, std::size_t p) {
  if (lf.spp() < 2) return false;  // one sample says nothing of its pixel's spread
  const std::size_t spp = std::size_t(lf.spp()), k0 = p * spp;
  const int x = int(p % std::size_t(lf.width)), y = int(p / std::size_t(lf.width));
  for (int qy = std::max(0, y - 1); qy <= std::min(lf.height - 1, y + 1); ++qy)
    for (int qx = std::max(0, x - 1); qx <= std::min(lf.width - 1, x + 1); ++qx) {
      const std::size_t j0 = (std::size_t(qy) * std::size_t(lf.width) + std::size_t(qx)) * spp;
      for (std::size_t k = 0; k < spp; ++k)
        if (lf.r[j0 + k] != lf.r[k0] || lf.g[j0 + k] != lf.g[k0] || lf.b[j0 + k] != lf.b[k0]) return false;
    }
  return true;
}

LightFieldSummary summarize(const LightField& lf) {
  LightFieldSummary s;
  bool first = true;
  double e1 = 0, e2 = 0;
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    const float a = lf.smin[p], b = lf.smax[p];
    if (a == 0 && b == 0) {
      ++s.nothing_to_shear;
    } else {
      s.slope_min = first ? a : std::min(s.slope_min, a);
      s.slope_max = first ? b : std::max(s.slope_max, b);
      first = false;
      s.opposite_signs += a * b < 0;
    }
    s.converged += lightfield_converged(lf, p);
    e1 += std::hypot(lf.e1x[p], lf.e1y[p]);
    e2 += std::hypot(lf.e2x[p], lf.e2y[p]);
  }
  if (lf.pixels()) s.e1_mean = float(e1 / double(lf.pixels())), s.e2_mean = float(e2 / double(lf.pixels()));
  return s;
}

DeepSamples encode_lightfield(const LightField& lf) {
  DeepSamples d;
  d.width = lf.width;
  d.height = lf.height;
  const std::size_t spp = std::size_t(lf.spp()), np = lf.pixels();
  if (lf.r.size() != lf.samples() || lf.smin.size() != np)
    throw Error(Errc::Internal, "encode_lightfield: arrays do not match width x height x l*l");
  d.offsets.resize(np + 1);
  for (std::size_t p = 0; p <= np; ++p) d.offsets[p] = std::uint64_t(p) * spp;
  for (const char* c : kSampleChannels) d.channel_names.push_back(c);
  for (const char* c : kPixelChannels) d.channel_names.push_back(c);
  if (lf.has_geometry())
    for (const char* c : kGeometryChannels) d.channel_names.push_back(c);
  if (lf.has_world_axes())
    for (const char* c : kAxisChannels) d.channel_names.push_back(c);
  if (lf.has_modulation())
    for (const char* c : kModChannels) d.channel_names.push_back(c);
  if (lf.combined()) {
    for (const char* c : kLensSampleChannels) d.channel_names.push_back(c);
    for (const char* c : kLensPixelChannels) d.channel_names.push_back(c);
  }
  d.values.reserve(d.channel_names.size());
  for (const auto* v : {&lf.r, &lf.g, &lf.b, &lf.y1, &lf.y2}) d.values.push_back(*v);
  auto repeat = [&](const std::vector<float>& per_pixel) {
    std::vector<float> out(np * spp);
    for (std::size_t p = 0; p < np; ++p)
      for (std::size_t k = 0; k < spp; ++k) out[p * spp + k] = per_pixel[p];
    d.values.push_back(std::move(out));
  };
  for (const auto* v : {&lf.smin, &lf.smax, &lf.e1x, &lf.e1y, &lf.e2x, &lf.e2y, &lf.depth}) repeat(*v);
  if (lf.has_geometry())
    for (const auto* v : {&lf.px, &lf.py, &lf.pz, &lf.nx, &lf.ny, &lf.nz}) repeat(*v);
  if (lf.has_world_axes())
    for (const auto* v : {&lf.w1x, &lf.w1y, &lf.w1z, &lf.w2x, &lf.w2y, &lf.w2z}) repeat(*v);
  if (lf.has_modulation())
    for (const auto* v : {&lf.mod_r, &lf.mod_g, &lf.mod_b}) repeat(*v);
  auto text = [](float v) {
    std::ostringstream os;
    os.precision(9);
    os << v;
    return os.str();
  };
  if (lf.combined()) {
    const LightField& u = *lf.lens;
    if (u.r.size() != lf.samples() || u.smin.size() != np)
      throw Error(Errc::Internal, "encode_lightfield: the lens arrays do not match the light field");
    for (const auto* v : {&u.r, &u.g, &u.b, &u.y1, &u.y2}) d.values.push_back(*v);
    for (const auto* v : {&u.smin, &u.smax}) repeat(*v);
    d.attributes["mcrecon:lf_u_range"] = text(u.y_range);
    d.attributes["mcrecon:lf_sigma_u"] = text(u.sigma_y);
  }
  d.attributes["mcrecon:lightfield"] = lightfield_kind(lf);
  d.attributes["mcrecon:lf_l"] = std::to_string(lf.l);
  d.attributes["mcrecon:lf_y_range"] = text(lf.y_range);
  d.attributes["mcrecon:lf_sigma_y"] = text(lf.sigma_y);
  return d;
}

}  // namespace mcr
