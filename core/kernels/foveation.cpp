#include "kernels/foveation.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"

namespace mcr {

ParamTable with_foveation(ParamTable own, const std::vector<std::string>& foveated_params) {
  for (const std::string& name : foveated_params) {
    auto it = std::find_if(own.begin(), own.end(), [&](const ParamSpec& s) { return s.name == name; });
    if (it == own.end() || it->type != ParamType::Float)
      throw Error(Errc::Internal, "with_foveation: no Float parameter '" + name + "' in the table");
    ParamSpec twin = *it;
    twin.name = name + "_outer";
    twin.help = "'" + name + "' beyond outer_radius when foveated (between the radii interpolated linearly)";
    own.insert(it + 1, twin);
  }
  own.push_back(ParamSpec::Bool("foveated", false,
                                "vary the parameters with the distance from the gaze: inner set (e.g. sigma) within "
                                "inner_radius, the _outer twins beyond outer_radius, linear between"));
  own.push_back(ParamSpec::Float("gaze_x", 0.5, 0.0, 1.0, "point of gaze, fraction of the image width (0 = left)"));
  own.push_back(ParamSpec::Float("gaze_y", 0.5, 0.0, 1.0, "point of gaze, fraction of the image height (0 = top)"));
  own.push_back(ParamSpec::Float("inner_radius", 0.1, 0.0, 1.0,
                                 "radius of the inner (foveal) circle, fraction of the image diagonal"));
  own.push_back(ParamSpec::Float("outer_radius", 0.3, 0.0, 1.0,
                                 "radius beyond which the outer set applies, fraction of the image diagonal; >= inner_radius"));
  return own;
}

void check_foveation_params(const ParamSet& params, const std::string& filter) {
  if (!params.get_bool("foveated")) return;
  const double in = params.get_float("inner_radius"), out = params.get_float("outer_radius");
  if (out < in)
    throw Error(Errc::ParameterOutOfRange, "parameter 'outer_radius' of filter '" + filter + "' must be >= inner_radius (" +
                                               param_value_text(in) + "), got " + param_value_text(out));
}

std::vector<std::string> foveation_unused(const ParamSet& params) {
  std::vector<std::string> out;
  if (!params.has("foveated") || params.get_bool("foveated")) return out;
  for (const auto& kv : params.values()) {
    const std::string& n = kv.first;
    const bool outer = n.size() > 6 && n.compare(n.size() - 6, 6, "_outer") == 0;
    if (outer || n == "gaze_x" || n == "gaze_y" || n == "inner_radius" || n == "outer_radius")
      report_unused(params, n, "with foveated=false", out);
  }
  return out;
}

Foveation::Foveation(const ParamSet& params, int width, int height) : params_(params) {
  enabled_ = params.get_bool("foveated");
  const double diag = std::sqrt(double(width) * width + double(height) * height);
  gx_ = params.get_float("gaze_x") * width;
  gy_ = params.get_float("gaze_y") * height;
  r_in_ = params.get_float("inner_radius") * diag;
  r_out_ = std::max(r_in_, params.get_float("outer_radius") * diag);
}

float Foveation::blend(double px, double py) const {
  if (!enabled_) return 0.0f;
  const double dx = px - gx_, dy = py - gy_;
  const double d = std::sqrt(dx * dx + dy * dy);
  if (d <= r_in_) return 0.0f;
  if (d >= r_out_) return 1.0f;
  return float((d - r_in_) / (r_out_ - r_in_));  // r_out_ > r_in_ here
}

double Foveation::inner(const std::string& name) const { return params_.get_float(name); }
double Foveation::outer(const std::string& name) const { return params_.get_float(name + "_outer"); }

FoveatedValue Foveation::param(const std::string& name) const {
  FoveatedValue v;
  v.inner = inner(name);
  v.outer = enabled_ ? outer(name) : v.inner;
  v.varies = enabled_ && v.inner != v.outer;
  return v;
}

bool Foveation::varies(const std::string& name) const { return enabled_ && inner(name) != outer(name); }

std::vector<float> Foveation::blend_plane(const Roi& box) const {
  std::vector<float> t(std::size_t(std::max(0, box.width())) * std::size_t(std::max(0, box.height())), 0.0f);
  if (!enabled_) return t;
  for (int y = box.y0; y < box.y1; ++y)
    for (int x = box.x0; x < box.x1; ++x) t[std::size_t(y - box.y0) * box.width() + (x - box.x0)] = blend_at(x, y);
  return t;
}

}  // namespace mcr
