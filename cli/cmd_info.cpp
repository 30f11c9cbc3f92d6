#include <algorithm>
#include <cstdint>
#include <iostream>

#include "commands.h"
#include "image/lightfield.h"
#include "io/frame_reader.h"
#include "json_views.h"
#include "pipeline/components.h"
#include "pipeline/filter_catalog.h"
#include "pipeline/reconstruction.h"

namespace mcr::cli {

namespace {

// The per-sample buffer: counts, channels, what the sweep's convention finds (README).
nlohmann::json deep_report(const DeepSamples& d) {
  std::uint64_t lo = UINT64_MAX, hi = 0, empty = 0;
  const std::size_t np = std::size_t(d.width) * std::size_t(d.height);
  for (std::size_t p = 0; p < np; ++p) {
    const std::uint64_t n = d.offsets[p + 1] - d.offsets[p];
    lo = std::min(lo, n);
    hi = std::max(hi, n);
    empty += n == 0;
  }
  nlohmann::json found = nlohmann::json::array(), missing = nlohmann::json::array(), camera = nlohmann::json::object();
  for (const char* c : {"R", "G", "B", "Z"}) (d.channel(c) >= 0 ? found : missing).push_back(c);
  for (const char* c : {"A", "dx", "dy", "blur", "mx", "my"})
    if (d.channel(c) >= 0) found.push_back(c);
  for (const auto& [k, v] : d.attributes) camera[k] = v;
  return {{"samples", d.total_samples()},
          {"per_pixel_min", np ? lo : 0},
          {"per_pixel_mean", np ? double(d.total_samples()) / double(np) : 0.0},
          {"per_pixel_max", hi},
          {"empty_pixels", empty},
          {"channels", d.channel_names},
          {"convention_found", found},
          {"convention_missing_required", missing},
          {"camera", camera}};
}

// A light field (README: the light-field convention): effect, sampling, slopes, work to do.
nlohmann::json lightfield_report(const LightField& lf) {
  const std::size_t repaired = lf.nonfinite_replaced;
  const LightFieldSummary s = summarize(lf);
  nlohmann::json j = {{"effect", lightfield_kind(lf)}, {"l", lf.l}, {"spp", lf.spp()}, {"y_range", lf.y_range},
          {"sigma_y", lf.sigma_y}, {"slope_min", s.slope_min}, {"slope_max", s.slope_max},
          {"pixels", lf.pixels()}, {"nothing_to_shear", s.nothing_to_shear}, {"opposite_slope_signs", s.opposite_signs},
          {"converged", s.converged}, {"axis1_pixels_per_unit", s.e1_mean}, {"axis2_pixels_per_unit", s.e2_mean},
          {"geometry", lf.has_geometry()}, {"nonfinite_values_replaced", repaired}};
  if (lf.combined()) {
    // The lens half (soft shadows through a lens): its bounds, the pixels in focus.
    const LightFieldSummary u = summarize(*lf.lens);
    j["lens"] = {{"u_range", lf.lens->y_range}, {"sigma_u", lf.lens->sigma_y}, {"slope_min", u.slope_min},
                 {"slope_max", u.slope_max}, {"in_focus", u.nothing_to_shear}, {"opposite_slope_signs", u.opposite_signs}};
  }
  return j;
}

struct InfoArgs {
  std::string input, layer;
  std::vector<std::string> passes;
  bool json = false;
};

int run_info(const InfoArgs& a) {
  ReadOptions ro;
  ro.layer = a.layer;
  ro.require_colour = false;
  ro.keep_extra = true;
  for (const auto& p : a.passes) ro.overrides.push_back(parse_pass_override(p));
  const Frame frame = read_frame(a.input, ro);

  nlohmann::json roles = nlohmann::json::object(), passes = nlohmann::json::array(), other = nlohmann::json::array();
  for (Role r : kAllRoles) {
    const Pass* feature = frame.find(r, Prefer::Feature);
    if (!feature) continue;
    nlohmann::json j = to_json(*feature);
    const Pass* geometry = frame.find(r, Prefer::Geometry);
    if (geometry != feature) j["geometry"] = to_json(*geometry);  // e.g. world Normal beside Denoising Normal
    roles[role_name(r)] = j;
  }
  for (const Pass& p : frame.passes) passes.push_back(to_json(p));
  for (const Pass& p : frame.extra) other.push_back({{"name", p.name}, {"channels", p.channels}});
  // Which filters can run with their default settings (Filter::needs()): the required
  // passes the file lacks, and the optional ones it has that they would use.
  nlohmann::json filters = nlohmann::json::array();
  for (const auto& name : catalog_names()) {
    const auto f = make_committed_filter(name, {});
    nlohmann::json missing = nlohmann::json::array(), uses = nlohmann::json::array();
    for (Role r : f->missing_passes(frame)) missing.push_back(role_name(r));
    if (f->info().lightfield_input && !(frame.deep && is_lightfield(*frame.deep)))
      missing.push_back("light-field (deep EXR) input");
    else if (f->info().deep_input && !frame.deep)
      missing.push_back("per-sample (deep) input");
    for (Role r : f->needs().optional)
      if (frame.has(r)) uses.push_back(role_name(r));
    filters.push_back({{"name", name}, {"can_run", missing.empty()}, {"missing", missing}, {"uses", uses}});
  }
  nlohmann::json j = {{"file", frame.path},   {"width", frame.width},     {"height", frame.height},
                      {"deep", bool(frame.deep)}, {"layers", frame.layers}, {"layer", frame.layer},
                      {"roles", roles},       {"passes", passes},         {"other_channels", other},
                      {"filters", filters}};
  if (frame.deep) {
    j["deep_samples"] = frame.deep->total_samples();
    j["deep_buffer"] = deep_report(*frame.deep);
    if (frame.lightfield) j["lightfield"] = lightfield_report(*frame.lightfield);
  }
  if (a.json) {
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::cout << frame.path << ": " << frame.width << "x" << frame.height << (frame.deep ? " deep" : "") << "\n";
  if (frame.deep) {
    const auto& d = j["deep_buffer"];
    std::cout << "deep: " << d["samples"].get<std::uint64_t>() << " samples, per pixel min "
              << d["per_pixel_min"].get<std::uint64_t>() << " mean " << d["per_pixel_mean"].get<double>() << " max "
              << d["per_pixel_max"].get<std::uint64_t>() << " (" << d["empty_pixels"].get<std::uint64_t>()
              << " pixels without samples)\n  channels:";
    for (const auto& c : d["channels"]) std::cout << " " << c.get<std::string>();
    std::cout << "\n  per-sample convention: found";
    for (const auto& c : d["convention_found"]) std::cout << " " << c.get<std::string>();
    if (!d["convention_missing_required"].empty()) {
      std::cout << "; missing required";
      for (const auto& c : d["convention_missing_required"]) std::cout << " " << c.get<std::string>();
    }
    std::cout << "\n  camera:";
    if (d["camera"].empty()) std::cout << " (no mcrecon:* attributes)";
    for (const auto& [k, v] : d["camera"].items()) std::cout << " " << k << "=" << v.get<std::string>();
    std::cout << "\n";
  }
  if (j.contains("lightfield")) {
    const auto& l = j["lightfield"];
    std::cout << "light field: " << l["effect"].get<std::string>() << ", " << l["l"].get<int>() << "x"
              << l["l"].get<int>() << " samples per pixel over y in [-" << l["y_range"].get<float>() << ", "
              << l["y_range"].get<float>() << "]^2, sigma_y " << l["sigma_y"].get<float>() << "\n  slopes "
              << l["slope_min"].get<float>() << " .. " << l["slope_max"].get<float>() << "; nothing to shear in "
              << l["nothing_to_shear"].get<std::size_t>() << " of " << l["pixels"].get<std::size_t>()
              << " pixels, slopes of both signs (axis-aligned fallback) in " << l["opposite_slope_signs"].get<std::size_t>()
              << ", converged " << l["converged"].get<std::size_t>() << "\n  axes: " << l["axis1_pixels_per_unit"].get<float>()
              << " and " << l["axis2_pixels_per_unit"].get<float>() << " pixels per x unit (mean); geometry (P, N): "
              << (l["geometry"].get<bool>() ? "yes" : "no") << "\n";
    if (l.contains("lens")) {
      const auto& u = l["lens"];
      std::cout << "  lens: u in [-" << u["u_range"].get<float>() << ", " << u["u_range"].get<float>() << "]^2, sigma_u "
                << u["sigma_u"].get<float>() << "; lens slopes " << u["slope_min"].get<float>() << " .. "
                << u["slope_max"].get<float>() << "; in focus " << u["in_focus"].get<std::size_t>()
                << ", slopes of both signs " << u["opposite_slope_signs"].get<std::size_t>() << "\n";
    }
  }
  std::cout << "layers:";
  for (const auto& l : frame.layers) std::cout << " " << (l.empty() ? "(top level)" : l);
  std::cout << "\nusing layer: " << (frame.layer.empty() ? "(top level)" : frame.layer) << "\npasses:\n";
  for (const Pass& p : frame.passes) {
    std::cout << "  " << role_name(p.role) << ": " << (p.name.empty() ? "(bare)" : p.name) << " [";
    for (std::size_t i = 0; i < p.channels.size(); ++i) std::cout << (i ? " " : "") << p.channels[i];
    std::cout << "]";
    if (p.space != Space::None) std::cout << " " << space_name(p.space) << " space";
    const auto light = light_pass_roles();
    if (std::find(light.begin(), light.end(), p.role) != light.end()) std::cout << " (light pass: components=light_passes)";
    else if (frame.find(p.role, Prefer::Feature) == &p) std::cout << " (used by feature filters)";
    else if (frame.find(p.role, Prefer::Geometry) == &p) std::cout << " (used for geometry)";
    std::cout << "\n";
  }
  if (!frame.extra.empty()) {
    std::cout << "other channels:";
    for (const Pass& p : frame.extra) std::cout << " " << (p.name.empty() ? "(bare)" : p.name) << "(" << p.channels.size() << ")";
    std::cout << "\n";
  }
  std::cout << "filters:\n";
  for (const auto& f : filters) {
    std::cout << "  " << f["name"].get<std::string>() << ": " << (f["can_run"].get<bool>() ? "can run" : "cannot run, lacks");
    for (const auto& m : f["missing"]) std::cout << " " << m.get<std::string>();
    if (f["can_run"].get<bool>() && !f["uses"].empty()) {
      std::cout << ", uses";
      for (const auto& u : f["uses"]) std::cout << " " << u.get<std::string>();
    }
    std::cout << "\n";
  }
  return 0;
}

}  // namespace

Run add_info(CLI::App& app) {
  auto a = std::make_shared<InfoArgs>();
  app.add_option("input", a->input, "render (EXR, multilayer or plain; deep EXR)")->required();
  app.add_option("--layer", a->layer, "view layer to use (default: the first with a colour pass)");
  app.add_option("--pass", a->passes, "ROLE=FILE or ROLE=CHANNEL_GROUP override (repeatable)")->allow_extra_args(false);
  app.add_flag("--json", a->json, "machine-readable output");
  return [a] { return run_info(*a); };
}

}  // namespace mcr::cli
