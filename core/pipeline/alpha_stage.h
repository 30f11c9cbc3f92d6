#pragma once
// alpha=filter (prepare/preparation.h: alpha_param): the render's alpha is its coverage, a mean
// of its samples like the colour and as noisy: a shadow catcher's shadows, the edges, hair and
// veils of a transparent film (the product still at 16 spp: alpha MSE 0.0012 against its
// reference, 3.5x the 64-spp render's). The pipeline filters it by a second run on a frame whose
// colour is the alpha in R, G and B and whose features are the render's (coverage steps where
// the geometry does), with the filter's settings but demodulation (coverage is not lit through
// the albedo). Under `auto` the alpha runs pwaf with its defaults: auto's held-out pixels read
// every step of the coverage at an object's edge as noise and kept the input (on a transparent
// version of the tune scene glossy, a shadow catcher for its floor, pwaf was the best of the six
// filters at 16 and 64 spp: alpha MSE 0.00042 and 0.00021 against the input's 0.00105 and 0.00035).
// The result is clamped to [0, 1] (alpha_range). Unlike the colour (prepare/empty_pixels.h) an alpha of 0 is
// filtered too: a catcher's faint penumbra is 0 at many pixels by chance (there pwaf's error was
// 15% lower, and where the reference is 0 the filtered alpha's squared error was 0.58x the
// input's); the colour there stays 0, and a catcher's shadow is black at the alpha's opacity.
// A frame whose alpha is constant (an opaque render) is not run twice.
// Where the geometry covers a pixel only in part, the pixel keeps its own alpha (PartialCoverage).
#include <memory>
#include <string>
#include <vector>

#include "filters/filter.h"
#include "pipeline/tiled_run.h"

namespace mcr {

// alpha=filter in these settings (false for a table without the parameter).
bool filters_alpha(const ParamSet& params);

// The filter the alpha runs through, committed: `colour_filter`'s kind with every setting given
// to it, demodulation off; pwaf with its defaults when colour_filter is auto.
std::unique_ptr<Filter> make_alpha_filter(const Filter& colour_filter);

// Why `frame`'s alpha is not filtered, or "" when it is: no alpha pass, an alpha equal
// everywhere (its value named), holes=alpha (the alpha marks the sampled pixels, not coverage).
std::string alpha_kept_because(const ParamSet& params, const Frame& frame);
// "alpha: kept as it is (<why>)" for a frame with an alpha pass, "" without one (nothing to say).
std::string alpha_kept_note(const Frame& frame, const std::string& why);

// The frame the alpha's filter runs on: the colour pass replaced by the alpha in R, G and B, and
// every feature pass, but not the alpha (the filter would keep its 0s), the variance (the
// colour's), the light passes (the alpha's run is a beauty run) or the channels without a role (a
// copy of those would double a many-pass frame's memory for nothing).
Frame alpha_frame(const Frame& frame);

// The range the filtered alpha is clamped to: [0, 1], widened to the input's least and greatest
// finite value where it goes beyond (an alpha pass that holds something else than coverage is
// not cut).
struct AlphaRange {
  float lo = 0.0f, hi = 1.0f;
};
AlphaRange alpha_range(const Image& alpha);

// The pixels the geometry covers only in part: the geometric normal pass (Blender's world-space
// Normal, a mean over the pixel's samples, 0 for a sample that sees the world) longer than 0 and
// shorter than kCoveredNormal. Their alpha is the share of samples that hit something, and their
// features hold the same draw: no filter reads the true coverage from them, and every filter made
// it worse at 64 spp (on glossy's objects over a transparent world, a tune scene: pwaf 2.41x the
// input's alpha MSE, bilateral 1.80x, all of it at the silhouettes). A shadow catcher's pixels are
// covered (normal length 1; 2 where Cycles writes the catcher's passes twice). Keeping their own
// alpha left every filter within 1.5% of the input's on the tune scenes (tc, a catcher version of
// glossy and of studio: 10 renders, 1-64 spp) and kept the catchers' gains; a pixel no sample
// covered (normal 0: the world) is still filtered: the fringe beside an edge drew no hit by
// chance at low spp (keeping those 0s too was worse for every filter, summed log over the 10:
// box -4.54 against -4.67, bilateral -4.53 against -4.56). A frame without a normal pass has none.
inline constexpr float kCoveredNormal = 0.999f;
class PartialCoverage {
 public:
  PartialCoverage(int width, int height) : width_(width), mask_(std::size_t(width) * std::size_t(height), 0) {}
  // Marks rows [y0, y0 + rows.height) from rows' geometric normal (a band, or the whole frame at 0).
  void mark(const Frame& rows, int y0);
  bool partial(int x, int y) const { return mask_[std::size_t(y) * std::size_t(width_) + std::size_t(x)] != 0; }

 private:
  int width_;
  std::vector<unsigned char> mask_;
};

// The alpha filter's RGB result as the output's alpha (1 channel): its R (the three channels
// are one signal), clamped to range; non-finite values (none leave a filter) become range.lo.
// A partly covered pixel takes `own`'s channel 0 instead where it is finite (the frame's alpha, or
// the accumulated one); `kept` (when given) counts them.
Image finish_alpha(const Image& filtered, const Image& own, const PartialCoverage& coverage, AlphaRange range,
                   int nthreads, std::size_t* kept = nullptr);

// "alpha: filtered by pwaf as a grey colour (demodulation off), clamped to [0, 1], its own at N
// partly covered pixels": the note of a run that filtered the alpha.
std::string alpha_note(const Filter& alpha_filter, AlphaRange range, std::size_t kept);

// frame's alpha pass with alpha's pixels (the filtered alpha, for a writer that takes the
// frame's); nothing when alpha is empty (kept).
void put_alpha(Frame& frame, Image alpha);

// The rows of `inner` as alpha_frame() gives them (the alpha's run over bands), marking the
// partly covered pixels of each band as they pass.
class AlphaRows : public BandSource {
 public:
  explicit AlphaRows(BandSource& inner) : inner_(inner), coverage_(inner.width(), inner.height()) {}
  int width() const override { return inner_.width(); }
  int height() const override { return inner_.height(); }
  Frame rows(int y0, int y1) override {
    Frame f = inner_.rows(y0, y1);
    coverage_.mark(f, y0);
    return alpha_frame(f);
  }
  void overlap_hint(int rows) override { inner_.overlap_hint(rows); }
  const PartialCoverage& coverage() const { return coverage_; }

 private:
  BandSource& inner_;
  PartialCoverage coverage_;
};

}  // namespace mcr
