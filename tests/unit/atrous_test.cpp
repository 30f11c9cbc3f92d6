// Edge-avoiding A-Trous against a brute-force double-precision cascade of the
// dilated generating kernels (Dammertz et al. 2010) with the documented policy.
#include "filters/image/atrous.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "util/error.h"
#include "util/isa.h"

namespace mcr {
namespace {

using namespace testutil;

Result run_on(const Frame& frame, const Params& params, int nthreads = 0, Roi roi = {}) {
  return run_filter<AtrousFilter>(frame, params, nthreads, roi);
}

Params mild() { return with(mild_features(), {{"iterations", std::int64_t(3)}}); }

std::vector<double> kernel_1d(int kg) {
  if (kg == 3) return {1 / 4.0, 2 / 4.0, 1 / 4.0};
  if (kg == 5) return {1 / 16.0, 4 / 16.0, 6 / 16.0, 4 / 16.0, 1 / 16.0};
  return {1 / 256.0, 8 / 256.0, 28 / 256.0, 56 / 256.0, 70 / 256.0, 56 / 256.0, 28 / 256.0, 8 / 256.0, 1 / 256.0};
}

// The documented cascade, in double: pass i spaces the k_g taps 2^(i-1) apart,
// weighs h(dx) h(dy) exp(-sum_f |f(p)-f(q)|^2 / (2 sigma_f^2)) with the colour
// compared on the pass' input and colour sigma * decay^(i-1); clipped and
// renormalised at the borders; non-finite policy as in the filter's info.
Image reference(const Frame& frame, const Params& given) {
  AtrousFilter probe;
  testutil::with_kernel_colour_weight(probe);
  for (const auto& [k, v] : given) probe.set(k, v);
  const ParamSet& ps = probe.params();
  const int w = frame.width, h = frame.height;
  const int kg = int(ps.get_int("kernel_size")), n = int(ps.get_int("iterations")), half = kg / 2;
  const std::vector<double> h1 = kernel_1d(kg);
  const double decay = ps.get_float("colour_sigma_decay");
  const bool use_colour = ps.get_enum("use_colour") != "off";
  const double sc = ps.get_float("colour_sigma");
  using F = OracleFeature;
  const std::vector<F> feats = oracle_features(frame, ps);
  const Image& colour = frame.image(Role::Colour);
  const std::size_t np = std::size_t(w) * h;
  std::vector<double> cur(np * 3, 0.0);
  std::vector<char> cok(np, 0), fv(np, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      if (finite_n(colour.pixel(x, y), 3)) {
        cok[i] = 1;
        for (int c = 0; c < 3; ++c) cur[i * 3 + c] = colour.at(x, y, c);
      }
      for (const F& f : feats) fv[i] = fv[i] && finite_n(f.im->pixel(x, y), f.ch);
    }
  for (int it = 1; it <= n; ++it) {
    const int step = 1 << (it - 1);
    const double sci = sc * std::pow(decay, it - 1);
    const double kc = 1.0 / (2 * sci * sci);
    std::vector<double> nxt(np * 3, 0.0);
    std::vector<char> nok(np, 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t p = std::size_t(y) * w + x;
        double s[3] = {0, 0, 0}, sw = 0;
        for (int j = -half; j <= half; ++j)
          for (int i = -half; i <= half; ++i) {
            const int qx = x + i * step, qy = y + j * step;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
            const std::size_t q = std::size_t(qy) * w + qx;
            if (!cok[q] || !fv[q]) continue;
            double e = 0;
            if (use_colour && cok[p])
              for (int c = 0; c < 3; ++c) e += kc * (cur[p * 3 + c] - cur[q * 3 + c]) * (cur[p * 3 + c] - cur[q * 3 + c]);
            for (const F& f : feats) {
              const float* a = f.im->pixel(x, y);
              const float* b = f.im->pixel(qx, qy);
              if (!finite_n(a, f.ch)) continue;
              for (int c = 0; c < f.ch; ++c) e += f.k * (double(a[c]) - b[c]) * (double(a[c]) - b[c]);
            }
            const double wq = h1[std::size_t(i + half)] * h1[std::size_t(j + half)] * std::exp(-e);
            for (int c = 0; c < 3; ++c) s[c] += wq * cur[q * 3 + c];
            sw += wq;
          }
        if (sw > 0) {
          for (int c = 0; c < 3; ++c) nxt[p * 3 + c] = s[c] / sw;
          nok[p] = 1;
        } else {
          for (int c = 0; c < 3; ++c) nxt[p * 3 + c] = cok[p] ? cur[p * 3 + c] : 0.0;
          nok[p] = cok[p];
        }
      }
    cur.swap(nxt);
    cok.swap(nok);
  }
  Image out(w, h, 3);
  for (std::size_t i = 0; i < np; ++i)
    for (int c = 0; c < 3; ++c) out.data()[i * 3 + c] = float(cur[i * 3 + c]);
  return out;
}

TEST(AtrousFilterTest, GeneratingKernels) {
  for (int kg : {3, 5, 9}) {
    const std::vector<float> h = AtrousFilter::generating_kernel(kg);
    ASSERT_EQ(int(h.size()), kg);
    double sum = 0;
    for (float v : h) sum += v;
    EXPECT_DOUBLE_EQ(sum, 1.0);
    for (int i = 0; i < kg; ++i) EXPECT_EQ(h[std::size_t(i)], h[std::size_t(kg - 1 - i)]);
  }
  // The 9-tap kernel is the B3 5-tap kernel convolved with itself.
  const std::vector<float> h5 = AtrousFilter::generating_kernel(5), h9 = AtrousFilter::generating_kernel(9);
  for (int i = 0; i < 9; ++i) {
    double s = 0;
    for (int j = 0; j < 5; ++j)
      if (i - j >= 0 && i - j < 5) s += double(h5[std::size_t(j)]) * h5[std::size_t(i - j)];
    EXPECT_DOUBLE_EQ(h9[std::size_t(i)], s);
  }
}

// Edge stopping off: the cascade of dilated kernels, computed directly.
TEST(AtrousFilterTest, AllEdgeStoppingOffIsTheDilatedKernelCascade) {
  const Frame f = colour_frame(random_image(37, 29, 3, 1));
  const Image& in = f.image(Role::Colour);
  for (int kg : {3, 5, 9})
    for (int n : {1, 2, 3, 4}) {
      SCOPED_TRACE(testing::Message() << "kg=" << kg << " iterations=" << n);
      const Image got = run_on(f, with(all_off(), {{"kernel_size", std::int64_t(kg)}, {"iterations", std::int64_t(n)}})).out;
      // Straight cascade, independent of reference(): h(dx) h(dy) at step 2^(i-1).
      const std::vector<double> h1 = kernel_1d(kg);
      std::vector<double> cur(in.storage().begin(), in.storage().end());
      for (int it = 1; it <= n; ++it) {
        const int step = 1 << (it - 1);
        std::vector<double> nxt(cur.size());
        for (int y = 0; y < f.height; ++y)
          for (int x = 0; x < f.width; ++x) {
            double s[3] = {0, 0, 0}, sw = 0;
            for (int j = 0; j < kg; ++j)
              for (int i = 0; i < kg; ++i) {
                const int qx = x + (i - kg / 2) * step, qy = y + (j - kg / 2) * step;
                if (qx < 0 || qy < 0 || qx >= f.width || qy >= f.height) continue;
                const double wq = h1[std::size_t(i)] * h1[std::size_t(j)];
                for (int c = 0; c < 3; ++c) s[c] += wq * cur[(std::size_t(qy) * f.width + qx) * 3 + c];
                sw += wq;
              }
            for (int c = 0; c < 3; ++c) nxt[(std::size_t(y) * f.width + x) * 3 + c] = s[c] / sw;
          }
        cur.swap(nxt);
      }
      for (std::size_t i = 0; i < cur.size(); ++i) ASSERT_NEAR(got.storage()[i], cur[i], 1e-5) << i;
    }
}

TEST(AtrousFilterTest, MatchesReferenceWithFeatures) {
  const Frame f = full_frame(41, 27, 2);
  for (double decay : {0.5, 1.0})
    for (int kg : {3, 5, 9}) {
      SCOPED_TRACE(testing::Message() << "kg=" << kg << " decay=" << decay);
      const Params p = {{"kernel_size", std::int64_t(kg)}, {"iterations", std::int64_t(3)},
                        {"colour_sigma", 0.6},              {"colour_sigma_decay", decay},
                        {"normal_sigma", 0.9},              {"position_sigma", 1.0},
                        {"albedo_sigma", 0.7},              {"use_depth", std::string("on")},
                        {"depth_sigma", 0.8}};
      expect_close(run_on(f, p).out, reference(f, p), 1e-4);
    }
}

TEST(AtrousFilterTest, TinyFeatureSigmaIsIdentity) {
  const Frame f = full_frame(20, 14, 3);
  for (const char* n : {"normal", "position", "albedo", "colour"}) {
    SCOPED_TRACE(n);
    const Params p = with(all_off(), {{std::string("use_") + n, std::string("on")}, {std::string(n) + "_sigma", 1e-6}});
    expect_close(run_on(f, p).out, f.image(Role::Colour), 1e-7);  // h^2 c / h^2: exact to rounding
  }
}

TEST(AtrousFilterTest, NormalEdgeIsPreserved) {
  const TwoSided s = two_sided(40, 24);
  Frame f = colour_frame(s.colour);
  add_pass(f, Role::Normal, s.normal);
  const Image out = run_on(f, with(all_off(), {{"use_normal", std::string("on")}, {"normal_sigma", 0.1},
                                               {"iterations", std::int64_t(4)}})).out;
  expect_edge_kept_and_flat_smoothed(out, s.colour, 2, 12);
}

TEST(AtrousFilterTest, ColourWeightStopsFireflies) {
  Image in(21, 21, 3, 0.5f);
  in.at(10, 10, 1) = 1e6f;
  // firefly_k=0: the colour weight alone, not the common outlier step, stops it.
  const Image out =
      run_on(colour_frame(in), with(all_off(), {{"use_colour", std::string("on")}, {"firefly_k", 0.0}})).out;
  EXPECT_FLOAT_EQ(out.at(11, 10, 1), 0.5f);
  EXPECT_FLOAT_EQ(out.at(6, 14, 1), 0.5f);
}

TEST(AtrousFilterTest, ConstantImageAndEqualFeatures) {
  expect_constant_stays_constant(run_on, {{"iterations", std::int64_t(3)}});
}

TEST(AtrousFilterTest, ParameterLimits) {
  const Frame f = full_frame(23, 17, 4);
  // 10 passes of k_g 9 reach 4 * 1023 pixels, far beyond the image.
  const Params big = with(mild(), {{"kernel_size", std::int64_t(9)}, {"iterations", std::int64_t(10)},
                                   {"colour_sigma_decay", 1.0}});
  expect_close(run_on(f, big).out, reference(f, big), 1e-4);
  const Params fast_decay = with(mild(), {{"iterations", std::int64_t(4)}, {"colour_sigma_decay", 0.05}});
  expect_close(run_on(f, fast_decay).out, reference(f, fast_decay), 1e-4);
  const Params flat = {{"iterations", std::int64_t(1)}, {"colour_sigma", 1e6}, {"normal_sigma", 1e6},
                       {"position_sigma", 1e6}, {"albedo_sigma", 1e6}};
  expect_close(run_on(f, flat).out, run_on(f, with(all_off(), {{"iterations", std::int64_t(1)}})).out, 1e-5);
  auto a = make_filter("atrous");
  EXPECT_THROW(a->set("iterations", std::int64_t(11)), Error);
  EXPECT_THROW(a->set("iterations", std::int64_t(0)), Error);
  a->set("kernel_size", std::int64_t(4));
  try {
    a->commit();
    FAIL() << "kernel_size 4 must be rejected";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::ParameterOutOfRange);
    EXPECT_NE(std::string(e.what()).find("kernel_size"), std::string::npos);
  }
}

TEST(AtrousFilterTest, DegenerateShapes) {
  expect_degenerate_shapes_match(run_on, reference, mild(), {19, 2});
}

TEST(AtrousFilterTest, TinyAndHugeValues) {
  expect_tiny_and_huge_values_handled(
      run_on, reference,
      {Params{{"iterations", std::int64_t(3)}, {"normal_sigma", 1.0}}, with(all_off(), {{"iterations", std::int64_t(3)}})},
      with(all_off(), {{"iterations", std::int64_t(4)}}));
}

TEST(AtrousFilterTest, NonFiniteColourAndFeaturesFollowThePolicy) {
  const Params p = {{"iterations", std::int64_t(3)}, {"colour_sigma", 0.6}, {"normal_sigma", 1.0},
                    {"position_sigma", 1.0}, {"albedo_sigma", 0.8}, {"use_depth", std::string("on")},
                    {"depth_sigma", 1.0}};
  for (Role role : kFeatureRoles) {
    SCOPED_TRACE(role_name(role));
    Frame f = full_frame(19, 15, 9);
    poison(pass_image(f, role), Roi{11, 0, 18, 4});  // a blob wider than the first pass' reach
    Result r = run_on(f, p);
    ASSERT_NO_FATAL_FAILURE(expect_finite_unrepaired(r));
    expect_close(r.out, reference(f, p), 1e-4);
  }
}

TEST(AtrousFilterTest, ZeroAlbedoWithDemodulation) {
  expect_finite_unrepaired(run_on(zero_albedo_frame(), {{"demodulate", true}}));
}

TEST(AtrousFilterTest, AbsentFeaturesAreDroppedWithANoteOrRequired) {
  const Frame f = colour_frame(random_image(10, 8, 3, 7));
  EXPECT_TRUE(has_note(run_on(f, {}), "normal weight dropped"));
  EXPECT_THROW(run_on(f, {{"use_position", std::string("on")}}), Error);
}

TEST(AtrousFilterTest, IdenticalForOneAndTwoThreads) {
  Frame f = full_frame(70, 45, 11);
  pass_image(f, Role::Position).at(5, 5, 1) = kNaN;
  pass_image(f, Role::Colour).at(50, 20, 0) = kInf;
  expect_same_for_one_and_two_threads(
      run_on, f,
      {with(mild(), {{"iterations", std::int64_t(4)}}),
       with(mild(), {{"foveated", true}, {"colour_sigma", 0.1}, {"colour_sigma_outer", 2.0},
                     {"normal_sigma_outer", 3.0}, {"inner_radius", 0.05}})});
}

TEST(AtrousFilterTest, RegionChangesOnlyPixelsInside) {
  expect_region_changes_only_inside(run_on, full_frame(50, 36, 12), Roi{13, 9, 31, 20},
                                    with(mild(), {{"iterations", std::int64_t(4)}, {"kernel_size", std::int64_t(5)}}));
}

TEST(AtrousFilterTest, EveryInstructionSetMatchesTheReference) {
  Frame f = full_frame(45, 21, 22);
  pass_image(f, Role::Albedo).at(7, 7, 0) = kNaN;
  pass_image(f, Role::Colour).at(40, 3, 2) = -kInf;
  const Params p = {{"iterations", std::int64_t(3)}, {"use_depth", std::string("on")}, {"normal_sigma", 0.9},
                    {"position_sigma", 1.2}, {"albedo_sigma", 0.6}};
  const int ran = for_each_isa([&](Isa) {
    expect_close(run_on(f, p).out, reference(f, p), 1e-4);
    EXPECT_EQ(run_on(f, p, 1).out.storage(), run_on(f, p, 2).out.storage());
  });
  EXPECT_GE(ran, 1);
}

TEST(AtrousFilterTest, ScratchReuseAcrossFrames) {
  // The same filter object on frames of different sizes and passes gives what a fresh one gives.
  AtrousFilter f;
  testutil::without_step_back(f);
  testutil::with_kernel_colour_weight(f);
  for (const auto& [k, v] : mild()) f.set(k, v);
  f.set("use_depth", std::string("auto"));
  f.commit();
  const Frame a = full_frame(40, 30, 13), b = colour_frame(random_image(17, 23, 3, 14)), c = full_frame(40, 30, 15);
  for (const Frame* fr : {&a, &b, &c, &a}) {
    const Image got = f.execute(*fr);
    expect_close(got, run_on(*fr, with(mild(), {{"use_depth", std::string("auto")}})).out, 0.0);
  }
  // And a region after a full frame: stale planes from the last frame must not leak in.
  const Roi roi{5, 4, 20, 17};
  ExecOptions eo;
  eo.roi = roi;
  const Image part = f.execute(c, eo);
  const Image full = run_on(c, with(mild(), {{"use_depth", std::string("auto")}})).out;
  for (int y = roi.y0; y < roi.y1; ++y)
    for (int x = roi.x0; x < roi.x1; ++x) ASSERT_EQ(part.at(x, y, 1), full.at(x, y, 1)) << x << "," << y;
}

TEST(AtrousFilterTest, DefaultsFollowTheNoise) {
  AtrousFilter f;
  EXPECT_EQ(f.params().get_enum("colour_weight"), "noise");
  EXPECT_EQ(f.params().get_float("colour_sigma"), 4.0);
  EXPECT_EQ(f.params().get_float("albedo_sigma"), 0.05);
  expect_defaults_follow_the_noise<AtrousFilter>();
}

}  // namespace
}  // namespace mcr
