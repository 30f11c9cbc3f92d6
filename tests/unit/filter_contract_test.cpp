// Contracts every registered filter keeps (new filters are covered by registering them):
// the region promise with every preparation step on, and the instruction-set paths.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "util/isa.h"

namespace mcr {
namespace {

using testutil::full_frame;
using testutil::pass_image;

// A frame with every pass, a few unsampled pixels (sample_count 0) and bright spikes, so
// that every preparation step changes something.
Frame busy_frame(int w, int h, unsigned seed) {
  Frame f = full_frame(w, h, seed);
  Image spp(w, h, 1, 8.0f);
  for (int i = 0; i < 9; ++i) spp.at((i * 7 + 3) % w, (i * 5 + 2) % h, 0) = 0.0f;
  testutil::add_pass(f, Role::SampleCount, std::move(spp));
  for (int i = 0; i < 6; ++i) {
    float* p = pass_image(f, Role::Colour).pixel((i * 11 + 5) % w, (i * 3 + 1) % h);
    p[0] = p[1] = p[2] = 40.0f;
  }
  return f;
}

// Every common option on that the filter has (step_back off: see with_every_step_and_back).
std::unique_ptr<Filter> with_every_step(const std::string& name, bool step_back = false) {
  auto f = make_filter(name);
  if (f->params().has("step_back")) f->set("step_back", step_back);
  const ParamSet& p = f->params();
  if (p.has("demodulate")) f->set("demodulate", true);
  if (p.has("albedo_prefilter")) f->set("albedo_prefilter", 0.2);
  if (p.has("holes")) f->set("holes", std::string("sample_count"));
  if (p.has("firefly_k")) f->set("firefly_k", 2.0);
  if (p.has("clamp")) f->set("clamp", 20.0);
  if (p.has("colour_weight")) f->set("colour_weight", std::string("noise"));  // reads farther
  f->commit();
  return f;
}

TEST(FilterContract, PixelsOutsideTheRegionKeepTheInputColour) {
  const int w = 26, h = 19;
  const Roi region{6, 4, 17, 13};
  for (const std::string& name : image_filter_names()) {
    SCOPED_TRACE(name);
    const Frame f = busy_frame(w, h, 11);
    auto filter = with_every_step(name, true);
    ExecOptions eo;
    eo.roi = region;
    const Image out = filter->execute(f, eo);
    const Image& in = f.image(Role::Colour);
    std::size_t outside_changed = 0, inside_changed = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) {
          const bool same = std::memcmp(&out.pixel(x, y)[c], &in.pixel(x, y)[c], sizeof(float)) == 0;
          if (region.contains(x, y)) inside_changed += !same;
          else outside_changed += !same;
        }
    EXPECT_EQ(outside_changed, 0u);
    EXPECT_GT(inside_changed, 0u);  // the filter did run inside
  }
}

// Inside the region a filter gives what it gives on the whole frame (the preparation
// steps cover what it reads), for every filter without frame-wide state.
TEST(FilterContract, InsideTheRegionAsOnTheWholeFrame) {
  const int w = 26, h = 19;
  const Roi region{6, 4, 17, 13};
  for (const std::string& name : image_filter_names()) {
    SCOPED_TRACE(name);
    if (make_filter(name)->info().temporal) continue;  // bmfr's blocks span the frame
    const Frame f = busy_frame(w, h, 12);
    ExecOptions eo;
    eo.roi = region;
    // Without the step back: its windows stop at the region, where the filter's result ends.
    const Image part = with_every_step(name)->execute(f, eo);
    const Image whole = with_every_step(name)->execute(f);
    for (int y = region.y0; y < region.y1; ++y)
      for (int x = region.x0; x < region.x1; ++x)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(part.pixel(x, y)[c], whole.pixel(x, y)[c]) << x << "," << y;
  }
}

// MCRECON_ISA=generic against the best build: every filter within 1e-5 relative, and
// bit-identical where the code promises it (every path but the cross-bilateral kernel's
// FMA builds, used by gaussian's foveated path, bilateral, atrous and the albedo
// prefilter).
TEST(FilterContract, GenericAndBestInstructionSetsAgree) {
  if (best_isa() == Isa::Generic) GTEST_SKIP() << "this CPU has only the generic build";
  const int w = 40, h = 29;
  for (const std::string& name : image_filter_names()) {
    SCOPED_TRACE(name);
    for (bool steps : {false, true}) {
      const Frame f = busy_frame(w, h, 13);
      Image out[2];
      for (int k = 0; k < 2; ++k) {
        const ScopedIsa use(k == 0 ? Isa::Generic : best_isa());
        auto filter = steps ? with_every_step(name, true) : make_filter(name);
        if (!steps) filter->commit();
        // Two frames: temporal filters run their history paths too.
        filter->execute(f);
        out[k] = filter->execute(f);
      }
      const bool fma = name == "bilateral" || name == "atrous" ||
                       (steps && make_filter(name)->params().has("albedo_prefilter"));
      if (!fma) {
        EXPECT_EQ(out[0].storage(), out[1].storage()) << "steps " << steps;
        continue;
      }
      for (std::size_t i = 0; i < out[0].storage().size(); ++i) {
        const float a = out[0].storage()[i], b = out[1].storage()[i];
        ASSERT_LE(std::fabs(a - b), 1e-5 * std::max(1.0f, std::fabs(b))) << "steps " << steps << " value " << i;
      }
    }
  }
}

// A filter that takes no preparation step (a per-sample filter) gets none of their
// parameters and reads the colour exactly as rendered, holes and fireflies included.
class NoStepsFilter : public Filter {
 public:
  NoStepsFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info() {
    static const FilterInfo info = [] {
      FilterInfo i;
      i.name = "no_steps";
      i.steps = PrepSteps::none();
      i.params = with_preparation_params({ParamSpec::Float("gain", 1.0, 0.0, 10.0, "output = gain * input")}, i.steps);
      i.required = {Role::Colour};
      return i;
    }();
    return info;
  }
  Image seen;

 protected:
  void run(const Frame&, const Image& colour, const Roi& roi, Image& out, int) override {
    seen = colour;
    const float g = float(params_.get_float("gain"));
    for (int y = roi.y0; y < roi.y1; ++y)
      for (int x = roi.x0; x < roi.x1; ++x)
        for (int c = 0; c < 3; ++c) out.pixel(x, y)[c] = g * colour.pixel(x, y)[c];
  }
};

TEST(FilterContract, AFilterWithoutStepsSeesTheRenderAsItIs) {
  NoStepsFilter f;
  for (const char* p : {"demodulate", "albedo_floor", "albedo_prefilter", "holes", "firefly_k", "firefly_radius", "clamp"})
    EXPECT_FALSE(f.params().has(p)) << p;
  EXPECT_EQ(f.params().values().size(), 2u);  // its own, and components (read by the pipeline only)
  EXPECT_TRUE(f.params().has("components"));
  f.set("gain", 2.0);
  f.commit();
  const Frame frame = busy_frame(20, 15, 14);  // holes and spikes the steps would change
  const Image out = f.execute(frame);
  const Image& in = frame.image(Role::Colour);
  EXPECT_EQ(f.seen.storage(), in.storage());
  for (std::size_t i = 0; i < out.storage().size(); ++i) ASSERT_EQ(out.storage()[i], 2.0f * in.storage()[i]);
}

}  // namespace
}  // namespace mcr
