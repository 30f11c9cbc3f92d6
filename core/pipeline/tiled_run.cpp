#include "pipeline/tiled_run.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

Frame frame_rows(const Frame& frame, int y0, int y1) {
  if (frame.deep || frame.lightfield)
    throw Error(Errc::InvalidArgument, "'" + frame.path + "' is a deep file: it is filtered whole, not in bands");
  if (y0 < 0 || y1 > frame.height || y0 >= y1)
    throw Error(Errc::Internal, "frame_rows: rows " + std::to_string(y0) + ".." + std::to_string(y1) + " outside the frame");
  Frame f = frame.header(frame.width, y1 - y0);
  f.window = frame.window;
  auto rows_of = [&](const Pass& p) {
    const Image& im = p.image;
    Image band(im.width(), y1 - y0, im.channels());
    const std::size_t row = std::size_t(im.width()) * std::size_t(im.channels());
    if (row) std::memcpy(band.data(), im.pixel(0, y0), row * std::size_t(y1 - y0) * sizeof(float));
    return with_pixels(p, std::move(band));
  };
  for (const Pass& p : frame.passes) f.passes.push_back(rows_of(p));
  return f;
}

Frame FrameRows::rows(int y0, int y1) { return frame_rows(frame_, y0, y1); }

BandPlan plan_bands(int height, int band_rows, int halo) {
  BandPlan p;
  p.halo = std::max(0, halo);
  const int aligned = std::max(kBandAlign, (std::max(band_rows, 1) + kBandAlign - 1) / kBandAlign * kBandAlign);
  p.band_rows = std::min(aligned, std::max(height, 1));
  p.bands = height <= 0 ? 0 : (height + p.band_rows - 1) / p.band_rows;
  return p;
}

int band_rows_for(const Filter& filter, int width, int height, int input_channels, double max_bytes) {
  const double px = double(width) * double(height);
  // Held for the whole frame: the result (RGB float) and the alpha; first the statistics
  // pass's values (Filter::statistics_bytes()), at the end the writer's interleaved RGBA copy.
  const double stats = filter.statistics_bytes();
  // The statistics are freed before the filtering pass; while they are gathered a band holds
  // what the filter computes before them (at most kMeasureShare of its planes).
  constexpr double kMeasureShare = 0.6;
  constexpr double kProcess = 160.0 * 1024 * 1024;  // the process itself (code, libraries, thread stacks)
  const double whole = kProcess + px * (12.0 + 4.0);
  // The passes read (twice where the exposure step may copy them to scale), the planes.
  const double passes = (filter.exposure_may_scale() ? 8.0 : 4.0) * input_channels;
  const double per_row = double(width) * (passes + filter.band_work_bytes());
  const double halo_rows = 2.0 * filter.band_halo() + filter.band_alignment();
  // A file source keeps the rows consecutive bands share (io/band_reader.h).
  const double overlap = halo_rows * double(width) * 4.0 * input_channels;
  const double budget = max_bytes - whole - overlap;
  const double rows = std::min(budget / per_row, (budget - px * stats) / (kMeasureShare * per_row)) - halo_rows;
  if (!(rows >= kBandAlign) || kProcess + px * (12.0 + 4.0 + 32.0) > max_bytes) {
    const double need = whole + overlap + std::max(per_row, kMeasureShare * per_row + px * stats / (halo_rows + kBandAlign)) *
                                              (halo_rows + kBandAlign);
    throw Error(Errc::InvalidArgument,
                "--max-memory " + std::to_string(int(max_bytes / (1024.0 * 1024.0))) + " MB is too little for a " +
                    std::to_string(width) + "x" + std::to_string(height) + " frame with filter '" + filter.info().name +
                    "': at least " + std::to_string(int(std::max(need, kProcess + px * 48.0) / (1024.0 * 1024.0)) + 1) +
                    " MB");
  }
  return int(std::min(rows, double(std::max(height, kBandAlign)))) / kBandAlign * kBandAlign;
}

namespace {

void add_notes(const std::vector<std::string>& from, std::vector<std::string>& to) {
  for (const std::string& n : from)
    if (std::find(to.begin(), to.end(), n) == to.end()) to.push_back(n);
}

}  // namespace

Image run_tiled(Filter& filter, BandSource& source, const TiledOptions& options, std::vector<std::string>* notes,
                Frame* kept) {
  const int halo = filter.band_halo(), margin = filter.band_margin(), align = filter.band_alignment();
  if (halo < 0)
    throw Error(Errc::InvalidArgument, "filter '" + filter.info().name + "' cannot run in bands under these settings (" +
                                           filter.why_not_tileable() + ")");
  const int w = source.width(), h = source.height();
  const BandPlan plan = plan_bands(h, options.band_rows, halo);
  source.overlap_hint(2 * plan.halo + align);
  std::vector<std::string> said = {std::to_string(plan.bands) + (plan.bands == 1 ? " band of " : " bands of ") +
                                   std::to_string(plan.band_rows) + " rows (halo " + std::to_string(plan.halo) + ")"};
  // Band b's frame with the statistics fixed so far; rows: its own, in its coordinates; r0:
  // its first row in the frame (the halo rounded out to the filter's grid).
  auto fetch = [&](int b, Roi& rows, int& r0) {
    const int y0 = b * plan.band_rows, y1 = std::min(h, y0 + plan.band_rows);
    r0 = std::max(0, (y0 - plan.halo) / align * align);
    rows = Roi{0, y0 - r0, w, y1 - r0};
    Frame band = source.rows(r0, std::min(h, y1 + plan.halo));
    filter.attach_statistics(band);
    return band;
  };

  // The exposure's pass (Filter::measures_exposure_first) comes before the statistics' own.
  bool exposure_pass = filter.measures_exposure_first();
  int step = 0, passes = exposure_pass ? 2 : 1;
  auto stepped = [&] {
    ++step;
    if (options.progress) options.progress(step, (passes + 1) * plan.bands);
  };
  Image out(w, h, 3);
  filter.begin_statistics();
  try {
    do {
      for (int b = 0; b < plan.bands; ++b) {
        Roi rows;
        int r0 = 0;
        filter.measure(fetch(b, rows, r0), rows, options.nthreads);
        stepped();
      }
      if (exposure_pass)
        exposure_pass = false;  // counted from the start
      else
        ++passes;
    } while (filter.end_statistics_pass());
    --passes;
    if (filter.measured_holes())
      said.push_back(std::to_string(filter.measured_holes()) +
                     " unsampled pixels filled by each band's own pull-push (not the whole frame's: those pixels may differ)");

    for (int b = 0; b < plan.bands; ++b) {
      Roi rows;
      int r0 = 0;
      const Frame band = fetch(b, rows, r0);
      ExecOptions eo;
      eo.nthreads = options.nthreads;
      eo.roi = rows.grown(margin, band.width, band.height);
      const Image part = filter.execute(band, eo);
      const std::size_t row = std::size_t(w) * 3;
      std::memcpy(out.pixel(0, r0 + rows.y0), part.pixel(0, rows.y0), row * std::size_t(rows.height()) * sizeof(float));
      if (kept)
        for (Role r : options.keep)
          if (const Pass* p = band.find(r)) {
            auto k = std::find_if(kept->passes.begin(), kept->passes.end(), [&](const Pass& q) { return q.role == r; });
            if (k == kept->passes.end()) k = kept->passes.insert(kept->passes.end(), with_pixels(*p, Image(w, h, p->image.channels())));
            const std::size_t kr = std::size_t(w) * std::size_t(p->image.channels());
            std::memcpy(k->image.pixel(0, r0 + rows.y0), p->image.pixel(0, rows.y0), kr * std::size_t(rows.height()) * sizeof(float));
          }
      add_notes(filter.notes(), said);
      stepped();
    }
  } catch (...) {
    filter.drop_statistics();
    throw;
  }
  filter.drop_statistics();
  if (notes) *notes = std::move(said);
  return out;
}

}  // namespace mcr
