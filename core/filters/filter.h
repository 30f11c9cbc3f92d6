#pragma once
// Filter interface (set -> commit -> execute), after OIDN's filter lifecycle.
// Parameters live in a ParamSet built from the filter's one table; every input
// check happens in commit() (parameters) and execute() (passes, before any work).
//
// execute() = the preparation steps the filter takes (prepare/preparation.h: holes,
// albedo prefilter, demodulation, outliers) -> run() -> finish (remodulation; outside
// the roi the input colour; nothing non-finite leaves).
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "image/pass.h"
#include "prepare/exposure.h"
#include "prepare/preparation.h"
#include "util/params.h"

namespace mcr {

struct FilterInfo {
  std::string name;     // registry name, e.g. "box"
  std::string summary;  // one line
  std::string reference;  // paper / section it implements
  ParamTable params;
  std::vector<Role> required;  // passes it cannot run without (under any setting)
  std::vector<Role> optional;  // passes it may use when present (under some setting)
  PrepSteps steps;             // the preparation steps it takes (their parameters end its table)
  bool temporal = false;       // keeps history between execute() calls (frame order matters)
  bool deep_input = false;     // reads the frame's per-sample (deep) buffer; a flat frame is refused
  bool lightfield_input = false;  // reads a light-field deep EXR (image/lightfield.h); with deep_input
  std::string nonfinite_policy;  // what it does with NaN/Inf input, for docs and `filters`
};

// `own` followed by the parameters of every preparation step (what most filters take).
ParamTable with_common_params(ParamTable own);

// The passes a filter needs and uses under its current settings.
struct PassNeeds {
  std::vector<Role> required;  // execute() fails without them
  std::vector<Role> optional;  // used when present
  std::vector<std::string> why;  // per required pass: the setting that needs it ("" = always)
  void require(Role r, const std::string& setting = "");
  void use(Role r);
};

// Throws MissingPass "<who> needs the normal (for use_normal=on), depth passes, absent in
// '<file>'" when the frame lacks required passes.
void check_passes(const PassNeeds& need, const Frame& frame, const std::string& who);

struct ExecOptions {
  Roi roi;           // {} = whole frame; any other roi must lie inside it; pixels outside keep the input colour
  int nthreads = 0;  // 0 = all cores
};

class Filter {
 public:
  explicit Filter(const FilterInfo& info);
  virtual ~Filter() = default;

  const FilterInfo& info() const { return info_; }
  const ParamSet& params() const { return params_; }

  void set(const std::string& name, const ParamValue& value);
  void set_text(const std::string& name, const std::string& text);
  // Validates cross-parameter constraints; execute() requires a committed filter.
  void commit();

  // Runs on one frame and returns its RGB result (same size as the frame).
  // Throws MissingPass naming the passes the frame lacks, before any work.
  Image execute(const Frame& frame, const ExecOptions& options = {});

  // Drops temporal history (new shot, frames out of order), and a temporal filter's exposure.
  void reset();

  // The exposure step (prepare/exposure.h) at a fixed factor k instead of the frame's own, for
  // good: `auto` runs its candidates at 1 on the frame it scaled (a sample tile's level is not
  // the frame's). (A temporal filter keeps its first frame's until reset(): its history is at
  // that scale.) Without the step (exposure=off, or a filter that does not take it) no effect.
  // prior: the factor the frames it gets were already scaled by (auto's), so its step back
  // still weighs errors as relMSE does on the render itself.
  void pin_exposure(double k, double prior = 1.0);
  // Whether the exposure step may scale a frame (then it copies the passes it reads: the
  // memory a tiled run plans for).
  bool exposure_may_scale() const { return exposure_applies(); }
  // Whether begin_statistics() will first measure the frame's exposure (one more pass).
  bool measures_exposure_first() const { return exposure_applies() && exposure_pin_ == ExposurePin::None; }

  // With light passes (pipeline/components.h): whether it divides each component by its
  // colour pass (the albedo it is given) itself and multiplies back before work that must
  // see the shown colour (bmfr's TAA), so that it takes the component remodulated. Else it
  // takes the light alone and the recombination multiplies its result.
  virtual bool demodulates_itself() const { return false; }

  // What the current settings read: the filter's own needs plus its preparation steps'.
  PassNeeds needs() const;
  // The preparation steps this run takes: info().steps, with the first-hit holes where the
  // filter reads position or depth (prepare/first_hit.h).
  PrepSteps prep_steps() const;
  // Passes in needs().required that the frame lacks.
  std::vector<Role> missing_passes(const Frame& frame) const;
  // Settings given that change nothing under the others (from commit()), e.g.
  // "firefly_radius has no effect with firefly_k=0".
  const std::vector<std::string>& unused_settings() const { return unused_; }
  // Notes from the last execute() (which optional weights were dropped, ...).
  const std::vector<std::string>& notes() const { return notes_; }
  // Non-finite values the safety net replaced in the last execute(); a correct
  // filter keeps this at 0 (tests check it).
  std::size_t nonfinite_repaired() const { return repaired_; }

  // ---- Tiled runs (pipeline/tiled_run.h): a frame in bands of rows, same pixels ----
  // Rows a band needs above and below the rows execute() filters for them to come out as
  // the whole frame's; -1 when these settings cannot run in bands (why_not_tileable()).
  int band_halo() const;
  std::string why_not_tileable() const;
  // Rows around a band's own that execute() must filter too (the step back's windows read
  // the filtered result around each pixel).
  int band_margin() const;
  // Rows a band's first row must be a multiple of (grids its estimates lie on): a multiple of 64.
  virtual int band_alignment() const { return 64; }
  // For the band height --max-memory gives (pipeline/tiled_run.h): bytes per pixel of a band
  // that its working planes take beyond the passes read (the preparation's copies, its own
  // planes; peak RSS measured on a 4096x3072 frame, README "Huge frames", plus a tenth), and
  // bytes per pixel of the frame its statistics hold while they are gathered.
  virtual double band_work_bytes() const { return 224; }
  virtual double statistics_bytes() const { return 0; }
  // The statistics passes: begin_statistics(); then, while end_statistics_pass() says another
  // is needed, attach_statistics() and measure() on every band in frame order (`rows`: the
  // band's own rows, in its coordinates); then attach_statistics() on each band before its
  // execute(), until drop_statistics(). measure() runs the preparation steps on the band and
  // records, for its rows, the spread of every pass as the filter reads it (first pass:
  // Image::whole_frame) and the filter's own frame statistics (measure_band(); a filter whose
  // statistics build on others, e.g. a guide chosen by a noise level, asks for a second pass).
  void begin_statistics();
  void measure(const Frame& band, const Roi& rows, int nthreads);
  bool end_statistics_pass();
  void attach_statistics(Frame& band) const;
  void drop_statistics();
  bool statistics_fixed() const { return stats_state_ == StatsState::Fixed; }
  // Unsampled pixels met while measuring (their pull-push fill spans the frame, so a band
  // fills them from its own rows: not the whole frame's pixels there).
  std::size_t measured_holes() const { return measured_holes_; }

 protected:
  virtual void check_params() {}
  // What reset() drops besides the exposure (a temporal filter's history).
  virtual void reset_history() {}
  // During run(): the factor the exposure step scaled the frame by (1: not scaled). A setting
  // in the render's colour units (an absolute colour sigma) is multiplied by it.
  double exposure_scale() const { return exposure_; }
  // The factor between the colour run() sees and the render's own (this filter's exposure
  // step times a caller's): relMSE's term 0.01 is 0.01 metric_scale()^2 in run()'s units.
  double metric_scale() const { return exposure_ * exposure_prior_; }
  // The filter's own needs under params_ (default: info().required, plus the feature
  // block's use_<f>=on; info().optional less the use_<f>=off ones).
  virtual PassNeeds own_needs() const;
  // Settings of its own table that have no effect under params_ (commit() time; default:
  // the feature block's and foveation's). Overrides add to Filter::own_unused().
  virtual std::vector<std::string> own_unused() const;
  // The pixels run() reads to write roi (the preparation steps work there): default the
  // whole frame.
  virtual Roi reads(const Roi& roi, int width, int height) const {
    (void)roi;
    return Roi::all(width, height);
  }
  // colour: the RGB input to filter (after the preparation steps); read it, not frame's
  // colour pass. frame: every pass (holes filled, albedo prefiltered). out arrives as a
  // copy of colour; write the result inside roi.
  virtual void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) = 0;
  // True when run() reads `colour` only before it writes any pixel of `out` and writes
  // every pixel of the roi: the base class then passes the colour buffer itself as `out`
  // (the same object: no copy of the frame).
  virtual bool run_in_place() const { return false; }
  // Pixels beyond a region that run() reads to write it, through every stage of its own
  // (not the preparation's); -1: unknown (not tileable). Default: from reads().
  virtual int own_reach() const;
  // Tiled runs: this band's share of the statistics the filter takes from the whole frame
  // (band: the prepared passes, colour: the prepared colour; rows: the band's own), then
  // the combined ones fixed (run() uses them while statistics_fixed()), then dropped.
  virtual void measure_band(const Frame& band, const Image& colour, const Roi& rows, int nthreads) {
    (void)band, (void)colour, (void)rows, (void)nthreads;
  }
  // For a filter whose statistics come out of its own first stages: run() on the band's rows
  // with measuring_run() true (it records them and returns before filtering).
  void run_to_measure(const Frame& band, const Image& colour, const Roi& rows, int nthreads);
  bool measuring_run() const { return measuring_run_; }
  virtual void fix_statistics() {}
  // The pass just measured is complete: true to measure every band again (statistics_pass()
  // then counts it), false when the filter's statistics are fixed.
  virtual bool statistics_pass_done() { return false; }
  int statistics_pass() const { return stats_pass_; }
  virtual void drop_own_statistics() {}
  // Whether the step back (prepare/step_back.h) applies to the result run() just gave: its
  // limits assume a spatial estimate from this frame's input (a temporal filter's output
  // built from history may lie outside this frame's local range, rightly).
  virtual bool step_back_applies() const { return true; }
  // During run(): the demodulation divisor (RGB, valid inside the roi), null when the
  // colour was not demodulated.
  const Image* demodulation_divisor() const { return prepared_.divisor.empty() ? nullptr : &prepared_.divisor; }
  void note(std::string text) { notes_.push_back(std::move(text)); }
  // "<name> has no effect <why>" when the setting was given (for own_unused()).
  void unused_when(bool no_effect, const std::string& name, const std::string& why, std::vector<std::string>& out) const;

  ParamSet params_;

 private:
  const FilterInfo& info_;
  bool committed_ = false;
  Prepared prepared_;
  std::vector<std::string> unused_, notes_;
  std::size_t repaired_ = 0;
  enum class StatsState { None, Measuring, Fixed };
  StatsState stats_state_ = StatsState::None;
  std::vector<std::pair<std::string, WholeFrameRange>> measuring_ranges_;  // by pass name
  std::vector<std::pair<std::string, std::shared_ptr<const WholeFrameRange>>> ranges_;
  std::size_t measured_holes_ = 0;
  int stats_pass_ = 0;
  bool measuring_run_ = false;
  // The exposure step: the factor of the current run; pinned (by pin_exposure(), a temporal
  // filter's first frame, or a tiled run's first statistics pass, which measures it).
  enum class ExposurePin { None, Caller, History, Statistics };
  double exposure_ = 1.0, exposure_prior_ = 1.0;
  double exposure_level_seen_ = 0;  // the level exposure_ was chosen from (for the note)
  ExposurePin exposure_pin_ = ExposurePin::None;
  bool exposure_measuring_ = false;
  ExposureLevel exposure_level_;
  bool exposure_applies() const;
  double exposure_for(const Image& colour, int nthreads);
};

}  // namespace mcr
