#pragma once
// Shared by the image-filter tests (gaussian, bilateral, atrous): random frames with
// every feature pass, and a one-call run of a filter with a parameter map.
#include <gtest/gtest.h>

#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "filters/filter.h"

namespace mcr::testutil {

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline const char* const kFeatureNames[5] = {"colour", "normal", "position", "albedo", "depth"};
inline const Role kFeatureRoles[5] = {Role::Colour, Role::Normal, Role::Position, Role::Albedo, Role::Depth};

using Params = std::map<std::string, ParamValue>;

inline Image random_image(int w, int h, int ch, unsigned seed, float lo = 0.0f, float hi = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(lo, hi);
  Image im(w, h, ch);
  for (float& v : im.storage()) v = dist(rng);
  return im;
}

inline void add_pass(Frame& f, Role role, Image im) {
  Pass p;
  p.role = role;
  p.name = role_name(role);
  p.image = std::move(im);
  f.passes.push_back(std::move(p));
}

inline Frame colour_frame(const Image& colour) {
  Frame f;
  f.width = colour.width();
  f.height = colour.height();
  f.path = "test.exr";
  add_pass(f, Role::Colour, colour);
  return f;
}

inline Frame full_frame(int w, int h, unsigned seed) {
  Frame f = colour_frame(random_image(w, h, 3, seed));
  add_pass(f, Role::Normal, random_image(w, h, 3, seed + 1, -1.0f, 1.0f));
  add_pass(f, Role::Position, random_image(w, h, 3, seed + 2, 0.0f, 2.0f));
  add_pass(f, Role::Albedo, random_image(w, h, 3, seed + 3, 0.1f, 1.0f));
  add_pass(f, Role::Depth, random_image(w, h, 1, seed + 4, 1.0f, 3.0f));
  return f;
}

inline Image& pass_image(Frame& f, Role r) {
  for (Pass& p : f.passes)
    if (p.role == r) return p.image;
  throw std::runtime_error("no pass");
}

struct Result {
  Image out;
  std::size_t repaired = 0;
  std::vector<std::string> notes;
};

template <class F>
Result run_filter(const Frame& frame, const Params& params, int nthreads = 0, Roi roi = {}) {
  F f;
  for (const auto& [k, v] : params) f.set(k, v);
  f.commit();
  ExecOptions eo;
  eo.nthreads = nthreads;
  eo.roi = roi;
  Result r;
  r.out = f.execute(frame, eo);
  r.repaired = f.nonfinite_repaired();
  r.notes = f.notes();
  return r;
}

// The non-colour features an oracle weighs with: each enabled pass the frame has,
// its channel count and k = 1/(2 sigma^2), in Feature order.
struct OracleFeature {
  const Image* im;
  int ch;
  double k;
};
inline std::vector<OracleFeature> oracle_features(const Frame& frame, const ParamSet& ps) {
  std::vector<OracleFeature> feats;
  for (int i = 1; i < 5; ++i) {
    const std::string n = kFeatureNames[i];
    if (ps.get_enum("use_" + n) == "off" || !frame.has(kFeatureRoles[i])) continue;
    const double s = ps.get_float(n + "_sigma");
    feats.push_back({&frame.image(kFeatureRoles[i]), i == 4 ? 1 : 3, 1.0 / (2 * s * s)});
  }
  return feats;
}

inline Params all_off() {
  Params p;
  for (const char* n : kFeatureNames) p[std::string("use_") + n] = std::string("off");
  return p;
}

inline Params with(Params p, const Params& more) {
  for (const auto& [k, v] : more) p[k] = v;
  return p;
}

}  // namespace mcr::testutil
