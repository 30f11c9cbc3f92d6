#pragma once
// The file pipeline shared by the front ends: read passes -> reconstruction (optional
// accumulation, the filter) -> write, with per-stage timings. One session keeps one
// reconstruction (and its temporal history) across the frames of a sequence.
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "pipeline/reconstruction.h"
#include "pipeline/tiled_run.h"

namespace mcr {

class FileBands;

struct StageTimes {
  double read_ms = 0, filter_ms = 0, write_ms = 0;
  std::vector<std::string> notes;  // the reconstruction's notes on this frame
  std::vector<StageChoice> choices;  // filter auto: what it ran in each stage
  double total_ms() const { return read_ms + filter_ms + write_ms; }
};

class DenoiseSession {
 public:
  // Makes the filter, sets every key=value (from its table) and commits: all
  // parameter errors surface here, before any file is touched. accumulate: the
  // temporal accumulation stage before the filter (pipeline/reconstruction.h).
  DenoiseSession(const std::string& filter, const std::vector<std::pair<std::string, std::string>>& params,
                 bool accumulate = false);

  Filter& filter() { return reconstruction_.filter(); }
  Reconstruction& reconstruction() { return reconstruction_; }

  // Reads input, filters, and writes output unless output is empty (warm-up of
  // temporal history on frames that already have an output). The output is checked
  // first (io/output_guard.h): never an input of the run, only a regular file or a
  // new path. write.keep_components (needs components=light_passes) adds every denoised
  // component as its own layer (pipeline/components.h), summing to R,G,B exactly.
  StageTimes run(const std::string& input, const std::string& output, const ReadOptions& read,
                 const WriteOptions& write, const ExecOptions& exec);

  // run() of one frame in bands of rows (pipeline/tiled_run.h): the same pixels, in bounded
  // memory; only the passes the filter reads are decoded, a band at a time. band_rows > 0
  // sets the band height; else max_bytes (> 0) chooses it (band_rows_for). progress(done,
  // all) after each band of each pass (with alpha=filter, the alpha's run counts again from
  // 1: pipeline/alpha_stage.h). Throws InvalidArgument, naming the option, for what
  // bands cannot do: a temporal run, components=light_passes, a region, --keep-passes,
  // --keep-components, a deep or multi-part file, loose pass files, half buffers, foveation.
  StageTimes run_in_bands(const std::string& input, const std::string& output, const ReadOptions& read,
                          const WriteOptions& write, const ExecOptions& exec, int band_rows, double max_bytes,
                          const std::function<void(int, int)>& progress);

  // A sequence of run()s. pipelined: frame i+1 is read and frame i-1 written while frame i
  // is filtered (three frames in memory instead of one; the same outputs, in order). An
  // error stops the run after the write in flight has finished: every output written is
  // complete. done(i, times) is called in order once job i is written (or filtered, for a
  // job without output).
  struct Job {
    std::string input, output;  // output empty: filtered for the temporal history only
    ReadOptions read;
  };
  void run_sequence(const std::vector<Job>& jobs, const WriteOptions& write, const ExecOptions& exec, bool pipelined,
                    const std::function<void(std::size_t, const StageTimes&)>& done);

 private:
  struct Filtered;
  // The output against every input of the run (never one of them) and the write options.
  static void check_output(const std::string& input, const std::string& output, const ReadOptions& read,
                           const WriteOptions& write);
  Frame read_checked(const std::string& input, const std::string& output, const ReadOptions& read,
                     const WriteOptions& write) const;
  void filter_into(Filtered& f, const WriteOptions& write, const ExecOptions& exec);
  static void write_filtered(const std::string& output, const Filtered& f, const WriteOptions& write);
  // The alpha's own run over the bands of `source` after the colour's (alpha=filter): frame's
  // alpha pass (gathered by the colour's run) becomes the filtered one. max_bytes 0: the
  // colour's band height, else the height that fits beside the colour's result.
  void filter_alpha_in_bands(Filter& alpha_filter, FileBands& source, const TiledOptions& colour, double max_bytes,
                             Frame& frame, std::vector<std::string>& notes);

  Reconstruction reconstruction_;
};

// "key=value" -> pair; throws InvalidArgument.
std::pair<std::string, std::string> parse_key_value(const std::string& text, const std::string& option);

}  // namespace mcr
