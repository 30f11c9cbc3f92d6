#include "report/report_runs.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <regex>
#include <sstream>

#include "io/frame_reader.h"
#include "io/sequence.h"
#include "pipeline/auto_filter.h"
#include "util/error.h"
#include "util/memory_usage.h"

namespace mcr {

namespace fs = std::filesystem;

LoadedReportScene load_report_scene(const ReportScene& scene) {
  LoadedReportScene s;
  s.scene = scene;
  for (std::size_t i = 0; i < scene.frames.size(); ++i) {
    s.flat.push_back(read_frame(scene.noisy[i]));
    s.flat.back().frame_number = scene.frames[i];
    if (!scene.deep[i].empty()) {
      if (scene.deep[i] == scene.noisy[i]) {
        if (s.flat.back().deep) s.deep.push_back(s.flat.back());
      } else {
        s.deep.push_back(read_frame(scene.deep[i]));
        s.deep.back().frame_number = scene.frames[i];
      }
    }
    Frame ref = read_frame(scene.reference[i]);
    const Image& rgb = ref.image(Role::Colour);
    if (rgb.width() != s.flat.back().width || rgb.height() != s.flat.back().height)
      throw Error(Errc::SizeMismatch, "reference '" + scene.reference[i] + "' is " + std::to_string(rgb.width()) + "x" +
                                          std::to_string(rgb.height()) + ", the render '" + scene.noisy[i] + "' " +
                                          std::to_string(s.flat.back().width) + "x" +
                                          std::to_string(s.flat.back().height));
    s.references.push_back(rgb);
  }
  if (s.deep.size() != s.flat.size()) s.deep.clear();  // deep filters need every frame
  if (s.scene.kind.empty()) {
    const Frame& f = s.flat.front();
    s.scene.kind = f.lightfield ? "lightfield" : f.deep ? "deep" : s.flat.size() > 1 ? "sequence" : "still";
  }
  return s;
}

Scores score_outputs(const std::vector<Image>& outputs, const std::vector<Image>& references, int nthreads) {
  Scores sc;
  const double n = double(outputs.size());
  double temporal = 0;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const ImageMetrics m = compare_images(references[i], outputs[i], nthreads);
    sc.mean.rmse += m.rmse / n;
    sc.mean.relmse += m.relmse / n;
    sc.mean.psnr += m.psnr / n;
    sc.mean.ssim += m.ssim / n;
    sc.frame_relmse.push_back(m.relmse);
    sc.frame_temporal.push_back(i ? temporal_error(outputs[i - 1], outputs[i], nthreads) : -1.0);
    if (i) temporal += sc.frame_temporal.back();
  }
  if (outputs.size() > 1) sc.temporal_error = temporal / (n - 1);
  return sc;
}

const std::vector<Frame>* frames_for(const LoadedReportScene& s, Filter& filter, std::string& why) {
  const FilterInfo& info = filter.info();
  const std::vector<Frame>* frames = &s.flat;
  if (info.deep_input) {
    const bool lightfield = !s.deep.empty() && s.deep.front().lightfield;
    if (s.deep.empty() || lightfield != info.lightfield_input) {
      why = info.lightfield_input ? "needs a light-field deep EXR" : "needs per-sample (deep) input";
      return nullptr;
    }
    frames = &s.deep;
  }
  const std::vector<Role> missing = filter.missing_passes(frames->front());
  if (!missing.empty()) {
    why = "missing passes:";
    for (Role m : missing) why += std::string(" ") + role_name(m);
    return nullptr;
  }
  return frames;
}

std::string choices_summary(const std::vector<std::string>& per_frame) {
  std::vector<std::pair<std::string, int>> counts;  // in the order they came
  for (const std::string& c : per_frame) {
    auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& p) { return p.first == c; });
    if (it == counts.end()) counts.emplace_back(c, 1);
    else ++it->second;
  }
  if (counts.size() == 1) return counts.front().first;
  std::stable_sort(counts.begin(), counts.end(), [](const auto& x, const auto& y) { return x.second > y.second; });
  std::string t;
  for (const auto& [name, n] : counts) t += (t.empty() ? "" : ", ") + name + " x" + std::to_string(n);
  return t;
}

RunResult run_in_process(const LoadedReportScene& s, Filter& filter, const std::vector<Frame>& frames, int nthreads) {
  RunResult r;
  r.filter = filter.info().name;
  ExecOptions exec;
  exec.nthreads = nthreads;
  filter.reset();
  const bool peak = reset_peak_resident();
  const double before = resident_mb();
  double seconds = 0;
  const auto* a = dynamic_cast<const AutoFilter*>(&filter);
  std::vector<std::string> chosen;  // auto's, per frame
  for (const Frame& f : frames) {
    const auto t0 = std::chrono::steady_clock::now();
    r.outputs.push_back(filter.execute(f, exec));
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (a) chosen.push_back(a->chosen());
  }
  // The outputs are kept for scoring: subtract them, they are not the filter's working memory.
  double kept = 0;
  for (const Image& o : r.outputs) kept += double(o.storage().size() * sizeof(float)) / (1024.0 * 1024.0);
  if (peak) r.peak_memory_mb = std::max(0.0, peak_resident_mb() - before - kept);
  r.seconds = r.filter_seconds = seconds;
  r.scores = score_outputs(r.outputs, s.references, nthreads);
  for (const std::string& n : filter.notes()) r.notes.push_back(n);
  if (a) {
    r.kind = "auto";
    r.chosen = choices_summary(chosen);
  }
  return r;
}

namespace {

// "mcrecon: ...: read 28.9 ms, filter 13.0 ms, write ..." (the last such line: all frames).
double parse_filter_ms(const std::string& log) {
  static const std::regex re("filter ([0-9.]+) ms");
  double ms = -1;
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (line.rfind("mcrecon:", 0) == 0 && std::regex_search(line, m, re)) ms = std::stod(m[1]);
  }
  return ms;
}

// The notes `mcrecon denoise --verbose` printed ("mcrecon: FILE: note"; not its timing lines),
// once each, and auto's choice from each frame's "auto: chose X with ..." / "auto: chose the
// input ..." (choices_summary()).
void take_notes(const std::string& log, RunResult& r) {
  std::istringstream in(log);
  std::vector<std::string> chosen;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("mcrecon: ", 0) != 0) continue;
    const std::size_t colon = line.find(": ", 9);
    if (colon == std::string::npos) continue;
    const std::string note = line.substr(colon + 2);
    if (note.rfind("read ", 0) == 0) continue;  // "read 24 ms, filter 12 ms, ..."
    if (std::find(r.notes.begin(), r.notes.end(), note) == r.notes.end() && r.notes.size() < 40) r.notes.push_back(note);
    if (note.rfind("auto: chose the input", 0) == 0) chosen.push_back("input");
    else if (note.rfind("auto: chose ", 0) == 0) chosen.push_back(note.substr(12, note.find(' ', 12) - 12));
  }
  r.chosen = choices_summary(chosen);
}

void fail(RunResult& r, const std::string& what, const CommandRun& run, const std::string& log) {
  r.error = what + (run.timed_out ? ": timed out" : ": exit " + std::to_string(run.exit_code)) + "; " + log_tail(log);
}

std::vector<Image> read_outputs(const std::vector<std::string>& files, const LoadedReportScene& s, RunResult& r) {
  std::vector<Image> out;
  for (std::size_t i = 0; i < files.size(); ++i) {
    try {
      Image img = read_pass_file(files[i], Role::Colour).image;
      if (img.width() != s.references[i].width() || img.height() != s.references[i].height() || img.channels() < 3)
        throw Error(Errc::SizeMismatch, "'" + files[i] + "' is " + std::to_string(img.width()) + "x" +
                                            std::to_string(img.height()) + " with " + std::to_string(img.channels()) +
                                            " channels, the render " + std::to_string(s.references[i].width()) + "x" +
                                            std::to_string(s.references[i].height()) + " RGB");
      out.push_back(std::move(img));
    } catch (const Error& e) {
      r.error = std::string("its output: ") + e.what();
      return {};
    }
  }
  return out;
}

}  // namespace

RunResult run_as_command(const LoadedReportScene& s, const std::string& filter, const std::string& set,
                         bool deep_input, const CommandTiming& timing) {
  RunResult r;
  r.filter = filter;
  const ReportScene& sc = s.scene;
  const bool sequence = !sc.frames_text.empty();
  std::string tag = filter + (set.empty() ? "" : "_" + set);  // one file name per setting
  for (char& ch : tag)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '.' && ch != '_') ch = '_';
  const std::string out = (fs::path(timing.work_dir) / (sc.id + "_" + tag + (sequence ? "_####.exr" : ".exr"))).string();
  // --verbose: the timings and the filter's notes (auto's choice among them).
  std::vector<std::string> argv = {timing.cli, "denoise", "-f", filter, "--verbose", "-j", std::to_string(timing.nthreads)};
  if (!set.empty()) argv.insert(argv.end(), {"--set", set});
  if (sequence) argv.insert(argv.end(), {"--frames", sc.frames_text});
  argv.push_back(sequence ? (deep_input ? sc.deep_pattern : sc.noisy_pattern) : (deep_input ? sc.deep[0] : sc.noisy[0]));
  argv.insert(argv.end(), {"-o", out});
  const std::string log = out.substr(0, out.size() - 4) + ".log";
  const CommandRun run = run_timed_command(argv, log, timing.timeout_seconds);
  if (run.exit_code != 0 || run.timed_out) {
    fail(r, "mcrecon denoise -f " + filter, run, log);
    return r;
  }
  r.seconds = run.seconds;
  r.peak_memory_mb = run.peak_memory_mb;
  const std::string text = read_log(log);
  const double ms = parse_filter_ms(text);
  r.filter_seconds = ms >= 0 ? ms / 1000.0 : -1;
  take_notes(text, r);
  std::vector<std::string> files;
  for (int f : sc.frames) files.push_back(sequence ? sequence_path(out, f) : out);
  r.outputs = read_outputs(files, s, r);
  if (r.ok()) r.scores = score_outputs(r.outputs, s.references, timing.nthreads);
  return r;
}

RunResult run_peer(const LoadedReportScene& s, const PeerCommand& peer, const CommandTiming& timing) {
  RunResult r;
  r.filter = peer.name;
  r.kind = "peer";
  r.id = "peer_" + peer.name;
  r.seconds = 0;
  std::vector<std::string> files;
  for (std::size_t i = 0; i < s.flat.size(); ++i) {
    const fs::path dir = fs::path(timing.work_dir) / (s.scene.id + "_peer_" + peer.name + "_" + std::to_string(i));
    fs::create_directories(dir);
    std::string output;
    std::vector<std::string> argv;
    try {
      argv = peer_argv(peer, s.flat[i], dir.string(), output);
    } catch (const Error& e) {
      r.error = e.what();
      return r;
    }
    const std::string log = (dir / "peer.log").string();
    const CommandRun run = run_timed_command(argv, log, timing.timeout_seconds);
    if (run.exit_code != 0 || run.timed_out) {
      fail(r, "peer '" + peer.name + "' on '" + s.scene.noisy[i] + "'", run, log);
      return r;
    }
    if (!fs::is_regular_file(output)) {
      r.error = "peer '" + peer.name + "' exited 0 but wrote no '" + output + "'; " + log_tail(log);
      return r;
    }
    r.seconds += run.seconds;
    r.peak_memory_mb = std::max(r.peak_memory_mb, run.peak_memory_mb);
    files.push_back(output);
  }
  r.outputs = read_outputs(files, s, r);
  if (r.ok()) r.scores = score_outputs(r.outputs, s.references, timing.nthreads);
  return r;
}

}  // namespace mcr
