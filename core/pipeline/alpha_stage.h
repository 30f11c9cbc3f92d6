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
#include <memory>
#include <string>

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

// The alpha filter's RGB result as the output's alpha (1 channel): its R (the three channels
// are one signal), clamped to range; non-finite values (none leave a filter) become range.lo.
Image finish_alpha(const Image& filtered, AlphaRange range, int nthreads);

// "alpha: filtered by pwaf as a grey colour (demodulation off), clamped to [0, 1]": the note of a
// run that filtered the alpha.
std::string alpha_note(const Filter& alpha_filter, AlphaRange range);

// frame's alpha pass with alpha's pixels (the filtered alpha, for a writer that takes the
// frame's); nothing when alpha is empty (kept).
void put_alpha(Frame& frame, Image alpha);

// The rows of `inner` as alpha_frame() gives them (the alpha's run over bands).
class AlphaRows : public BandSource {
 public:
  explicit AlphaRows(BandSource& inner) : inner_(inner) {}
  int width() const override { return inner_.width(); }
  int height() const override { return inner_.height(); }
  Frame rows(int y0, int y1) override { return alpha_frame(inner_.rows(y0, y1)); }
  void overlap_hint(int rows) override { inner_.overlap_hint(rows); }

 private:
  BandSource& inner_;
};

}  // namespace mcr
