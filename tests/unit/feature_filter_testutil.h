#pragma once
// Shared by the image-filter tests (gaussian, bilateral, atrous, guided, foveation): random
// frames with every feature pass, a one-call run of a filter with a parameter map, and the
// checks the feature filters (bilateral, atrous) share, each given the filter's run and oracle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "filters/filter.h"
#include "util/isa.h"

namespace mcr::testutil {

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline const char* const kFeatureNames[5] = {"colour", "normal", "position", "albedo", "depth"};
inline const Role kFeatureRoles[5] = {Role::Colour, Role::Normal, Role::Position, Role::Albedo, Role::Depth};

using Params = std::map<std::string, ParamValue>;

// Every one of the n values at p is finite.
inline bool finite_n(const float* p, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(p[i])) return false;
  return true;
}

// Mean of the colour over the (2r+1)^2 window clipped at the borders, in double.
inline Image box_oracle(const Image& in, int r) {
  Image out(in.width(), in.height(), 3);
  for (int y = 0; y < in.height(); ++y)
    for (int x = 0; x < in.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        double s = 0;
        int n = 0;
        for (int qy = std::max(0, y - r); qy <= std::min(in.height() - 1, y + r); ++qy)
          for (int qx = std::max(0, x - r); qx <= std::min(in.width() - 1, x + r); ++qx, ++n) s += in.at(qx, qy, c);
        out.at(x, y, c) = float(s / n);
      }
  return out;
}

// relMSE of the RGB of `a` against `ref` as the metrics define it, written out plainly.
inline double relmse_oracle(const Image& a, const Image& ref) {
  double s = 0;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const double d = double(a.at(x, y, c)) - ref.at(x, y, c);
        s += d * d / (double(ref.at(x, y, c)) * ref.at(x, y, c) + 0.01);
      }
  return s / (3.0 * double(a.pixel_count()));
}

inline Image random_image(int w, int h, int ch, unsigned seed, float lo = 0.0f, float hi = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(lo, hi);
  Image im(w, h, ch);
  for (float& v : im.storage()) v = dist(rng);
  return im;
}

inline Pass named_pass(Role role, std::string name, Image im) {
  Pass p;
  p.role = role;
  p.name = std::move(name);
  p.image = std::move(im);
  return p;
}

inline void add_pass(Frame& f, Role role, Image im) { f.passes.push_back(named_pass(role, role_name(role), std::move(im))); }

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

// Sets the parameters (name, value pairs in any container) on a fresh filter object,
// commits and runs it once.
// The filter's own algorithm, as its oracles define it: the step back (which blends the
// result toward the input, prepare/step_back.h) off unless a test sets it.
inline void without_step_back(Filter& f) {
  if (f.params().has("step_back")) f.set("step_back", false);
}

// The oracles of bilateral and atrous weigh colour in radiance units with colour_sigma 2
// and albedo_sigma 0.1 (the kernel's own defaults); the filters' defaults are
// colour_weight=noise, colour_sigma 4, albedo_sigma 0.05 (tested on their own). Set
// before the test's parameters, which override them.
inline void with_kernel_colour_weight(Filter& f) {
  if (!f.params().has("colour_weight")) return;
  f.set("colour_weight", std::string("absolute"));
  for (const char* suffix : {"", "_outer"}) {
    if (!f.params().has(std::string("colour_sigma") + suffix)) continue;
    f.set(std::string("colour_sigma") + suffix, 2.0);
    f.set(std::string("albedo_sigma") + suffix, 0.1);
  }
}

template <class ParamList>
Result run_filter(Filter& f, const Frame& frame, const ParamList& params, int nthreads = 0, Roi roi = {}) {
  without_step_back(f);
  with_kernel_colour_weight(f);
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

template <class F>
Result run_filter(const Frame& frame, const Params& params, int nthreads = 0, Roi roi = {}) {
  F f;
  return run_filter(f, frame, params, nthreads, roi);
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

// Feature sigmas wide enough that random features still let neighbours mix (the
// defaults make random data close to the identity, which would prove little), depth on.
inline Params mild_features() {
  return {{"colour_sigma", 0.8}, {"normal_sigma", 1.0}, {"position_sigma", 1.5},
          {"albedo_sigma", 0.8}, {"use_depth", std::string("on")}, {"depth_sigma", 1.0}};
}

// ---------------------------------------------------------------------------
// Checks shared by the feature filters. RunFn is the test's run_on (frame, parameters,
// thread count, region); RefFn its oracle (frame, parameters).

using RunFn = std::function<Result(const Frame&, const Params&, int, Roi)>;
using RefFn = std::function<Image(const Frame&, const Params&)>;

// Fraction of values that moved by more than 1e-3: the filter did something.
inline double changed(const Image& out, const Image& in) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < out.storage().size(); ++i) n += std::fabs(out.storage()[i] - in.storage()[i]) > 1e-3f;
  return double(n) / double(out.storage().size());
}

// |got - want| <= rel * max(1, |want|) in the three colour channels of every pixel.
inline void expect_close(const Image& got, const Image& want, double rel, const char* what = "") {
  ASSERT_EQ(got.width(), want.width());
  ASSERT_EQ(got.height(), want.height());
  for (int y = 0; y < got.height(); ++y)
    for (int x = 0; x < got.width(); ++x)
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(got.at(x, y, c), want.at(x, y, c), rel * std::max(1.0f, std::fabs(want.at(x, y, c))))
            << what << " pixel " << x << "," << y << " channel " << c;
}

// Nothing repaired by the base class' safety net and every output value finite.
inline void expect_finite_unrepaired(const Result& r) {
  EXPECT_EQ(r.repaired, 0u);
  for (float v : r.out.storage()) ASSERT_TRUE(std::isfinite(v));
}

inline bool has_note(const Result& r, const std::string& part) {
  for (const std::string& n : r.notes)
    if (n.find(part) != std::string::npos) return true;
  return false;
}

// A constant colour with all-equal features (even huge) stays that constant.
inline void expect_constant_stays_constant(const RunFn& run, const Params& p) {
  for (float v : {0.0f, 0.375f, -2.5f, 1e-30f, 1e30f, 3.3e38f, FLT_MAX}) {
    Frame f = colour_frame(Image(13, 9, 3, v));
    add_pass(f, Role::Normal, Image(13, 9, 3, 0.5f));
    add_pass(f, Role::Position, Image(13, 9, 3, v));
    add_pass(f, Role::Albedo, Image(13, 9, 3, 0.0f));
    Result r = run(f, p, 0, {});
    EXPECT_EQ(r.repaired, 0u);
    for (float o : r.out.storage()) ASSERT_NEAR(o, v, 1e-6 * std::fabs(v)) << "constant " << v;
  }
}

// 1x1, single rows and columns, two pixels and one wider strip (w x h): the oracle's result.
inline void expect_degenerate_shapes_match(const RunFn& run, const RefFn& ref, const Params& p,
                                           std::pair<int, int> strip) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{1, 9}, std::pair{9, 1}, std::pair{2, 1}, std::pair{1, 2}, strip}) {
    SCOPED_TRACE(testing::Message() << w << "x" << h);
    const Frame f = full_frame(w, h, unsigned(w * 31 + h));
    expect_close(run(f, p, 0, {}).out, ref(f, p), 1e-4);
  }
}

// Colour 1e-30 with a +-1e30 pixel, random normals, positions 1e30: each parameter set is
// finite, unrepaired and the oracle's result; then an all-FLT_MAX colour (one -FLT_MAX)
// with `big` is finite and unrepaired.
inline void expect_tiny_and_huge_values_handled(const RunFn& run, const RefFn& ref, std::initializer_list<Params> ps,
                                                const Params& big_params) {
  Image in(30, 20, 3, 1e-30f);
  in.at(5, 5, 0) = 1e30f;
  in.at(5, 5, 1) = -1e30f;
  Frame f = colour_frame(in);
  add_pass(f, Role::Normal, random_image(30, 20, 3, 8));
  add_pass(f, Role::Position, Image(30, 20, 3, 1e30f));
  for (const Params& p : ps) {
    Result r = run(f, p, 0, {});
    ASSERT_NO_FATAL_FAILURE(expect_finite_unrepaired(r));
    expect_close(r.out, ref(f, p), 1e-4);
  }
  Image big(12, 12, 3, FLT_MAX);
  big.at(2, 2, 2) = -FLT_MAX;
  ASSERT_NO_FATAL_FAILURE(expect_finite_unrepaired(run(colour_frame(big), big_params, 0, {})));
}

// NaN at (4,4), Inf at (10,7), -Inf in the corner (18,14) of a 19x15 pass, and a NaN blob.
inline void poison(Image& im, Roi blob) {
  im.at(4, 4, 0) = kNaN;
  im.at(10, 7, std::min(1, im.channels() - 1)) = kInf;
  im.at(18, 14, 0) = -kInf;
  for (int y = blob.y0; y < blob.y1; ++y)
    for (int x = blob.x0; x < blob.x1; ++x) im.at(x, y, 0) = kNaN;
}

// full_frame(16, 12, 10) with an all-zero albedo.
inline Frame zero_albedo_frame() {
  Frame f = full_frame(16, 12, 10);
  for (float& v : pass_image(f, Role::Albedo).storage()) v = 0.0f;
  return f;
}

// The same bits on one and two threads, and a result that differs from the input.
inline void expect_same_for_one_and_two_threads(const RunFn& run, const Frame& f, std::initializer_list<Params> ps) {
  for (const Params& p : ps) {
    const Image one = run(f, p, 1, {}).out;
    const Image two = run(f, p, 2, {}).out;
    EXPECT_EQ(one.storage(), two.storage());
    EXPECT_GT(changed(one, f.image(Role::Colour)), 0.3);
  }
}

// The result of a run with a region (part): the whole-frame result inside, the input outside.
inline void expect_only_region_changed(const Image& part, const Image& full, const Image& in, Roi roi) {
  for (int y = 0; y < in.height(); ++y)
    for (int x = 0; x < in.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const bool inside = x >= roi.x0 && x < roi.x1 && y >= roi.y0 && y < roi.y1;
        ASSERT_EQ(part.at(x, y, c), inside ? full.at(x, y, c) : in.at(x, y, c)) << x << "," << y;
      }
}

// With a region: the whole-frame result inside, the input colour outside.
inline void expect_region_changes_only_inside(const RunFn& run, const Frame& f, Roi roi, const Params& p) {
  const Image full = run(f, p, 0, {}).out;
  const Image& in = f.image(Role::Colour);
  ASSERT_NO_FATAL_FAILURE(expect_only_region_changed(run(f, p, 0, roi).out, full, in, roi));
  EXPECT_GT(changed(full, in), 0.5);
}

// out has in's size and 3 channels, and each value lies within rel * max(1, |want|) of
// want(x, y, double[3]), the oracle's pixel; what(x, y), a testing::Message, names the setting.
template <class Want, class What>
void expect_each_pixel_near(const Image& in, const Image& out, Want&& want, double rel, What&& what) {
  ASSERT_EQ(out.width(), in.width());
  ASSERT_EQ(out.height(), in.height());
  ASSERT_EQ(out.channels(), 3);
  for (int y = 0; y < in.height(); ++y)
    for (int x = 0; x < in.width(); ++x) {
      double w[3];
      want(x, y, w);
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(out.at(x, y, c), w[c], rel * std::max(1.0, std::fabs(w[c])))
            << "pixel " << x << "," << y << " channel " << c << what(x, y);
    }
}

// Runs body once per instruction set this CPU has (generic, AVX2, AVX-512), that set in
// force; returns how many ran.
inline int for_each_isa(const std::function<void(Isa)>& body) {
  int ran = 0;
  for (Isa level : {Isa::Generic, Isa::Avx2, Isa::Avx512}) {
    if (int(level) > int(best_isa())) continue;
    const ScopedIsa use(level);
    SCOPED_TRACE(isa_name(level));
    body(level);
    ++ran;
  }
  return ran;
}

// A w x h colour: 0.2 left of x = w/2, 0.8 right of it, with +-0.05 noise (seed 6); normals
// +z on the left and +x on the right; positions with a depth step of 5 at the same edge.
struct TwoSided {
  Image colour, normal, position;
};
inline TwoSided two_sided(int w, int h) {
  TwoSided s{random_image(w, h, 3, 6, -0.05f, 0.05f), Image(w, h, 3, 0.0f), Image(w, h, 3, 0.0f)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool left = x < w / 2;
      for (int c = 0; c < 3; ++c) s.colour.at(x, y, c) += left ? 0.2f : 0.8f;
      s.normal.at(x, y, left ? 2 : 0) = 1.0f;
      s.position.at(x, y, 2) = left ? 0.0f : 5.0f;
    }
  return s;
}

// The pixels next to the edge keep their own side (channel 0 on the left, right_channel on
// the right, within 0.03), and columns 2 .. flat_x1-1 lose 90% of their variance.
inline void expect_edge_kept_and_flat_smoothed(const Image& out, const Image& colour, int right_channel,
                                               int flat_x1) {
  const int w = colour.width(), h = colour.height();
  double var_in = 0, var_out = 0;
  for (int y = 0; y < h; ++y) {
    EXPECT_NEAR(out.at(w / 2 - 1, y, 0), 0.2f, 0.03f) << "left of the edge, row " << y;
    EXPECT_NEAR(out.at(w / 2, y, right_channel), 0.8f, 0.03f) << "right of the edge, row " << y;
    for (int x = 2; x < flat_x1; ++x) {
      var_in += std::pow(colour.at(x, y, 0) - 0.2, 2);
      var_out += std::pow(out.at(x, y, 0) - 0.2, 2);
    }
  }
  EXPECT_LT(var_out, 0.1 * var_in) << "flat regions are smoothed";
}

// The noise-relative defaults of bilateral and atrous (colour_weight=noise, colour_sigma 4):
// blocks of 16 px at levels in [0.5, 2] with white noise of std 0.1, the block edges in the
// albedo pass (as texture edges are; colour 4 noise deviations alone lets steps of a few
// deviations through).
//  - scaled by L = 1e-3 or 1e3, the result scales by L (the colour weight counts noise
//    standard deviations, which scale with the image); with the radiance-unit weight it does not;
//  - the noise left is under a quarter of the input's (mean squared error to the clean blocks).
template <class F>
void expect_defaults_follow_the_noise() {
  const int w = 64, h = 48;
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> level(0.5f, 2.0f);
  std::normal_distribution<float> noise(0.0f, 0.1f);
  std::vector<float> lv(4 * 3 * 3);
  for (float& v : lv) v = level(rng);
  Image clean(w, h, 3), noisy(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        clean.at(x, y, c) = lv[std::size_t(((y / 16) * 4 + x / 16) * 3 + c)];
        noisy.at(x, y, c) = clean.at(x, y, c) + noise(rng);
      }
  Image albedo = clean;
  for (float& v : albedo.storage()) v *= 0.5f;
  auto run = [&albedo](const Image& colour, const Params& params) {
    F f;
    without_step_back(f);
    for (const auto& [k, v] : params) f.set(k, v);
    f.commit();
    Frame fr = colour_frame(colour);
    add_pass(fr, Role::Albedo, albedo);
    return f.execute(fr);
  };
  auto scaled = [](Image im, float l) {
    for (float& v : im.storage()) v *= l;
    return im;
  };
  // Largest |a - l b| relative to l.
  auto off_by = [](const Image& a, const Image& b, float l) {
    double m = 0;
    for (std::size_t i = 0; i < a.storage().size(); ++i)
      m = std::max(m, std::fabs(double(a.storage()[i]) - double(l) * b.storage()[i]) / l);
    return m;
  };
  const Image base = run(noisy, {});
  const Image absolute = run(noisy, {{"colour_weight", std::string("absolute")}});
  for (float l : {1e-3f, 1e3f}) {
    SCOPED_TRACE(l);
    EXPECT_LT(off_by(run(scaled(noisy, l), {}), base, l), 1e-4);
    // In radiance units sigma 4 stops nothing at L = 1 and every neighbour at L = 1e3.
    if (l > 1) EXPECT_GT(off_by(run(scaled(noisy, l), {{"colour_weight", std::string("absolute")}}), absolute, l), 1e-2);
  }
  double in = 0, out = 0;
  for (std::size_t i = 0; i < clean.storage().size(); ++i) {
    in += std::pow(noisy.storage()[i] - clean.storage()[i], 2);
    out += std::pow(base.storage()[i] - clean.storage()[i], 2);
  }
  EXPECT_LT(out, 0.25 * in);
}

}  // namespace mcr::testutil
