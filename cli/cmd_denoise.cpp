#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <regex>

#include <tbb/info.h>

#include "commands.h"
#include "io/atomic_write.h"
#include "io/exr_output.h"
#include "io/sequence.h"
#include "json_views.h"
#include "pipeline/denoise_session.h"
#include "pipeline/sequence_plan.h"
#include "progress.h"
#include "util/error.h"
#include "validators.h"

namespace mcr::cli {

namespace {

struct DenoiseArgs {
  std::string input, output, filter, layer, frames, region, compression = "zip";
  std::string half;  // the other half buffer (a pattern for sequences)
  std::vector<std::string> sets, passes;
  bool keep_passes = false, keep_components = false, timings = false, verbose = false, resume = false;
  bool json = false;  // --json: a JSON line per frame on stdout
  bool accumulate = false;  // the accumulation stage before the filter
  bool serial = false;      // --serial: no overlap of read, filter and write
  bool pipelined = false;   // --pipelined: overlap them whatever the core count
  int threads = 0;
  int warmup = -1;  // --warmup N; -1: not given
  int max_memory = 0, band_rows = 0;  // --max-memory MB, --band-rows N: a single frame in bands
  DisplayTransform display;  // PNG/JPEG/TIFF outputs
  int bits = 0;
};

Roi parse_region(const std::string& text) {
  static const std::regex re(R"(^\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, re))
    throw Error(Errc::InvalidArgument, "--region expects X0,Y0,X1,Y1 (pixels, end exclusive), got '" + text + "'");
  Roi r;
  try {
    r = {std::stoi(m[1]), std::stoi(m[2]), std::stoi(m[3]), std::stoi(m[4])};
  } catch (const std::out_of_range&) {
    throw Error(Errc::InvalidArgument, "--region '" + text + "': a coordinate is out of range");
  }
  if (r.empty()) throw Error(Errc::InvalidArgument, "--region '" + text + "' is empty");
  return r;
}

std::string times_text(const StageTimes& t) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "read %.1f ms, filter %.1f ms, write %.1f ms, total %.1f ms", t.read_ms,
                t.filter_ms, t.write_ms, t.total_ms());
  return buf;
}

// --json: one frame's record, a line of its own on stdout (JSON Lines: a sequence's frames
// can be read as they come). output empty: a frame read for a temporal filter's history only.
void print_record(const std::string& input, const std::string& output, DenoiseSession& session, const StageTimes& t) {
  nlohmann::json chosen = nullptr;
  if (!t.choices.empty()) {
    chosen = nlohmann::json::object();
    for (const StageChoice& c : t.choices) chosen[c.stage] = c.filter;
  }
  const nlohmann::json j = {{"input", input},
                            {"output", output.empty() ? nlohmann::json(nullptr) : nlohmann::json(output)},
                            {"filter", session.filter().info().name},
                            {"parameters", session.reconstruction().parameters_text()},
                            {"chosen", chosen},
                            {"notes", t.notes},
                            {"ms", {{"read", number(t.read_ms)}, {"filter", number(t.filter_ms)}, {"write", number(t.write_ms)}}}};
  std::cout << j.dump() << std::endl;  // flushed: a farm's log shows each frame as it is done
}

int run_denoise(const DenoiseArgs& a) {
  std::vector<std::pair<std::string, std::string>> params;
  for (const auto& s : a.sets) params.push_back(parse_key_value(s, "--set"));
  DenoiseSession session(a.filter, params, a.accumulate);  // unknown filter / parameter errors first

  ReadOptions ro;
  ro.layer = a.layer;
  ro.keep_extra = a.keep_passes;
  for (const auto& p : a.passes) ro.overrides.push_back(parse_pass_override(p));
  WriteOptions wo;
  wo.keep_passes = a.keep_passes;
  wo.keep_components = a.keep_components;
  wo.compression = checked_exr_compression(a.compression);
  wo.display = a.display;
  wo.bits = a.bits;
  ExecOptions eo;
  eo.nthreads = a.threads;
  if (!a.region.empty()) eo.roi = parse_region(a.region);

  // Frame list: a single file, or a pattern with --frames.
  const bool seq = is_sequence_pattern(a.input);
  if (!a.half.empty() && seq != is_sequence_pattern(a.half))
    throw Error(Errc::InvalidArgument, "--half '" + a.half + "' must be a pattern exactly when the input '" + a.input + "' is");
  const bool temporal = session.reconstruction().temporal();
  const std::string filter_name = session.filter().info().name;
  if (seq && a.frames.empty()) throw Error(Errc::InvalidArgument, "input '" + a.input + "' is a sequence pattern: give --frames A-B");
  if (!seq && !a.frames.empty()) throw Error(Errc::InvalidArgument, "--frames needs a sequence pattern (#### or %04d) as input");
  if (!seq && a.warmup >= 0) throw Error(Errc::InvalidArgument, "--warmup needs a sequence pattern (#### or %04d) as input");
  if (seq && !is_sequence_pattern(a.output))
    throw Error(Errc::InvalidArgument, "output '" + a.output + "' must be a pattern (#### or %04d) for a sequence input");
  const FrameList frames = seq ? parse_frame_list(a.frames) : FrameList({0});
  if (seq && temporal && !frames.consecutive())
    throw Error(Errc::InvalidArgument, "--frames '" + a.frames + "': " + filter_name +
                                           (a.accumulate ? " with --accumulate" : "") +
                                           " carries history by one frame's motion, so its frames must be consecutive "
                                           "(run each consecutive range on its own)");
  auto input_of = [&](int f) { return seq ? sequence_path(a.input, f) : a.input; };
  auto output_of = [&](int f) { return seq ? sequence_path(a.output, f) : a.output; };
  auto half_of = [&](int f) { return a.half.empty() ? std::string() : seq ? sequence_path(a.half, f) : a.half; };

  // Check every frame before the first is filtered: a missing frame 90 of 100
  // or an output over an input should not cost a whole run.
  std::vector<std::string> inputs;
  auto need_input = [&](int f, const std::string& why) {
    const std::string in = input_of(f);
    std::error_code ec;
    if (!std::filesystem::exists(in, ec)) throw Error(Errc::FileNotFound, "cannot read '" + in + "'" + why + ": no such file");
    inputs.push_back(in);
    const std::string h = half_of(f);
    if (h.empty()) return;
    if (!std::filesystem::exists(h, ec)) throw Error(Errc::FileNotFound, "cannot read --half '" + h + "': no such file");
    if (std::filesystem::equivalent(h, in, ec))
      throw Error(Errc::InvalidArgument, "--half '" + h + "' is the input itself: give the other half buffer");
    inputs.push_back(h);
  };
  for (int f : frames.frames()) need_input(f, "");
  for (std::string& f : loose_pass_files(ro)) inputs.push_back(std::move(f));  // --pass normal=n.exr
  if (seq) check_sequence_outputs(a.output, frames, inputs);  // every frame its own file
  else check_output_paths({a.output}, inputs);
  check_write(a.output, wo);  // after the guard: a device or an input is the graver fault to name

  // Settings that change nothing: said once, not per frame.
  const std::vector<std::string>& unused = session.filter().unused_settings();
  if (a.verbose) {
    for (const auto& n : unused) std::cerr << "mcrecon: note: " << n << "\n";
    if (!temporal && a.warmup >= 0)
      std::cerr << "mcrecon: note: --warmup changes nothing: " << filter_name << " keeps no history\n";
  }
  // --resume: an output counts as done only if it reads completely (a run killed by
  // SIGKILL or a full disk may have left it cut short) and its header names this filter,
  // these parameters and this input; any other is redone.
  std::vector<bool> done(frames.size(), false);
  int redo = 0;
  if (a.resume) {
    const std::string params = session.reconstruction().parameters_text();
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const int f = frames.frames()[i];
      std::error_code ec;
      if (!std::filesystem::exists(output_of(f), ec)) continue;
      const std::string why = stale_output_reason(output_of(f), filter_name, params, input_of(f));
      done[i] = why.empty();
      if (done[i] && seq) std::cerr << "mcrecon: skip " << output_of(f) << " (done)\n";
      if (!done[i]) {
        ++redo;
        std::cerr << "mcrecon: redo " << output_of(f) << " (" << why << ")\n";
      }
    }
  }
  if (a.max_memory > 0 || a.band_rows > 0) {
    // Each frame in bands, one after the other (a temporal run is refused before any work).
    const std::string opt = a.band_rows > 0 ? "--band-rows" : "--max-memory";
    if (!a.half.empty()) throw Error(Errc::InvalidArgument, opt + ": --half merges two whole frames; not in bands");
    if (temporal)
      throw Error(Errc::InvalidArgument, opt + ": a temporal run (history between frames) is not cut into bands");
    const std::vector<int>& list = frames.frames();
    if (seq && std::count(done.begin(), done.end(), true))
      std::cerr << "mcrecon: " << std::count(done.begin(), done.end(), true) << " of " << frames.size()
                << " frames already done (--resume)\n";
    Progress frames_bar("denoise " + a.filter + " in bands", int(list.size()));
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (done[i]) {
        if (!seq) std::cerr << "mcrecon: " << a.output << " is done (same filter, parameters and input): kept (--resume)\n";
        continue;
      }
      std::unique_ptr<Progress> bar;  // a single frame: progress per band
      int last = 0, runs = 0;         // the alpha's run (alpha=filter) counts again from 1
      const StageTimes t = session.run_in_bands(input_of(list[i]), output_of(list[i]), ro, wo, eo, a.band_rows,
                                                double(a.max_memory) * 1024.0 * 1024.0, [&](int d, int all) {
                                                  if (seq) return;
                                                  if (!bar || d <= last) {
                                                    if (bar) bar->finish("the colour");
                                                    bar = std::make_unique<Progress>(
                                                        "denoise " + a.filter + " in bands" + (runs++ ? " (alpha)" : ""), all);
                                                  }
                                                  last = d;
                                                  bar->step(d, "statistics passes, then the filter");
                                                });
      if (bar) bar->finish(a.output);
      if (a.json) print_record(input_of(list[i]), output_of(list[i]), session, t);
      if (a.verbose)
        for (const auto& n : t.notes)
          if (std::find(unused.begin(), unused.end(), n) == unused.end())
            std::cerr << "mcrecon: " << input_of(list[i]) << ": " << n << "\n";
      if (seq) frames_bar.step(int(i + 1), output_of(list[i]) + (a.timings || a.verbose ? "  " + times_text(t) : ""));
      else if (a.timings || a.verbose) std::cerr << "mcrecon: " << a.output << ": " << times_text(t) << "\n";
    }
    if (seq) frames_bar.finish();
    return 0;
  }
  const std::vector<FrameJob> jobs = plan_sequence(frames, done, temporal, a.warmup);
  // Warm-up frames before the list's first: they must exist, and no output may fall on one.
  const std::size_t listed = inputs.size();
  for (const FrameJob& j : jobs)
    if (j.frame < frames.first()) need_input(j.frame, " (a --warmup " + std::to_string(a.warmup) + " frame)");
  if (inputs.size() > listed)
    check_sequence_outputs(a.output, frames, std::vector<std::string>(inputs.begin() + long(listed), inputs.end()));
  const int skipped = int(std::count(done.begin(), done.end(), true));
  Progress progress("denoise " + a.filter, int(jobs.size()));
  if (seq && skipped)
    std::cerr << "mcrecon: " << skipped << " of " << frames.size() << " frames already done"
              << (redo ? ", " + std::to_string(redo) + " to redo" : "") << " (--resume)\n";
  if (!seq && skipped) std::cerr << "mcrecon: " << a.output << " is done (same filter, parameters and input): kept (--resume)\n";
  StageTimes sum;
  int written = 0, replayed = 0;
  std::vector<DenoiseSession::Job> session_jobs;
  for (const FrameJob& job : jobs) {
    DenoiseSession::Job j{input_of(job.frame), job.write ? output_of(job.frame) : std::string(), ro};
    j.read.second_half = half_of(job.frame);
    session_jobs.push_back(std::move(j));
  }
  // Sequences overlap reading, filtering and writing where there are cores to spare: on 2 every
  // stage already uses both, and the overlap gained nothing (0.98x-1.02x, mcrecon_bench_sequence)
  // for three frames in memory instead of one. One frame has nothing to overlap.
  const int cores = tbb::info::default_concurrency();
  const bool spare = (a.threads > 0 ? std::min(a.threads, cores) : cores) >= 4;
  session.run_sequence(session_jobs, wo, eo, seq && !a.serial && (a.pipelined || spare), [&](std::size_t i, const StageTimes& t) {
    const std::string& in = session_jobs[i].input;
    const std::string& out = session_jobs[i].output;
    sum.read_ms += t.read_ms;
    sum.filter_ms += t.filter_ms;
    sum.write_ms += t.write_ms;
    out.empty() ? ++replayed : ++written;
    if (a.json) print_record(in, out, session, t);
    if (a.verbose)
      for (const auto& n : t.notes)
        if (std::find(unused.begin(), unused.end(), n) == unused.end()) std::cerr << "mcrecon: " << in << ": " << n << "\n";
    if (seq) progress.step(int(i + 1), (out.empty() ? "warm-up " + in : out) + (a.timings || a.verbose ? "  " + times_text(t) : ""));
    else if (a.timings || a.verbose) std::cerr << "mcrecon: " << out << ": " << times_text(t) << "\n";
  });
  if (seq) {
    progress.finish(std::to_string(written) + " written, " + std::to_string(skipped) + " already done" +
                    (replayed ? ", " + std::to_string(replayed) + " read for history only" : ""));
    if (a.timings || a.verbose) std::cerr << "mcrecon: all frames: " << times_text(sum) << "\n";
  }
  return 0;
}

}  // namespace

Run add_denoise(CLI::App& app) {
  auto a = std::make_shared<DenoiseArgs>();
  app.add_option("input", a->input, "render or sequence pattern (shot_####.exr, shot_%04d.exr)")->required();
  app.add_option("-o,--output", a->output,
                 "output file (a pattern for sequences): .exr (scene-linear float) or .png, .jpg, .tif "
                 "(display-referred through --view)")
      ->required();
  app.add_option("-f,--filter", a->filter,
                 "filter name (see `mcrecon filters`); auto scores every filter the passes allow on sample tiles "
                 "and runs the best, or keeps the input (--verbose names its choice and the scores)")
      ->required();
  app.add_option("-s,--set", a->sets, "filter parameter KEY=VALUE (repeatable)")->allow_extra_args(false);
  app.add_option("--layer", a->layer, "view layer (default: the first with a colour pass)");
  app.add_option("--pass", a->passes, "ROLE=FILE or ROLE=CHANNEL_GROUP override (repeatable)")->allow_extra_args(false);
  app.add_option("--frames", a->frames, "frames of a sequence pattern as oiiotool writes them: 1-16, 1-16x2, 1-16y2, 1,5,9");
  app.add_option("--half", a->half,
                 "the other half buffer of the input (the same render's samples split in two, e.g. Blender's "
                 "sample_offset): filter their mean, with the noise from their difference (a pattern for sequences)");
  app.add_option("--region", a->region, "only filter X0,Y0,X1,Y1 (end exclusive); the rest keeps the input");
  add_threads_option(app, a->threads);
  app.add_option("--compression", a->compression, "EXR compression of the output (zip, piz, none, ...)");
  app.add_flag("--keep-passes", a->keep_passes, "carry the input's other channels into the output");
  app.add_flag("--keep-components", a->keep_components,
               "with --set components=light_passes: write each denoised light component as its own float layer "
               "(<layer>.Denoised.Diffuse, Glossy, Transmission, Emission, Environment), summing to R,G,B exactly");
  app.add_option("--view", a->display.view,
                 "PNG/JPEG/TIFF output: the OpenColorIO view (Blender's: Standard, Filmic, Filmic Log, Raw, False Color)")
      ->capture_default_str();
  app.add_option("--look", a->display.look, "PNG/JPEG/TIFF output: an OpenColorIO look (e.g. 'Medium High Contrast')");
  app.add_option("--display", a->display.display, "PNG/JPEG/TIFF output: the OpenColorIO display")->capture_default_str();
  app.add_option("--exposure", a->display.exposure, "PNG/JPEG/TIFF output: exposure in stops before the view")
      ->capture_default_str();
  app.add_option("--gamma", a->display.gamma, "PNG/JPEG/TIFF output: display gamma after the view")->capture_default_str();
  app.add_option("--ocio-config", a->display.config, "OpenColorIO config for the view (default: Blender's)")
      ->capture_default_str();
  app.add_option("--bit-depth", a->bits, "PNG/TIFF output: 8 or 16 bits per channel (default: PNG 8, TIFF 16; JPEG is 8)");
  app.add_flag("--resume", a->resume,
               "keep outputs that exist, read completely and were made by the same filter, parameters and input "
               "(others are redone); a temporal filter replays, without writing, only the done frames its history "
               "needs");
  app.add_option("--warmup", a->warmup,
                 "temporal filters: start the history N frames before the first of --frames, without writing "
                 "them (a chunk of a split sequence then has the history a single run has, up to N frames back)")
      ->check(CLI::Range(0, 1000000));
  app.add_flag("--accumulate", a->accumulate,
               "temporally accumulate the noisy colour (BMFR phase I: needs world position, normal; uses motion) before the filter");
  auto* serial = app.add_flag("--serial", a->serial,
                              "sequences: read, filter and write one frame after the other (the default with fewer "
                              "than 4 threads, where every stage already uses them all)");
  app.add_flag("--pipelined", a->pipelined,
               "sequences: read the next frame and write the last while one is filtered (the default with 4 threads "
               "or more; three frames in memory instead of one; hides slow storage)")
      ->excludes(serial);
  app.add_option("--max-memory", a->max_memory,
                 "one frame in bands of rows, sized to stay under MB megabytes (like OIDN's maxMemoryMB): only the "
                 "passes the filter reads are decoded, a band at a time; the same pixels as the whole frame")
      ->check(CLI::Range(1, 1 << 24));
  app.add_option("--band-rows", a->band_rows, "one frame in bands of N rows (a multiple of 64; see --max-memory)")
      ->check(CLI::Range(1, 1 << 24));
  app.add_flag("--timings", a->timings, "print read / filter / write times per frame");
  app.add_flag("--json", a->json,
               "a JSON object per frame on standard output, a line each: input, output (null for a frame read "
               "for history only), filter, parameters, chosen (filter auto: what it ran, per stage: {\"beauty\": "
               "\"atrous\"} or the light stages; else null), notes, ms (read, filter, write)");
  app.add_flag("-v,--verbose", a->verbose, "timings plus the filter's notes");
  return [a] { return run_denoise(*a); };
}

}  // namespace mcr::cli
