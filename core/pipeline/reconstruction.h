#pragma once
// What every front end runs per frame (CLI, OIIO plugin, Python module, Blender add-on):
// an optional temporal accumulation stage (BMFR phase I, Koskela et al. 2019, 4.1: the
// reprojected cumulative-then-exponential average of the noisy colour, with its own
// history across the frames of a run) before the filter, which then sees a frame whose
// colour pass holds the accumulated RGB (alpha and other channels kept). Only the
// pipeline combines stages; the filter knows nothing of it. The accumulation is guarded as
// bmfr's phase I is (prepare/history_guards.h, defaults): fireflies are cut before they
// enter the history, and mirror-like pixels keep none.
//
// With components=light_passes (pipeline/components.h) each light component (glossy and
// transmission: its direct and its indirect light) runs through its own accumulation and
// filter (one history per stage, light_stages()); the filter's demodulation
// is turned off (the light passes are already demodulated) and the result is their
// recombination.
//
// With alpha=filter (pipeline/alpha_stage.h) the alpha runs through a filter of its own after
// the colour (its own history too): run_in_place() puts it in the frame's alpha pass, run()
// gives it when asked.
//
// Shared use: run(), run_in_place(), reset() and notes() may be called from several
// threads at once; they are serialised (a mutex held for the whole call), in the order
// the calls take the lock. A temporal session's frame order is then the caller's
// responsibility. filter() gives the filter itself, outside that lock: use it to read
// its table and settings, not to execute it.
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "filters/filter.h"
#include "pipeline/components.h"
#include "prepare/history_guards.h"
#include "prepare/surface_classes.h"
#include "temporal/accumulation.h"

namespace mcr {

// What filter `auto` ran in one stage of a run: stage "beauty", or with components=light_passes
// the light stage's name ("diffuse", "glossy direct", ...); filter "input" where it kept the input.
struct StageChoice {
  std::string stage, filter;
};

// "atrous" (the beauty alone), "diffuse=atrous; glossy direct=pwaf; ..." (light stages): the
// mcreconChosen attribute; empty for none.
std::string choices_text(const std::vector<StageChoice>& choices);

// The reconstruction's notes (unused settings first) as one line, "; " between them: the
// mcreconNotes attribute every front end writes.
std::string notes_text(const std::vector<std::string>& notes);

// What an output's header says of the run, as every front end writes it: mcreconFilter,
// mcreconParameters (parameters_text()), then mcreconChosen (choices_text()) and mcreconNotes
// (notes_text()) when not empty.
std::vector<std::pair<std::string, std::string>> run_attributes(const std::string& filter, const std::string& params,
                                                                const std::string& chosen, const std::string& notes);

class Reconstruction {
 public:
  Reconstruction(std::unique_ptr<Filter> filter, bool accumulate);

  Filter& filter() { return *stages_.front()->filter; }
  const Filter& filter() const { return *stages_.front()->filter; }
  // components=light_passes: one stage per light_stages() entry.
  bool light_passes() const { return stages_.size() > 1; }
  bool accumulates() const { return accumulate_; }
  // Frame order matters (history between run() calls): a temporal filter, or accumulation.
  bool temporal() const { return accumulate_ || filter().info().temporal; }

  // The filter's needs plus the accumulation's (world position and normal; motion used),
  // plus every light pass with components=light_passes.
  PassNeeds needs() const;

  // Checks the passes (MissingPass naming the frame's file, before any work), accumulates
  // when asked, runs the filter. With light passes, `components` (when given) receives the
  // recombined layers, which sum to the returned beauty exactly. `alpha` (when given) receives
  // the filtered alpha (1 channel), or is left empty where the alpha is kept (alpha=keep, no
  // alpha pass, a constant alpha: the notes say why); without it the alpha is not filtered.
  Image run(const Frame& frame, const ExecOptions& options = {}, std::vector<ComponentImage>* components = nullptr,
            Image* alpha = nullptr);
  // The same without copying the frame: with accumulation its colour pass's RGB becomes
  // the accumulated one (other channels kept), and with alpha=filter its alpha pass becomes
  // the filtered alpha.
  Image run_in_place(Frame& frame, const ExecOptions& options = {}, std::vector<ComponentImage>* components = nullptr);
  // alpha=filter: the alpha's own filter (pipeline/alpha_stage.h; made on first use), else
  // null. For a run in bands, which filters the alpha itself.
  Filter* alpha_filter();
  // Drops the history of both stages (new shot, frames out of order).
  void reset();

  // The unused settings, then the notes of the last run() (the filter's, the accumulation's):
  // a copy, taken under the lock.
  std::vector<std::string> notes() const;
  // auto's choice in each stage of the last run(), under the lock; empty unless the filter is
  // auto (the notes say the same in words, with the scores).
  std::vector<StageChoice> choices() const;
  // "accumulate=true radius=3 ...": every setting, as the mcreconParameters attribute.
  std::string parameters_text() const;

 private:
  // One filter and its accumulation history: the beauty's, or one light stage's.
  struct Stage {
    std::unique_ptr<Filter> filter;
    TemporalAccumulator accumulator;
    SurfaceClasses classes;  // this frame's (prepare/surface_classes.h)
    HistoryGuards guards;    // the accumulation's (prepare/history_guards.h)
  };
  // Accumulates frame's colour in place when asked, runs the stage's filter.
  Image run_stage(Stage& stage, Frame& frame, const ExecOptions& options);
  // run_in_place() under the lock, the alpha aside.
  Image run_locked(Frame& frame, const ExecOptions& options, std::vector<ComponentImage>* components);
  // The alpha stage on the frame as the colour's filter saw it: the filtered alpha, or empty
  // where it is kept (a note says why).
  Image run_alpha(const Frame& frame, const ExecOptions& options);
  Image run_components(const Frame& frame, const ExecOptions& options, std::vector<ComponentImage>* components);

  std::vector<std::unique_ptr<Stage>> stages_;
  std::unique_ptr<Stage> alpha_;  // alpha=filter
  bool accumulate_ = false;
  std::vector<std::string> setup_notes_;  // settings the components mode overrides
  std::vector<std::string> notes_;
  // Held across every call that reads or changes the filter's per-run state (its prepared
  // buffers and notes) or the accumulation history: one frame at a time.
  mutable std::mutex mutex_;
};

// The filter made, every key=value set (from its table) and committed: all parameter
// errors surface here, before any file is touched.
std::unique_ptr<Filter> make_committed_filter(const std::string& filter,
                                              const std::vector<std::pair<std::string, std::string>>& params);

// "radius=3 demodulate=false ...": every parameter value of the filter.
std::string parameters_text(const Filter& filter);

}  // namespace mcr
