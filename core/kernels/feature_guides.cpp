#include "kernels/feature_guides.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <utility>

#include "kernels/feature_activity.h"
#include "kernels/planes.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

namespace {

constexpr Feature kFeatures[kFeatureCount] = {Feature::Colour, Feature::Normal, Feature::Position, Feature::Albedo,
                                              Feature::Depth};

Role feature_role(Feature f) {
  switch (f) {
    case Feature::Colour: return Role::Colour;
    case Feature::Normal: return Role::Normal;
    case Feature::Position: return Role::Position;
    case Feature::Albedo: return Role::Albedo;
    case Feature::Depth: return Role::Depth;
  }
  return Role::Colour;
}

// Largest k we let into the kernel: k * 0 must stay 0 (never inf * 0 = NaN), and
// k = 1e30 already zeroes any weight whose feature difference is above ~1e-14.
constexpr double kMaxK = 1e30;

float k_of_sigma(double sigma) { return float(std::min(kMaxK, 1.0 / (2.0 * sigma * sigma))); }

}  // namespace

const char* feature_name(Feature f) {
  switch (f) {
    case Feature::Colour: return "colour";
    case Feature::Normal: return "normal";
    case Feature::Position: return "position";
    case Feature::Albedo: return "albedo";
    case Feature::Depth: return "depth";
  }
  return "?";
}

void feature_needs(const ParamSet& params, std::vector<Role>& required, std::vector<std::string>& why,
                   std::vector<Role>& off) {
  for (Feature f : kFeatures) {
    const std::string use = std::string("use_") + feature_name(f);
    if (f == Feature::Colour || !params.has(use)) continue;
    const std::string& mode = params.get_enum(use);
    if (mode == "on") {
      required.push_back(feature_role(f));
      why.push_back(use + "=on");
    } else if (mode == "off") {
      off.push_back(feature_role(f));
    }
  }
}

std::vector<std::string> feature_unused(const ParamSet& params) {
  std::vector<std::string> out;
  for (Feature f : kFeatures) {
    const std::string use = std::string("use_") + feature_name(f);
    if (!params.has(use) || params.get_enum(use) != "off") continue;
    const std::string sigma = std::string(feature_name(f)) + "_sigma";
    report_unused(params, sigma, "with " + use + "=off", out);
    report_unused(params, sigma + "_outer", "with " + use + "=off", out);
  }
  return out;
}

ParamTable feature_params(const FeatureDefaults& d) {
  static const char* what[kFeatureCount] = {
      "colour (range) weight, on the colour as filtered (after demodulation; it always exists, so auto = on)",
      "normal weight (Blender's camera-space Denoising Normal, else Normal)",
      "world-position weight",
      "albedo (texture) weight",
      "depth weight (first channel of the depth pass; off by default: position carries it)"};
  static const char* unit[kFeatureCount] = {"radiance units", "unit-vector difference", "scene units", "reflectance",
                                            "scene units"};
  ParamTable t;
  for (int i = 0; i < kFeatureCount; ++i) {
    const std::string n = feature_name(kFeatures[i]);
    t.push_back(ParamSpec::Enum("use_" + n, d.use[i], {"auto", "on", "off"},
                                std::string(what[i]) + ": auto = used when the pass exists (dropped with a note otherwise), "
                                                       "on = required (missing pass is an error), off = not used"));
    t.push_back(ParamSpec::Float(n + "_sigma", d.sigma[i], 1e-6, 1e6,
                                 "sigma of the " + n + " weight exp(-|d|^2/(2 sigma^2)), in " + unit[i] +
                                     "; smaller = stronger edge stopping"));
  }
  return t;
}

std::vector<std::string> feature_sigma_names() {
  std::vector<std::string> names;
  for (Feature f : kFeatures) names.push_back(std::string(feature_name(f)) + "_sigma");
  return names;
}

void gather_guides(const Frame& frame, const ParamSet& params, const Foveation& fov, const std::string& filter,
                   const PlaneBox& pb, const std::function<void(std::string)>& note, int nthreads, Guides& g) {
  g.pb = pb;
  g.colour = false;
  g.colour_a.clear();
  g.used.clear();
  g.skipped.clear();
  std::vector<std::pair<const Image*, int>> mask_only;  // dropped as constant, but with non-finite pixels
  std::size_t used_guides = 0;  // g.list entries keep their memory for the next frame
  const Roi& box = pb.box;

  // k_f: a constant, plus a plane when the foveated sigma varies.
  auto k_of = [&](const std::string& name, float& k_const, std::vector<float>& k) {
    const FoveatedValue sigma = fov.param(name);
    k_const = k_of_sigma(sigma.inner);
    if (!sigma.varies) {
      k.clear();
      return;
    }
    pb.prepare(k);
    parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
      for (int x = box.x0; x < box.x1; ++x) k[pb.index(x, y)] = k_of_sigma(sigma.at(fov.blend_at(x, y)));
    });
  };

  for (Feature f : kFeatures) {
    const std::string name = feature_name(f);
    const std::string mode = params.get_enum("use_" + name);
    if (mode == "off") continue;
    if (f == Feature::Colour) {
      g.colour = true;
      // The colour weight is kept as a = sqrt(k): see CrossPass::colour_a.
      const FoveatedValue sigma = fov.param(name + "_sigma");
      auto a_of = [](double sg) { return float(1.0 / (std::sqrt(2.0) * sg)); };
      g.colour_a_const = a_of(sigma.inner);
      if (sigma.varies) {
        pb.prepare(g.colour_a);
        parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
          for (int x = box.x0; x < box.x1; ++x) g.colour_a[pb.index(x, y)] = a_of(sigma.at(fov.blend_at(x, y)));
        });
      }
      g.used.push_back(name);
      continue;
    }
    const Pass* pass = frame.find(feature_role(f));
    if (!pass) {
      if (mode == "on")
        throw Error(Errc::MissingPass, "filter '" + filter + "': use_" + name + "=on needs the " + name +
                                           " pass, absent in '" + frame.path + "'");
      note(name + " weight dropped: no " + name + " pass in '" + frame.path + "' (use_" + name + "=auto)");
      continue;
    }
    {
      // A pass constant within constant_tolerance(the smallest sigma) over the box: its
      // weight is 1 within 1e-4 for every pair, so it is dropped. Its non-finite pixels
      // stay unusable neighbours (mask_only), as with the weight on.
      const FoveatedValue sg = fov.param(name + "_sigma");
      const double sigma = sg.varies ? std::min(sg.inner, sg.outer) : sg.inner;
      const int nch = f == Feature::Depth ? 1 : 3;
      const FeatureActivity act = feature_activity(pass->image, nch, box, constant_tolerance(sigma), nthreads);
      if (act.kind != Activity::Varies) {
        note(activity_note(name, act, box, frame.width, frame.height, name + " weight not used"));
        g.skipped.push_back(name);
        if (act.kind == Activity::Constant && act.some_nonfinite) mask_only.emplace_back(&pass->image, nch);
        continue;
      }
    }
    if (g.list.size() <= used_guides) g.list.emplace_back();
    Guides::Guide& gd = g.list[used_guides++];
    gd.feature = f;
    gd.channels = f == Feature::Depth ? 1 : 3;
    for (int c = 0; c < 3; ++c) {
      if (c < gd.channels) pb.prepare(gd.c[c]);
      else gd.c[c].clear();
    }
    k_of(name + "_sigma", gd.k_const, gd.k);
    const Image& im = pass->image;
    const int ch = im.channels();
    std::vector<unsigned char> bad_row(std::size_t(std::max(0, box.height())), 0);
    parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
      const std::size_t i0 = pb.index(box.x0, y);
      const float* v = im.pixel(box.x0, y);
      float* c[3] = {gd.c[0].data() + i0, gd.channels == 3 ? gd.c[1].data() + i0 : nullptr,
                     gd.channels == 3 ? gd.c[2].data() + i0 : nullptr};
      std::vector<float> finite(std::size_t(box.width()));
      float* ok = finite.data();
      if (gd.channels == 3 && ch == 3) split_rgb3(v, box.width(), FLT_MAX, c[0], c[1], c[2], ok);
      else split_any(v, ch, box.width(), gd.channels, FLT_MAX, c, ok);
      int bad = 0;
      for (int x = 0; x < box.width(); ++x) bad += ok[x] == 0.0f;
      bad_row[std::size_t(y - box.y0)] = bad > 0;
    });
    if (std::find(bad_row.begin(), bad_row.end(), 1) != bad_row.end()) {
      // Some centres ignore this feature: k becomes a plane, 0 where the value is not finite.
      if (gd.k.empty()) pb.prepare(gd.k, gd.k_const);
      parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
        if (!bad_row[std::size_t(y - box.y0)]) return;
        for (int x = box.x0; x < box.x1; ++x) {
          const float* v = im.pixel(x, y);
          bool finite = true;
          for (int c = 0; c < gd.channels; ++c) finite = finite && std::isfinite(v[std::min(c, ch - 1)]);
          if (!finite) gd.k[pb.index(x, y)] = 0.0f;
        }
      });
    }
    g.used.push_back(name);
  }
  g.list.resize(used_guides);

  pb.prepare(g.ok, 1.0f);
  for (const auto& [im, nch] : mask_only)
    parallel_rows(box.y0, box.y1, nthreads, [&, im = im, nch = nch](int y) {
      const int ch = im->channels();
      for (int x = box.x0; x < box.x1; ++x) {
        const float* v = im->pixel(x, y);
        bool finite = true;
        for (int c = 0; c < nch; ++c) finite = finite && std::isfinite(v[std::min(c, ch - 1)]);
        if (!finite) g.ok[pb.index(x, y)] = 0.0f;
      }
    });
  for (const Guides::Guide& gd : g.list)
    if (!gd.k.empty())  // k >= 5e-13 for any sigma in range: 0 marks exactly the non-finite values
      parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
        for (int x = box.x0; x < box.x1; ++x)
          if (gd.k[pb.index(x, y)] == 0.0f) g.ok[pb.index(x, y)] = 0.0f;
      });
}

}  // namespace mcr
