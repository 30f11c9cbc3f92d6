#include "pipeline/alpha_stage.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "pipeline/filter_catalog.h"
#include "util/parallel.h"

namespace mcr {

bool filters_alpha(const ParamSet& params) { return params.has("alpha") && params.get_enum("alpha") == "filter"; }

std::unique_ptr<Filter> make_alpha_filter(const Filter& colour_filter) {
  const std::string name = colour_filter.info().name == "auto" ? "pwaf" : colour_filter.info().name;
  std::unique_ptr<Filter> f = make_catalog_filter(name);
  if (name == colour_filter.info().name)
    for (const auto& kv : colour_filter.params().values())
      if (colour_filter.params().was_set(kv.first)) f->set(kv.first, kv.second);
  // Coverage is not lit through the albedo: the preparation's demodulation and bmfr's own off.
  for (const char* p : {"demodulate", "albedo_demodulation"})
    if (f->params().has(p)) f->set(p, false);
  if (f->params().has("components")) f->set("components", std::string("beauty"));
  f->commit();
  return f;
}

std::string alpha_kept_because(const ParamSet& params, const Frame& frame) {
  if (params.has("holes") && params.get_enum("holes") == "alpha")
    return "holes=alpha (the alpha marks the sampled pixels)";
  const Pass* alpha = frame.find(Role::Alpha);
  if (!alpha || alpha->image.pixel_count() == 0) return "no alpha pass";
  const Image& a = alpha->image;
  const std::size_t n = a.pixel_count(), ch = std::size_t(a.channels());
  const float first = a.data()[0];
  for (std::size_t i = 1; i < n; ++i)
    if (!(a.data()[i * ch] == first)) return "";
  return "alpha " + rounded_text(first, 4) + " everywhere";
}

std::string alpha_kept_note(const Frame& frame, const std::string& why) {
  return frame.has(Role::Alpha) ? "alpha: kept as it is (" + why + ")" : std::string();
}

namespace {

// The light passes: only components=light_passes reads them (the alpha's run is the beauty's).
bool light_pass(Role r) {
  switch (r) {
    case Role::DiffuseDirect: case Role::DiffuseIndirect: case Role::GlossyDirect: case Role::GlossyIndirect:
    case Role::TransmissionDirect: case Role::TransmissionIndirect: case Role::TransmissionColour:
    case Role::Emission: case Role::Environment:
      return true;
    default:
      return false;
  }
}

}  // namespace

Frame alpha_frame(const Frame& frame) {
  Frame f = frame.header(frame.width, frame.height);
  f.window = frame.window;
  const Pass& colour = frame.get(Role::Colour);
  const Pass& alpha = frame.get(Role::Alpha);
  Image grey(frame.width, frame.height, 3);
  const std::size_t ac = std::size_t(alpha.image.channels());
  for (std::size_t i = 0, n = grey.pixel_count(); i < n; ++i)
    grey.data()[i * 3] = grey.data()[i * 3 + 1] = grey.data()[i * 3 + 2] = alpha.image.data()[i * ac];
  Pass c = with_pixels(colour, std::move(grey));
  c.channels.resize(std::min<std::size_t>(c.channels.size(), 3));
  f.passes.push_back(std::move(c));
  for (const Pass& p : frame.passes)
    if (p.role != Role::Colour && p.role != Role::Alpha && p.role != Role::Variance && !light_pass(p.role))
      f.passes.push_back(p);
  return f;
}

AlphaRange alpha_range(const Image& alpha) {
  AlphaRange r;
  const std::size_t ch = std::size_t(alpha.channels());
  for (std::size_t i = 0, n = alpha.pixel_count(); i < n; ++i) {
    const float v = alpha.data()[i * ch];
    if (!std::isfinite(v)) continue;
    r.lo = std::min(r.lo, v);
    r.hi = std::max(r.hi, v);
  }
  return r;
}

void PartialCoverage::mark(const Frame& rows, int y0) {
  const Pass* normal = rows.find(Role::Normal, Prefer::Geometry);
  if (!normal || normal->image.channels() < 3) return;
  const Image& n = normal->image;
  for (int y = 0; y < n.height(); ++y)
    for (int x = 0; x < n.width(); ++x) {
      const float* v = n.pixel(x, y);
      const float len2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];  // NaN: not partial (filtered)
      mask_[std::size_t(y0 + y) * std::size_t(width_) + std::size_t(x)] =
          len2 > 0.0f && len2 < kCoveredNormal * kCoveredNormal;
    }
}

Image finish_alpha(const Image& filtered, const Image& own, const PartialCoverage& coverage, AlphaRange range,
                   int nthreads, std::size_t* kept) {
  const int w = filtered.width(), h = filtered.height(), ch = filtered.channels(), och = own.channels();
  Image out(w, h, 1);
  std::vector<std::size_t> row_kept(std::size_t(h), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    const float* in = filtered.pixel(0, y);
    const float* mine = own.pixel(0, y);
    float* o = out.pixel(0, y);
    for (int x = 0; x < w; ++x) {
      const float v = in[x * ch], a = mine[x * och];
      if (coverage.partial(x, y) && std::isfinite(a)) {
        o[x] = a;
        ++row_kept[std::size_t(y)];
      } else {
        o[x] = std::isfinite(v) ? std::clamp(v, range.lo, range.hi) : range.lo;
      }
    }
  });
  if (kept) *kept = std::accumulate(row_kept.begin(), row_kept.end(), std::size_t(0));
  return out;
}

std::string alpha_note(const Filter& alpha_filter, AlphaRange range, std::size_t kept) {
  return "alpha: filtered by " + alpha_filter.info().name + " as a grey colour (demodulation off), clamped to [" +
         rounded_text(range.lo, 4) + ", " + rounded_text(range.hi, 4) + "], its own at " + std::to_string(kept) +
         " partly covered pixels (normal pass shorter than " + rounded_text(kCoveredNormal, 4) + ")";
}

void put_alpha(Frame& frame, Image alpha) {
  if (alpha.empty()) return;
  frame.passes[std::size_t(&frame.get(Role::Alpha) - frame.passes.data())].image = std::move(alpha);
}

}  // namespace mcr
