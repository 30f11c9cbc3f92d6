#pragma once
// Filter interface (set -> commit -> execute), after OIDN's filter lifecycle.
// Parameters live in a ParamSet built from the filter's one table; every input
// check happens in commit() (parameters) and execute() (passes), nowhere else.
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "util/params.h"
#include "image/pass.h"

namespace mcr {

struct FilterInfo {
  std::string name;     // registry name, e.g. "box"
  std::string summary;  // one line
  std::string reference;  // paper / section it implements
  ParamTable params;
  std::vector<Role> required;  // passes it cannot run without
  std::vector<Role> optional;  // passes it uses when present
  bool temporal = false;       // keeps history between execute() calls (frame order matters)
  std::string nonfinite_policy;  // what it does with NaN/Inf input, for docs and `filters`
  // The main parameter and the values the run-time-against-error benchmark sweeps.
  std::string sweep_param;
  std::vector<double> sweep_values;
  // Further settings ("key=value key=value") the benchmark sweeps the main parameter under,
  // besides the defaults and firefly_k=2 (which every filter gets).
  std::vector<std::string> sweep_variants;
};

// Parameters every filter's table ends with; the base class applies them
// around run(), so each filter gets them for free:
//   demodulate   divide the colour by the albedo pass before filtering, multiply after
//   albedo_floor albedo is raised to at least albedo_floor for that (Blender's albedo
//                reaches ~0.03 on glossy metal); no upper clamp: it exceeds 1 on
//                highlights (>100 near lights) and dividing and multiplying by the same
//                value is exact (a ceiling of 1 cost 8% relMSE on the glossy scene)
//   holes        pixels the render did not sample, filled by pull-push (features too)
//                before filtering: auto (sample_count == 0 when that pass exists),
//                none, sample_count, alpha (alpha == 0)
//   firefly_k, firefly_radius  bright outliers clamped to their window's
//                statistics before filtering (filters/fireflies.h); 0 = off
ParamTable with_common_params(ParamTable own);

// The albedo that demodulation divides by and remodulation multiplies by: at least
// albedo_floor, 1 where the pass is not finite (one rule for every filter and pwaf's
// variance scaling).
inline float demodulation_albedo(float v, float floor) { return (v - v == 0.0f) ? std::max(v, floor) : 1.0f; }

struct ExecOptions {
  Roi roi;           // empty = whole frame; pixels outside keep the input colour
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
  // Throws MissingPass naming the passes the frame lacks.
  Image execute(const Frame& frame, const ExecOptions& options = {});

  // Drops temporal history (new shot, frames out of order).
  virtual void reset() {}

  // Passes in info().required that the frame lacks.
  std::vector<Role> missing_passes(const Frame& frame) const;
  // Notes from the last execute(), e.g. which optional weights were dropped.
  const std::vector<std::string>& notes() const { return notes_; }
  // Non-finite values the safety net replaced in the last execute(); a correct
  // filter keeps this at 0 (tests check it).
  std::size_t nonfinite_repaired() const { return repaired_; }

 protected:
  virtual void check_params() {}
  // colour: the RGB input to filter (holes filled, demodulated when asked); read it,
  // not frame's colour pass. frame: every pass (holes filled too). out arrives as a
  // copy of colour; write the result inside roi.
  virtual void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) = 0;
  // True when run() reads `colour` only before it writes any pixel of `out` and writes
  // every pixel of the roi: the base class then passes the colour buffer itself as `out`
  // (the same object: no copy of the frame; pixels outside the roi keep the input).
  virtual bool run_in_place() const { return false; }
  void note(std::string text) { notes_.push_back(std::move(text)); }

  ParamSet params_;

 private:
  const FilterInfo& info_;
  bool committed_ = false;
  std::vector<std::string> notes_;
  std::size_t repaired_ = 0;
};

}  // namespace mcr
