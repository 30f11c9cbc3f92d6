// pipeline/auto_filter: what it chooses on renders whose truth is known, what it reports,
// and that its result is the chosen filter's.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "io/frame_reader.h"
#include "pipeline/auto_filter.h"
#include "pipeline/filter_catalog.h"
#include "util/error.h"

namespace mcr {
namespace {

// Blocks of 16 px (levels in [0.1, 1.5], one albedo per block), a normal per block, noise of
// relative deviation `sigma`. The features explain every edge.
Frame blocks(int w, int h, double sigma, unsigned seed, Image* clean_out, double fireflies = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> level(0.1f, 1.5f);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const int bw = w / 16 + 1;
  std::vector<float> lv(std::size_t(bw * (h / 16 + 1)) * 3);
  for (float& v : lv) v = level(rng);
  Image clean(w, h, 3), noisy(w, h, 3), albedo(w, h, 3), normal(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t b = std::size_t((y / 16) * bw + x / 16);
      for (int c = 0; c < 3; ++c) {
        const float v = lv[b * 3 + std::size_t(c)] * (0.8f + 0.4f * float(y) / float(h));
        clean.at(x, y, c) = v;
        noisy.at(x, y, c) = std::max(0.0f, v * (1.0f + float(sigma) * noise(rng)));
      }
      // Monte Carlo's heavy tail: a few samples far out.
      if (fireflies > 0 && std::uniform_real_distribution<double>(0, 1)(rng) < fireflies)
        for (int c = 0; c < 3; ++c) noisy.at(x, y, c) *= 30.0f;
      for (int c = 0; c < 3; ++c) {
        albedo.at(x, y, c) = lv[b * 3 + std::size_t(c)] / 1.5f;
      }
      const float a = 0.3f * float(b % 5);
      normal.at(x, y, 0) = std::sin(a);
      normal.at(x, y, 1) = 0.0f;
      normal.at(x, y, 2) = std::cos(a);
    }
  *clean_out = clean;
  Frame f = testutil::colour_frame(noisy);
  testutil::add_pass(f, Role::Albedo, albedo);
  testutil::add_pass(f, Role::Normal, normal);
  return f;
}

double relmse(const Image& a, const Image& ref) { return testutil::relmse_oracle(a, ref); }

// What auto's choice named `choice` ("a", or "a+b" for the mean of two) gives, run whole on f:
// each filter run once, by name, with its defaults.
class ChoiceRunner {
 public:
  explicit ChoiceRunner(const Frame& f) : f_(f) {}
  Image run(const std::string& choice) {
    const std::size_t plus = choice.find('+');
    if (plus == std::string::npos) return single(choice);
    Image m = single(choice.substr(0, plus));
    const Image& b = single(choice.substr(plus + 1));
    for (int y = 0; y < m.height(); ++y)
      for (int x = 0; x < m.width(); ++x)
        for (int c = 0; c < m.channels(); ++c) m.at(x, y, c) = 0.5f * m.at(x, y, c) + 0.5f * b.at(x, y, c);
    return m;
  }

 private:
  const Image& single(const std::string& name) {
    auto it = cache_.find(name);
    if (it != cache_.end()) return it->second;
    auto c = make_filter(name);
    c->commit();
    ExecOptions eo;
    eo.nthreads = 2;
    return cache_.emplace(name, c->execute(f_, eo)).first->second;
  }
  const Frame& f_;
  std::map<std::string, Image> cache_;
};

// The oracle: the lowest true relMSE among the choices auto scored (filters and means of two,
// or the filters alone), each run whole.
double best_candidate(const AutoFilter& a, const Frame& f, const Image& ref, bool singles_only = false) {
  double best = 1e300;
  ChoiceRunner runner(f);
  for (const AutoScore& s : a.scores()) {
    if (s.filter == "input" || (singles_only && s.filter.find('+') != std::string::npos)) continue;
    best = std::min(best, relmse(runner.run(s.filter), ref));
  }
  return best;
}

Image run_auto(const Frame& f, AutoFilter& a, Roi roi = {}) {
  a.commit();
  ExecOptions eo;
  eo.roi = roi;
  eo.nthreads = 2;
  return a.execute(f, eo);
}

TEST(AutoFilter, ANoisyRenderIsFilteredAndTheChoiceIsAmongTheBest) {
  for (auto [sigma, fireflies] : {std::pair{0.2, 0.0}, std::pair{0.6, 0.0}, std::pair{0.3, 0.01}}) {
    SCOPED_TRACE(testing::Message() << sigma << " fireflies " << fireflies);
    Image clean;
    const Frame f = blocks(160, 128, sigma, 3, &clean, fireflies);
    AutoFilter a;
    const Image out = run_auto(f, a);
    ASSERT_NE(a.chosen(), "input");
    const double in_err = relmse(f.image(Role::Colour), clean), err = relmse(out, clean);
    EXPECT_LT(err, 0.3 * in_err);
    // Within 2x of the best candidate's true error (the oracle: every candidate run whole).
    double best = 1e300;
    for (const std::string& name : image_filter_names()) {
      auto c = make_filter(name);
      if (c->info().temporal || !c->missing_passes(f).empty()) continue;
      c->commit();
      best = std::min(best, relmse(c->execute(f), clean));
    }
    // With fireflies within 2.5x: the held-out score ranks atrous (0.00505) ahead of pwaf, which
    // step_back_noise = 2 made 2x better here (0.00245; scores -0.034 against -0.016).
    EXPECT_LT(err, (fireflies > 0 ? 2.5 : 2.0) * best);
  }
}

// The per-sample sample scenes (clean 16-spp renders, sharp aliased detail, depth of field,
// motion blur; the variance from the halves of each pixel's samples): no candidate's estimated
// gain over the input is more than 3x worse than its true gain (relMSE against the 1024-spp
// reference), and the choice is within 10% of the best candidate. Before the per-pixel
// divergence was kept to its range, pwaf's radius jumping under the probe gave it an estimate
// 24x the input's on dof_spheres (truly a third of it) and auto chose gaussian. (The other way
// the estimates are optimistic on dof_garden, every candidate's gain 3-6x its true one: the
// input's own estimate runs high there. Not asserted.)
TEST(AutoFilter, ItsEstimatesFollowTheTruthOnThePerSampleScenes) {
  const std::string dir = std::string(MCRECON_SOURCE_DIR) + "/samples/data/per_sample/";
  for (const char* scene : {"dof", "motion", "dof_garden", "dof_spheres"}) {
    SCOPED_TRACE(scene);
    const Frame f = read_frame(dir + scene + "_16spp_deep.exr");
    const Image ref = read_frame(dir + scene + "_ref.exr").image(Role::Colour);
    AutoFilter a;
    const Image out = run_auto(f, a);
    double est_input = 0;
    for (const AutoScore& s : a.scores())
      if (s.filter == "input") est_input = s.relmse;
    ASSERT_GT(est_input, 0.0);
    const double true_input = relmse(f.image(Role::Colour), ref);
    double best = 1e300;
    ChoiceRunner runner(f);
    for (const AutoScore& s : a.scores()) {
      if (s.filter == "input") continue;
      const double truth = relmse(runner.run(s.filter), ref);
      best = std::min(best, truth);
      const double est_gain = s.relmse / est_input, true_gain = truth / true_input;
      EXPECT_LT(est_gain, 3.0 * true_gain) << s.filter;
    }
    EXPECT_LT(relmse(out, ref), 1.1 * best) << "chose " << a.chosen();
  }
}

// Monte Carlo's skewed noise, no variance pass: each pixel the mean of n samples that find the
// light with probability p, each worth level / p (a relative deviation sqrt((1 - p) / (n p))),
// a depth per block so that guided runs too. The choice is within 1.5x of the best candidate's
// true error (the oracle: every candidate run whole against the clean image; their truths lie
// within 1.4x of each other but for gaussian and box, 3x), the check
// confirms it, and its estimate of the input's relMSE is within 1.5x of the truth.
TEST(AutoFilter, TheHeldOutScoresChooseWellUnderSkewedNoise) {
  for (auto [n, p] : {std::pair{16, 0.1}, std::pair{4, 0.25}}) {
    SCOPED_TRACE(testing::Message() << n << " samples, p " << p);
    Image clean;
    Frame f = blocks(192, 160, 0.0, 8, &clean);
    Image depth(192, 160, 1);
    for (int yy = 0; yy < 160; ++yy)
      for (int x = 0; x < 192; ++x) depth.at(x, yy, 0) = 2.0f + float((yy / 16 * 13 + x / 16) % 5);
    testutil::add_pass(f, Role::Depth, depth);
    std::mt19937 rng(11);
    std::binomial_distribution<int> hits(n, p);
    Image& y = f.passes[0].image;
    for (int yy = 0; yy < y.height(); ++yy)
      for (int x = 0; x < y.width(); ++x) {
        const float k = float(hits(rng)) / float(n * p);
        for (int c = 0; c < 3; ++c) y.at(x, yy, c) = clean.at(x, yy, c) * k;
      }
    AutoFilter a;
    const Image out = run_auto(f, a);
    ASSERT_NE(a.chosen(), "input");
    EXPECT_EQ(a.check().filter, a.chosen());
    EXPECT_LT(relmse(out, clean), 1.5 * best_candidate(a, f, clean)) << "chose " << a.chosen();
    const double in_truth = relmse(y, clean);
    EXPECT_GT(a.check().input, in_truth / 1.5);
    EXPECT_LT(a.check().input, in_truth * 1.5);
  }
}

// The tune stills (room, glossy) at 4, 16 and 64 spp, no variance pass: the choice is within
// 1.3x of the best filter's true relMSE against the 2048-spp reference (the oracle: every
// filter run whole; the best mean of two is up to 1.5x below what auto chooses here, room at 4
// spp: atrous+guided 0.057 against guided's 0.085, a gain the scores do not see). SURE from the image's noise estimate chose pwaf on room at 16 spp (1.8x
// the best) and guided at 64 (1.5x).
TEST(AutoFilter, TheHeldOutScoresChooseWellOnTheTuneStills) {
  for (const char* scene : {"room", "glossy"}) {
    const std::string dir = std::string(MCRECON_SOURCE_DIR) + "/samples/data/" + scene + "/" + scene;
    const Image ref = read_frame(dir + "_ref.exr").image(Role::Colour);
    for (const char* spp : {"4", "16", "64"}) {
      SCOPED_TRACE(testing::Message() << scene << " " << spp << " spp");
      const Frame f = read_frame(dir + "_" + spp + "spp.exr");
      AutoFilter a;
      const Image out = run_auto(f, a);
      EXPECT_LT(relmse(out, ref), 1.3 * best_candidate(a, f, ref, true)) << "chose " << a.chosen();
    }
  }
}

// Issue 14, point 1: on a reference (2048 spp, colour only) auto is no worse than its input,
// measured against the reference itself: only the input as it is holds that. The image's own
// noise estimate reads room's and sunlit's remaining noise and detail as noise worth filtering
// (SURE scores pwaf and gaussian well below the input); the blind-spot check, which scores
// what a filter makes of a pixel from its neighbours, does not confirm them. (glossy's and
// showroom's references are still filtered: README, "Where auto still misses".)
// Oracle: a reference against itself (relMSE 0). glossy: a sun's reflection on a chrome sphere
// (93 among 0.06) inflates the window noise estimate beside it; showroom: one far-out pixel
// (16.8 among 0.56) in 2048 spp.
TEST(AutoFilter, TheReferencesAreKeptAsTheyAre) {
  // night: a street at its physical brightness, its fine detail read as noise once the exposure
  // step has scaled it (the candidates rank above the input, the check alone passed pwaf).
  for (const char* scene : {"room", "glossy", "sunlit", "dof", "showroom", "wall", "fog", "fence", "night", "studio", "product", "cutout"}) {
    SCOPED_TRACE(scene);
    const Frame f = read_frame(std::string(MCRECON_SOURCE_DIR) + "/samples/data/" + scene + "/" + scene + "_ref.exr");
    AutoFilter a;
    const Image out = run_auto(f, a);
    EXPECT_EQ(a.chosen(), "input");
    EXPECT_EQ(relmse(out, f.image(Role::Colour)), 0.0);
  }
}

// Held-out pixels need full coverage (alpha 1 around them) where a tile has any: above, the
// product still's reference. A render whose alpha is below 1 everywhere alike (a veil of smoke
// over a transparent world) is scored on the pixels covered alike instead, as if opaque: the
// glossy still at 16 spp with alpha 0.5 everywhere gives auto's choice and output with alpha 1
// (with full coverage required everywhere no pixel is held out, every score is 0, and the input
// was kept as converged). The alpha 1 -> 0.5 -> 0 and back at a coverage edge is left out.
TEST(AutoFilter, AVeilOfAlphaIsScoredLikeAnOpaqueRender) {
  const Frame opaque = read_frame(std::string(MCRECON_SOURCE_DIR) + "/samples/data/glossy/glossy_16spp.exr");
  ASSERT_NE(opaque.find(Role::Alpha), nullptr);
  Frame veiled = opaque;
  for (Pass& p : veiled.passes)
    if (p.role == Role::Alpha)
      for (std::size_t i = 0; i < p.image.pixel_count(); ++i) p.image.data()[i * std::size_t(p.image.channels())] = 0.5f;
  AutoFilter a, b;
  const Image want = run_auto(opaque, a), got = run_auto(veiled, b);
  EXPECT_NE(a.chosen(), "input");
  EXPECT_EQ(b.chosen(), a.chosen());
  EXPECT_EQ(got.storage(), want.storage());
}

// The same render drawn twice (the dof still at 64 spp, rendered again: other noise, relMSE
// 0.0198 against the first's 0.0200) is filtered both times. Oracle: the 2048-spp reference; on
// both, pwaf cuts the error about 4x. The held-out scores of pwaf and the input tie on the second
// draw (0.0137 each), and a rule that asked the best to rank strictly below the input kept it.
TEST(AutoFilter, ASecondDrawOfARenderIsFilteredLikeTheFirst) {
  const std::string dir = std::string(MCRECON_SOURCE_DIR) + "/samples/data/dof/";
  const Image ref = read_frame(dir + "dof_ref.exr").image(Role::Colour);
  for (const char* name : {"dof_64spp.exr", "dof_64spp_rerender.exr"}) {
    SCOPED_TRACE(name);
    const Frame f = read_frame(dir + name);
    AutoFilter a;
    const Image out = run_auto(f, a);
    EXPECT_NE(a.chosen(), "input");
    EXPECT_LT(relmse(out, ref), 0.5 * relmse(f.image(Role::Colour), ref));
  }
}

TEST(AutoFilter, ACleanRenderIsKeptAsItIs) {
  Image clean;
  Frame f = blocks(160, 128, 0.0, 4, &clean);
  AutoFilter a;
  const Image out = run_auto(f, a);
  EXPECT_EQ(a.chosen(), "input");
  EXPECT_EQ(out.storage(), clean.storage());
}

// A clean render with fireflies: rare ones (one pixel in a few thousand, a converged render's
// glints) are kept with the render; where they are one pixel in a hundred they are the error
// (the oracle: the clean image) and a filter is run.
TEST(AutoFilter, AConvergedRenderKeepsItsRareFarOutPixelsButNotFrequentOnes) {
  for (const double rate : {0.0003, 0.01}) {
    SCOPED_TRACE(rate);
    Image clean;
    const Frame f = blocks(320, 256, 0.0, 6, &clean, rate);
    AutoFilter a;
    const Image out = run_auto(f, a);
    if (rate < 0.001) {
      EXPECT_EQ(a.chosen(), "input");
      EXPECT_EQ(out.storage(), f.image(Role::Colour).storage());
    } else {
      EXPECT_NE(a.chosen(), "input");
      EXPECT_LT(relmse(out, clean), 0.5 * relmse(f.image(Role::Colour), clean));
    }
  }
}

// Where no filter is estimated to help and the input is not converged (the glossy still's 2048-spp
// reference: no candidate ranks within min_gain of it), the kept input still loses a lone firefly
// the scored tiles do not hold (a second draw of the jewel still at 64 spp had one pixel at 3000x
// its neighbours: relMSE 12.1 kept, every filter 0.0025). One pixel set 1000x brighter near the
// corner, outside the tiles: auto keeps the input but that pixel, which ends within 10x its
// neighbours' brightest (the oracle: the reference itself, the error under 1% of the firefly's);
// kept_firefly_k 0 keeps it too.
TEST(AutoFilter, AKeptInputLosesALoneFireflyTheTilesMissed) {
  const Image ref = read_frame(std::string(MCRECON_SOURCE_DIR) + "/samples/data/glossy/glossy_ref.exr").image(Role::Colour);
  Frame f = testutil::colour_frame(ref);
  Image& y = const_cast<Image&>(f.image(Role::Colour));
  const int fx = 5, fy = 6;
  for (int c = 0; c < 3; ++c) y.at(fx, fy, c) *= 1000.0f;
  double brightest = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (dx || dy) brightest = std::max(brightest, double(y.at(fx + dx, fy + dy, 1)));

  AutoFilter a;
  const Image out = run_auto(f, a);
  ASSERT_EQ(a.chosen(), "input");
  EXPECT_LT(out.at(fx, fy, 1), 10.0 * brightest);  // k = 32 deviations of its window above the mean
  EXPECT_LT(relmse(out, ref), 0.01 * relmse(y, ref));
  std::size_t changed = 0;
  for (int yy = 0; yy < y.height(); ++yy)
    for (int x = 0; x < y.width(); ++x)
      for (int c = 0; c < 3; ++c) changed += out.at(x, yy, c) != y.at(x, yy, c);
  EXPECT_EQ(changed, 3u);  // the firefly's three channels, nothing else

  AutoFilter off;
  off.set("kept_firefly_k", 0.0);
  const Image kept = run_auto(f, off);
  EXPECT_EQ(off.chosen(), "input");
  EXPECT_EQ(kept.storage(), y.storage());
}

// The mean of two filters' results (issue 14): where it beats each filter, auto runs the two and
// gives their mean. Held-out stills at 16 spp (sunlit, showroom; nothing was chosen on them):
// truth from the 2048-spp references, the oracle each filter run whole by name. With the means
// not scored (pairs=false) auto runs the best single filter here (atrous, pwaf) and this fails.
TEST(AutoFilter, TheMeanOfTwoFiltersIsChosenWhereItBeatsEach) {
  for (const char* scene : {"sunlit", "showroom"}) {
    SCOPED_TRACE(scene);
    const std::string dir = std::string(MCRECON_SOURCE_DIR) + "/samples/data/" + scene + "/" + scene;
    const Frame f = read_frame(dir + "_16spp.exr");
    const Image ref = read_frame(dir + "_ref.exr").image(Role::Colour);
    AutoFilter a;
    const Image out = run_auto(f, a);
    ChoiceRunner runner(f);
    double best_single = 1e300;
    for (const std::string& name : {"box", "gaussian", "bilateral", "atrous", "guided", "pwaf"})
      best_single = std::min(best_single, relmse(runner.run(name), ref));
    EXPECT_LT(relmse(out, ref), 0.95 * best_single) << "chose " << a.chosen();
    ASSERT_NE(a.chosen().find('+'), std::string::npos) << a.chosen();
    EXPECT_EQ(out.storage(), runner.run(a.chosen()).storage());
  }
}

TEST(AutoFilter, ItsResultIsTheChosenFiltersAndItReportsTheScores) {
  Image clean;
  const Frame f = blocks(160, 128, 0.3, 5, &clean);
  AutoFilter a;
  const Image out = run_auto(f, a);
  ASSERT_NE(a.chosen(), "input");
  EXPECT_EQ(out.storage(), ChoiceRunner(f).run(a.chosen()).storage());
  // Scores: the input and every filter whose passes are present, best first.
  ASSERT_GE(a.scores().size(), 2u);
  for (std::size_t i = 1; i < a.scores().size(); ++i) EXPECT_LE(a.scores()[i - 1].relmse, a.scores()[i].relmse);
  bool est = false, chose = false, skipped = false;
  for (const std::string& n : a.notes()) {
    est = est || n.rfind("auto: estimated relMSE", 0) == 0;
    chose = chose || n == "auto: chose " + a.chosen() + " with its defaults" ||
            n == "auto: chose " + a.chosen() + " (the mean of the two results) with their defaults";
    skipped = skipped || n.find("candidates skipped") != std::string::npos;
  }
  EXPECT_TRUE(est && chose);
  // The frame has no depth pass: guided's default guide leaves it out, so guided is still scored.
  EXPECT_FALSE(skipped);
  bool guided = false;
  for (const AutoScore& s : a.scores()) guided = guided || s.filter == "guided";
  EXPECT_TRUE(guided);
}

TEST(AutoFilter, OnlyTheRegionChangesAndNothingNonFiniteLeaves) {
  Image clean;
  Frame f = blocks(160, 128, 0.3, 6, &clean);
  Image& y = f.passes[0].image;
  y.at(50, 40, 0) = std::numeric_limits<float>::quiet_NaN();
  y.at(51, 40, 1) = std::numeric_limits<float>::infinity();
  const Roi roi{20, 10, 140, 100};
  AutoFilter a;
  const Image out = run_auto(f, a, roi);
  for (int yy = 0; yy < 128; ++yy)
    for (int x = 0; x < 160; ++x)
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(out.at(x, yy, c)));
        if (!roi.contains(x, yy)) EXPECT_EQ(out.at(x, yy, c), y.at(x, yy, c));
      }
}

// A region of a few pixels holds no pixel out with its four neighbours inside: it is scored
// by SURE on the image's noise instead, and a noisy one is still filtered (not kept as
// "converged" for want of a score).
TEST(AutoFilter, ARegionTooSmallToHoldOutIsStillScored) {
  Image clean;
  const Frame f = blocks(96, 80, 0.4, 9, &clean);
  const Roi roi{40, 30, 46, 35};
  AutoFilter a;
  const Image out = run_auto(f, a, roi);
  EXPECT_NE(a.chosen(), "input");
  EXPECT_TRUE(a.check().filter.empty());
  double in_err = 0, err = 0;
  for (int yy = roi.y0; yy < roi.y1; ++yy)
    for (int x = roi.x0; x < roi.x1; ++x)
      for (int c = 0; c < 3; ++c) {
        const double r = clean.at(x, yy, c), w = 1.0 / (r * r + 0.01);
        in_err += w * std::pow(f.image(Role::Colour).at(x, yy, c) - r, 2);
        err += w * std::pow(out.at(x, yy, c) - r, 2);
      }
  EXPECT_LT(err, 0.5 * in_err);
}

TEST(AutoFilter, TheCatalogNamesIt) {
  const std::vector<std::string> names = catalog_names();
  EXPECT_EQ(names.back(), "auto");
  EXPECT_EQ(catalog_info("auto").name, "auto");
  EXPECT_NE(dynamic_cast<AutoFilter*>(make_catalog_filter("auto").get()), nullptr);
  EXPECT_THROW(make_catalog_filter("autox"), Error);
}

}  // namespace
}  // namespace mcr
