#include "pipeline/denoise_session.h"

#include <chrono>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <future>
#include <memory>

#include "io/band_reader.h"
#include "io/exr_output.h"
#include "io/output_guard.h"
#include "pipeline/alpha_stage.h"
#include "pipeline/sequence_plan.h"
#include "pipeline/tiled_run.h"
#include "util/error.h"

namespace mcr {

namespace {

// A bounded-memory run frees each band's buffers before the next: they must go back to the
// system. glibc serves an allocation from its heap once a freed mapping of that size raised
// its mmap threshold, and a heap rarely shrinks: band buffers (megabytes each) then pile up.
// A fixed threshold keeps every large buffer a mapping of its own.
void release_freed_memory() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 256 * 1024);
#endif
}

// The reverse for a sequence: every frame allocates the same large buffers (a 50 MB decoded
// file, the passes, the output), which glibc maps afresh each time above 32 MB, so each frame
// paid the kernel's page faults and zeroing again. Kept in the heap instead, they are reused:
// 5% of a 1280x720 bmfr sequence on 2 cores, at the same peak (the frames are alike).
void keep_freed_memory() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

// What the output's header says of the run (run_attributes(), as the plugin writes it) and
// mcreconInput: --resume checks mcreconFilter, mcreconParameters and mcreconInput.
std::vector<std::pair<std::string, std::string>> describe_run(const std::string& filter, const std::string& params,
                                                              const std::string& input, const StageTimes& t) {
  auto a = run_attributes(filter, params, choices_text(t.choices), notes_text(t.notes));
  a.emplace_back("mcreconInput", input_stamp(input));
  return a;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

std::pair<std::string, std::string> parse_key_value(const std::string& text, const std::string& option) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error(Errc::InvalidArgument, option + " expects KEY=VALUE, got '" + text + "'");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

DenoiseSession::DenoiseSession(const std::string& filter,
                               const std::vector<std::pair<std::string, std::string>>& params, bool accumulate)
    : reconstruction_(make_committed_filter(filter, params), accumulate) {}

// One frame between the stages: the input as read, the result and its components, and the
// header strings, fixed when it was filtered (the writer may run on another thread).
struct DenoiseSession::Filtered {
  Frame frame;
  Image result;
  std::vector<ComponentImage> components;
  std::vector<std::pair<std::string, std::string>> attributes;
  StageTimes times;
};

void DenoiseSession::check_output(const std::string& input, const std::string& output, const ReadOptions& read,
                                  const WriteOptions& write) {
  if (output.empty()) return;
  // Every front end's file run passes here: the output is checked against every input of
  // the run (the render and any loose pass file) before anything is read.
  std::vector<std::string> inputs = loose_pass_files(read);
  inputs.push_back(input);
  check_output_path(output, inputs);
  check_write(output, write);  // Python and the add-on too: what the name says, or an error
}

Frame DenoiseSession::read_checked(const std::string& input, const std::string& output, const ReadOptions& read,
                                   const WriteOptions& write) const {
  if (write.keep_components) check_keep_components(reconstruction_.filter().params());
  check_output(input, output, read, write);
  return read_frame(input, read);
}

void DenoiseSession::filter_into(Filtered& f, const WriteOptions& write, const ExecOptions& exec) {
  const auto t0 = std::chrono::steady_clock::now();
  // The frame is ours: with accumulation its colour becomes the accumulated one, which
  // the writer never reads (it takes alpha and the other channels from it).
  f.result = reconstruction_.run_in_place(f.frame, exec, write.keep_components ? &f.components : nullptr);
  f.times.filter_ms = ms_since(t0);
  f.times.notes = reconstruction_.notes();
  f.times.choices = reconstruction_.choices();
  f.attributes = describe_run(reconstruction_.filter().info().name, reconstruction_.parameters_text(), f.frame.path, f.times);
}

void DenoiseSession::write_filtered(const std::string& output, const Filtered& f, const WriteOptions& write) {
  WriteOptions w = write;
  w.attributes.insert(w.attributes.end(), f.attributes.begin(), f.attributes.end());
  for (const ComponentImage& c : f.components)
    w.layers.emplace_back(component_layer_prefix(f.frame.layer) + c.name, &c.rgb);
  write_result(output, f.result, f.frame, w);
}

StageTimes DenoiseSession::run(const std::string& input, const std::string& output, const ReadOptions& read,
                               const WriteOptions& write, const ExecOptions& exec) {
  Filtered f;
  auto t0 = std::chrono::steady_clock::now();
  f.frame = read_checked(input, output, read, write);
  f.times.read_ms = ms_since(t0);
  filter_into(f, write, exec);
  if (!output.empty()) {
    t0 = std::chrono::steady_clock::now();
    write_filtered(output, f, write);
    f.times.write_ms = ms_since(t0);
  }
  return f.times;
}

StageTimes DenoiseSession::run_in_bands(const std::string& input, const std::string& output, const ReadOptions& read,
                                        const WriteOptions& write, const ExecOptions& exec, int band_rows, double max_bytes,
                                        const std::function<void(int, int)>& progress) {
  const std::string what = band_rows > 0 ? "--band-rows" : "--max-memory";
  auto refuse = [&](const std::string& why) { throw Error(Errc::InvalidArgument, what + ": " + why); };
  Filter& filter = reconstruction_.filter();
  if (reconstruction_.temporal()) refuse("a temporal run (history between frames) is not cut into bands");
  if (reconstruction_.light_passes()) refuse("components=light_passes filters every light pass whole");
  if (!(exec.roi == Roi{})) refuse("--region filters part of the frame; bands filter all of it");
  if (write.keep_passes || write.keep_components) refuse("--keep-passes and --keep-components write every pass whole");
  if (filter.band_halo() < 0) refuse("filter '" + filter.info().name + "': " + filter.why_not_tileable());
  check_output(input, output, read, write);
  release_freed_memory();
  StageTimes t;
  const auto t0 = std::chrono::steady_clock::now();
  PassNeeds needs = filter.needs();
  std::vector<Role> roles;
  const auto keep = [&roles](const std::vector<Role>& more) {
    for (Role r : more)
      if (std::find(roles.begin(), roles.end(), r) == roles.end()) roles.push_back(r);
  };
  keep(needs.required);
  keep(needs.optional);
  keep({Role::Alpha});  // the output's
  // Read where present but not asked for: what tells the first-hit holes (prepare/first_hit.h).
  if (filter.prep_steps().first_hit) keep({Role::Depth, Role::Normal});
  Filter* alpha_filter = reconstruction_.alpha_filter();
  if (alpha_filter) {  // what the alpha's own run reads besides, and the normal its partly covered pixels
    const PassNeeds an = alpha_filter->needs();
    keep(an.required);
    keep(an.optional);
    keep({Role::Normal});
  }
  FileBands source(input, read, roles);
  check_passes(needs, source.layout(), "filter '" + filter.info().name + "'");
  TiledOptions o;
  o.nthreads = exec.nthreads;
  o.band_rows = band_rows > 0 ? band_rows
                              : band_rows_for(filter, source.width(), source.height(), source.kept_channels(), max_bytes);
  o.progress = progress;
  o.keep = {Role::Alpha};
  Filtered f;
  f.frame = source.layout().header(source.width(), source.height());
  f.frame.window = source.layout().window;
  std::vector<std::string> notes;
  f.result = run_tiled(filter, source, o, &notes, &f.frame);
  notes.front() += ", " + std::to_string(source.kept_channels()) + " of " + std::to_string(source.file_channels()) +
                   " channels kept";
  if (alpha_filter) filter_alpha_in_bands(*alpha_filter, source, o, band_rows > 0 ? 0.0 : max_bytes, f.frame, notes);
  t.read_ms = source.read_ms();  // the bands' reads, interleaved with filtering
  t.filter_ms = ms_since(t0) - t.read_ms;
  t.notes = std::move(notes);
  f.attributes = describe_run(filter.info().name, reconstruction_.parameters_text(), input, t);
  if (!output.empty()) {
    const auto t1 = std::chrono::steady_clock::now();
    write_filtered(output, f, write);
    t.write_ms = ms_since(t1);
  }
  return t;
}

void DenoiseSession::filter_alpha_in_bands(Filter& alpha_filter, FileBands& source, const TiledOptions& colour,
                                           double max_bytes, Frame& frame, std::vector<std::string>& notes) {
  const std::string why = alpha_kept_because(reconstruction_.filter().params(), frame);
  if (!why.empty()) {
    if (std::string n = alpha_kept_note(frame, why); !n.empty()) notes.push_back(std::move(n));
    return;
  }
  TiledOptions o = colour;
  o.keep.clear();
  // The colour's result (RGB float) is held while the alpha runs.
  if (max_bytes > 0)
    o.band_rows = band_rows_for(alpha_filter, source.width(), source.height(), source.kept_channels(),
                                max_bytes - 12.0 * double(source.width()) * double(source.height()));
  AlphaRows rows(source);
  std::vector<std::string> said;
  const AlphaRange range = alpha_range(frame.image(Role::Alpha));
  const Image filtered = run_tiled(alpha_filter, rows, o, &said);
  std::size_t kept = 0;
  Image alpha = finish_alpha(filtered, frame.image(Role::Alpha), rows.coverage(), range, o.nthreads, &kept);
  put_alpha(frame, std::move(alpha));
  notes.push_back(alpha_note(alpha_filter, range, kept));
  for (const std::string& n : said) notes.push_back("alpha: " + n);
}

void DenoiseSession::run_sequence(const std::vector<Job>& jobs, const WriteOptions& write, const ExecOptions& exec,
                                  bool pipelined, const std::function<void(std::size_t, const StageTimes&)>& done) {
  if (jobs.size() > 1) keep_freed_memory();
  if (!pipelined) {
    for (std::size_t i = 0; i < jobs.size(); ++i) done(i, run(jobs[i].input, jobs[i].output, jobs[i].read, write, exec));
    return;
  }
  // The reader and the writer are one thread each beside the filter's; one frame waits in
  // each. Futures from std::async join in their destructors, so an error thrown below still
  // waits for the write in flight: it completes or removes its temp file.
  auto read_job = [&](std::size_t i) {
    auto f = std::make_unique<Filtered>();
    const auto t0 = std::chrono::steady_clock::now();
    f->frame = read_checked(jobs[i].input, jobs[i].output, jobs[i].read, write);
    f->times.read_ms = ms_since(t0);
    return f;
  };
  std::future<std::unique_ptr<Filtered>> next;
  std::future<StageTimes> writing;
  std::size_t writing_index = 0;
  if (!jobs.empty()) next = std::async(std::launch::async, read_job, 0);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    std::unique_ptr<Filtered> f = next.get();
    if (i + 1 < jobs.size()) next = std::async(std::launch::async, read_job, i + 1);
    filter_into(*f, write, exec);
    if (writing.valid()) done(writing_index, writing.get());
    if (jobs[i].output.empty()) {
      done(i, f->times);
      continue;
    }
    writing_index = i;
    writing = std::async(std::launch::async, [&write, out = jobs[i].output, g = std::move(f)]() {
      const auto t0 = std::chrono::steady_clock::now();
      write_filtered(out, *g, write);
      StageTimes t = g->times;
      t.write_ms = ms_since(t0);
      return t;
    });
  }
  if (writing.valid()) done(writing_index, writing.get());
}

}  // namespace mcr
