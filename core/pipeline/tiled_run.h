#pragma once
// Bounded memory on huge frames (#19): a frame filtered in horizontal bands. Each band is
// read with `halo` rows above and below it (the filter's reach, Filter::band_halo()), and
// only its own rows are kept. A run over bands gives the whole frame's pixels bit for bit:
//   1. every band is measured in order (Filter::measure_band: the statistics some defaults
//      take from the whole frame, e.g. a median noise level, a guide's spread, whether a
//      pass is constant), and the filter fixes the combined statistics;
//   2. every band is filtered with them, its rows written into the output.
// Bands start at multiples of kBandAlign rows, so the grids some estimates use (noise
// tiles) fall where they fall in the whole frame.
//
// A source gives a band's rows on demand: from a file (io/band_reader.h: only the passes
// the filter reads, a band at a time) or from a frame in memory (FrameRows, tests).
#include <functional>
#include <string>
#include <vector>

#include "filters/filter.h"
#include "image/pass.h"

namespace mcr {

constexpr int kBandAlign = 64;

class BandSource {
 public:
  virtual ~BandSource() = default;
  virtual int width() const = 0;
  virtual int height() const = 0;
  // Rows [y0, y1) of the frame as a frame of width() x (y1 - y0): every pass the run reads.
  virtual Frame rows(int y0, int y1) = 0;
  // Consecutive bands share up to this many rows (their halos): a source may keep them.
  virtual void overlap_hint(int rows) { (void)rows; }
};

// The rows of a frame in memory.
class FrameRows : public BandSource {
 public:
  explicit FrameRows(const Frame& frame) : frame_(frame) {}
  int width() const override { return frame_.width; }
  int height() const override { return frame_.height; }
  Frame rows(int y0, int y1) override;

 private:
  const Frame& frame_;
};

// Rows [y0, y1) of `frame` (every pass; a deep or light-field frame is refused).
Frame frame_rows(const Frame& frame, int y0, int y1);

struct BandPlan {
  int band_rows = 0;  // output rows per band (a multiple of kBandAlign, or the whole height)
  int halo = 0;       // rows read above and below
  int bands = 0;
};

// Bands of `band_rows` (rounded up to kBandAlign) over a frame of `height` rows.
BandPlan plan_bands(int height, int band_rows, int halo);

// Output rows per band that keep the whole run under max_bytes: the output (RGB float and
// alpha) is held for the whole frame, the statistics pass's values while it runs; the rest is
// one band with its halo.
// Throws InvalidArgument naming --max-memory when not even one aligned band fits.
int band_rows_for(const Filter& filter, int width, int height, int input_channels, double max_bytes);

struct TiledOptions {
  int band_rows = 0;  // from plan_bands / band_rows_for
  int nthreads = 0;
  // Called after each band measured or filtered: (steps done, steps in all).
  std::function<void(int, int)> progress;
  // Passes whose rows the run gathers into `kept` (full size), e.g. the alpha for the output.
  std::vector<Role> keep;
};

// The filter (committed, tileable: band_halo() >= 0) over every band of `source`: its RGB
// result, equal to filter.execute() on the whole frame. `notes`: the bands ("12 bands of 256
// rows (halo 74)"), unsampled pixels filled per band if any, then the filter's notes, each once.
Image run_tiled(Filter& filter, BandSource& source, const TiledOptions& options, std::vector<std::string>* notes = nullptr,
                Frame* kept = nullptr);

}  // namespace mcr
