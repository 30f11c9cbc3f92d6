#include "report/report.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include <nlohmann/json.hpp>

#include "io/atomic_write.h"
#include "io/frame_reader.h"
#include "io/output_guard.h"
#include "io/preview.h"
#include "io/sample_manifest.h"
#include "pipeline/filter_catalog.h"
#include "report/parameter_sweeps.h"
#include "report/report_math.h"
#include "report/report_images.h"
#include "report/report_runs.h"
#include "report/scaling.h"
#include "util/error.h"
#include "util/params.h"
#include "util/parallel.h"

namespace mcr {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
json nonneg(double v) { return v >= 0 && std::isfinite(v) ? json(v) : json(nullptr); }

std::string safe_name(std::string s) {
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return s;
}

// One process writes a report folder at a time: two runs into one folder would interleave.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& dir) {
    const std::string path = (dir / ".mcrecon-report.lock").string();
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Error(Errc::WriteFailed, "--out '" + dir.string() + "': cannot create " + path);
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw Error(Errc::InvalidArgument, "--out '" + dir.string() + "': another mcrecon report is writing there");
    }
  }
  ~FolderLock() { ::close(fd_); }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Removed however the run ends.
struct WorkDir {
  fs::path path;
  ~WorkDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

json machine_json(int threads) {
  json m;
  std::string cpu = "unknown";
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);)
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  double mem_gb = 0;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string line; std::getline(meminfo, line);)
    if (line.rfind("MemTotal:", 0) == 0) mem_gb = std::stod(line.substr(9)) / (1024.0 * 1024.0);
  struct utsname u {};
  uname(&u);
  m["cpu"] = cpu;
  m["logical_cores"] = int(std::thread::hardware_concurrency());
  m["threads"] = threads;
  m["os"] = std::string(u.sysname) + " " + u.release;
  m["memory_gb"] = std::round(mem_gb * 10) / 10;
  return m;
}

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

json per_frame_json(const ReportScene& sc, const Scores& s) {
  if (sc.frames.size() < 2) return nullptr;
  json t = json::array();
  for (double v : s.frame_temporal) t.push_back(nonneg(v));
  json r = json::array();
  for (double v : s.frame_relmse) r.push_back(num(v));
  return {{"frame", sc.frames}, {"relmse", r}, {"temporal_error", t}};
}

void mark_pareto(std::vector<RunResult>& runs) {
  std::vector<std::size_t> ok;
  std::vector<std::pair<double, double>> rel, ssim;
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (runs[i].ok()) {
      ok.push_back(i);
      rel.push_back({runs[i].seconds, runs[i].scores.mean.relmse});
      ssim.push_back({runs[i].seconds, runs[i].scores.mean.ssim});
    }
  const std::vector<bool> fr = pareto_front(rel, true), fs = pareto_front(ssim, false);
  for (std::size_t k = 0; k < ok.size(); ++k) {
    runs[ok[k]].pareto_relmse = fr[k];
    runs[ok[k]].pareto_ssim = fs[k];
  }
}

struct Context {
  Context(const ReportOptions& options, int nthreads) : o(options), out(options.out), threads(nthreads) {}
  const ReportOptions& o;
  fs::path out;
  int threads;
  bool command_timing = false;
  CommandTiming timing;
  std::vector<PeerCommand> peers;
  std::vector<std::string> filters;
  json scenes = json::array();
  std::vector<std::vector<std::string>> csv;
  std::string cpu;  // for every CSV row: a row read alone says where it was measured
  int runs = 0, failed = 0;
  void log(const std::string& line) const {
    if (o.log) o.log(line);
  }
};

void add_csv(Context& c, const json& scene, const json& row, const std::string& section) {
  auto cell = [](const json& v) -> std::string {
    if (v.is_null()) return "";
    if (v.is_string()) return v.get<std::string>();
    if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
    return number_text(v.get<double>());  // the fewest digits that read back as the JSON's value
  };
  c.csv.push_back({section, cell(scene["scene"]), cell(scene["input"]), cell(scene["spp"]), cell(scene["kind"]),
                   cell(row.value("filter", json(row.value("label", "")))), cell(row.value("parameters", json(""))),
                   cell(row.value("default", json(nullptr))), cell(row.value("seconds", json(nullptr))),
                   cell(row.value("filter_seconds", json(nullptr))), cell(row.value("peak_memory_mb", json(nullptr))),
                   cell(row["relmse"]), cell(row["psnr"]), cell(row["ssim"]), cell(row["temporal_error"]),
                   cell(row.value("worth_x_samples", json(nullptr))), cell(scene["width"]), cell(scene["height"]),
                   cell(json(double(scene["width"].get<int>()) * scene["height"].get<int>())), cell(scene["timing"]),
                   std::to_string(c.threads), c.cpu});
}

json run_json(const ReportScene& sc, const RunResult& r) {
  json j = {{"id", r.id},
            {"filter", r.filter},
            {"kind", r.kind},
            {"parameters", r.parameters},
            {"default", r.is_default},
            {"sweep", r.sweep_param.empty() ? json(nullptr) : json{{"param", r.sweep_param}, {"value", r.sweep_value}}},
            {"seconds", r.ok() ? nonneg(r.seconds) : json(nullptr)},
            {"filter_seconds", nonneg(r.filter_seconds)},
            {"peak_memory_mb", nonneg(r.peak_memory_mb)},
            {"relmse", r.ok() ? num(r.scores.mean.relmse) : json(nullptr)},
            {"psnr", r.ok() ? num(r.scores.mean.psnr) : json(nullptr)},
            {"ssim", r.ok() ? num(r.scores.mean.ssim) : json(nullptr)},
            {"temporal_error", r.ok() ? nonneg(r.scores.temporal_error) : json(nullptr)},
            {"worth_x_samples", nonneg(r.worth_x_samples)},
            {"pareto_relmse", r.pareto_relmse},
            {"pareto_ssim", r.pareto_ssim},
            {"chosen", r.chosen.empty() ? json(nullptr) : json(r.chosen)},
            {"notes", r.notes},
            {"per_frame", r.ok() ? per_frame_json(sc, r.scores) : json(nullptr)},
            {"images", nullptr}};
  if (!r.ok()) j["error"] = r.error;
  return j;
}

// Every setting of one filter in this scene: its defaults, then each sweep value.
void run_filter(Context& c, const LoadedReportScene& s, const std::string& name, std::vector<RunResult>& runs,
                json& skipped) {
  auto probe = make_catalog_filter(name);
  probe->commit();
  std::string why;
  const std::vector<Frame>* frames = frames_for(s, *probe, why);
  if (!frames) {
    skipped.push_back({{"filter", name}, {"why", why}});
    return;
  }
  std::vector<std::pair<std::string, double>> settings = {{"", 0.0}};
  const ParameterSweep& sweep = parameter_sweep(name);
  if (c.o.sweeps && !sweep.param.empty()) {
    const std::string def = param_value_text(probe->params().values().at(sweep.param));
    for (double v : sweep.values)
      if (number_text(v) != def) settings.push_back({sweep.param + "=" + number_text(v), v});
  }
  for (const auto& [set, value] : settings) {
    RunResult r;
    if (c.command_timing) {
      r = run_as_command(s, name, set, probe->info().deep_input, c.timing);
      if (name == "auto") r.kind = "auto";
    } else {
      std::unique_ptr<Filter> swept;
      if (!set.empty()) {
        swept = make_catalog_filter(name);
        swept->set_text(sweep.param, number_text(value));
        swept->commit();
      }
      try {
        r = run_in_process(s, set.empty() ? *probe : *swept, *frames, c.threads);
      } catch (const Error& e) {  // one setting that fails is a row, not the end of the report
        r = RunResult{};
        r.error = e.what();
      }
    }
    r.filter = name;
    r.parameters = set;
    r.is_default = set.empty();
    r.id = set.empty() ? name : safe_name(name + "_" + sweep.param + "_" + number_text(value));
    if (!set.empty()) {
      r.sweep_param = sweep.param;
      r.sweep_value = value;
    }
    ++c.runs;
    if (!r.ok()) ++c.failed;
    char line[256];
    if (r.ok())
      std::snprintf(line, sizeof line, "%-22s %-10s %-26s %9.4f %10.5f %8.3f %7.4f", s.scene.id.c_str(), name.c_str(),
                    set.empty() ? "(defaults)" : set.c_str(), r.seconds, r.scores.mean.relmse, r.scores.mean.psnr,
                    r.scores.mean.ssim);
    else
      std::snprintf(line, sizeof line, "%-22s %-10s %-26s FAILED: %.150s", s.scene.id.c_str(), name.c_str(),
                    set.empty() ? "(defaults)" : set.c_str(), r.error.c_str());
    c.log(line);
    if (!r.is_default) r.outputs.clear();  // only the defaults' pictures are shown
    runs.push_back(std::move(r));
  }
}

// Pictures of the middle frame: the whole frame, crops where the shown runs err most, error maps.
void write_pictures(Context& c, const LoadedReportScene& s, std::vector<RunResult>& runs, json& scene_json,
                    json& runs_json) {
  const std::size_t mid = s.flat.size() / 2;
  const Image& ref = s.references[mid];
  const fs::path img_dir = c.out / "images" / s.scene.id, err_dir = c.out / "errors" / s.scene.id;
  fs::create_directories(img_dir);
  fs::create_directories(err_dir);
  std::vector<Image> maps;
  std::vector<std::size_t> shown;
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (runs[i].ok() && !runs[i].outputs.empty()) {
      shown.push_back(i);
      maps.push_back(relative_error_map(ref, runs[i].outputs[mid]));
    }
  std::vector<const Image*> map_ptrs;
  for (const Image& m : maps) map_ptrs.push_back(&m);
  const std::vector<CropRegion> regions = highest_error_regions(map_ptrs);
  auto rel = [&](const fs::path& p) { return fs::relative(p, c.out).generic_string(); };
  auto pictures = [&](const Image& img, const std::string& stem, json& crops1, json& crops4) {
    write_display_png((img_dir / (stem + ".png")).string(), img);
    for (std::size_t k = 0; k < regions.size(); ++k) {
      const fs::path p1 = img_dir / (stem + "_crop" + std::to_string(k) + "_1x.png");
      const fs::path p4 = img_dir / (stem + "_crop" + std::to_string(k) + "_4x.png");
      write_display_png(p1.string(), img, regions[k].crop, 1);
      write_display_png(p4.string(), img, regions[k].zoom, 4);
      crops1.push_back(rel(p1));
      crops4.push_back(rel(p4));
    }
  };
  json n1 = json::array(), n4 = json::array(), r1 = json::array(), r4 = json::array();
  pictures(s.flat[mid].image(Role::Colour), "noisy", n1, n4);
  pictures(ref, "reference", r1, r4);
  scene_json["images"] = {{"noisy", rel(img_dir / "noisy.png")}, {"reference", rel(img_dir / "reference.png")}};
  json crops = json::array();
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const Roi& a = regions[k].crop;
    const Roi& z = regions[k].zoom;
    crops.push_back({{"x", a.x0}, {"y", a.y0}, {"w", a.width()}, {"h", a.height()},
                     {"zoom", {{"x", z.x0}, {"y", z.y0}, {"w", z.width()}, {"h", z.height()}}},
                     {"noisy_1x", n1[k]}, {"noisy_4x", n4[k]}, {"reference_1x", r1[k]}, {"reference_4x", r4[k]}});
  }
  scene_json["crops"] = crops;
  for (std::size_t m = 0; m < shown.size(); ++m) {
    RunResult& r = runs[shown[m]];
    json c1 = json::array(), c4 = json::array();
    pictures(r.outputs[mid], safe_name(r.id), c1, c4);
    const fs::path err = err_dir / (safe_name(r.id) + ".exr");
    write_error_map(err.string(), maps[m]);
    runs_json[shown[m]]["images"] = {{"full", rel(img_dir / (safe_name(r.id) + ".png"))},
                                     {"error", rel(err)},
                                     {"crops_1x", c1},
                                     {"crops_4x", c4}};
  }
}

void report_scene(Context& c, const ReportScene& scene, int index, int count) {
  c.log("scene " + std::to_string(index) + "/" + std::to_string(count) + ": " + scene.id + " (loading)");
  const LoadedReportScene s = load_report_scene(scene);
  const ReportScene& sc = s.scene;
  json sj = {{"id", sc.id},          {"scene", sc.scene},
             {"input", std::to_string(sc.spp) + "spp"}, {"spp", sc.spp},
             {"kind", sc.kind},      {"split", sc.split},
             {"width", s.flat.front().width}, {"height", s.flat.front().height},
             {"frames", int(sc.frames.size())}, {"reference_spp", sc.reference_spp},
             {"timing", c.command_timing ? "command" : c.peers.empty() ? "in-process" : "mixed"}};
  if (sc.spp <= 0) sj["input"] = "input";

  // The renders of this scene at known spp: the reference points of the plots.
  json levels = json::array();
  std::vector<std::pair<int, double>> level_points;
  for (const ReportLevel& level : sc.levels) {
    std::vector<Image> imgs;
    for (std::size_t i = 0; i < level.paths.size(); ++i)
      imgs.push_back(level.spp == sc.spp ? s.flat[i].image(Role::Colour) : read_frame(level.paths[i]).image(Role::Colour));
    const Scores sco = score_outputs(imgs, s.references, c.threads);
    const bool input = level.spp == sc.spp;
    std::string label = "noisy " + std::to_string(level.spp) + " spp";
    if (input) label += " (input)";
    else if (sc.spp > 0) label += " (" + number_text(std::round(100.0 * level.spp / sc.spp) / 100) + "x)";
    levels.push_back({{"label", label}, {"spp", level.spp}, {"is_input", input}, {"relmse", num(sco.mean.relmse)},
                      {"psnr", num(sco.mean.psnr)}, {"ssim", num(sco.mean.ssim)},
                      {"temporal_error", nonneg(sco.temporal_error)}, {"per_frame", per_frame_json(sc, sco)}});
    level_points.push_back({level.spp, sco.mean.relmse});
  }
  if (sc.levels.empty()) {  // a user render of unknown spp: the input alone
    std::vector<Image> imgs;
    for (const Frame& f : s.flat) imgs.push_back(f.image(Role::Colour));
    const Scores sco = score_outputs(imgs, s.references, c.threads);
    levels.push_back({{"label", "noisy (input)"}, {"spp", nullptr}, {"is_input", true}, {"relmse", num(sco.mean.relmse)},
                      {"psnr", num(sco.mean.psnr)}, {"ssim", num(sco.mean.ssim)},
                      {"temporal_error", nonneg(sco.temporal_error)}, {"per_frame", per_frame_json(sc, sco)}});
  }
  sj["levels"] = levels;

  std::vector<RunResult> runs;
  json skipped = json::array();
  for (const std::string& name : c.filters) run_filter(c, s, name, runs, skipped);
  for (const PeerCommand& p : c.peers) {
    RunResult r = run_peer(s, p, c.timing);
    ++c.runs;
    if (!r.ok()) ++c.failed;
    c.log(sc.id + " peer " + p.name + (r.ok() ? ": " + number_text(r.seconds) + " s, relMSE " + number_text(r.scores.mean.relmse)
                                              : ": FAILED: " + r.error));
    runs.push_back(std::move(r));
  }
  for (RunResult& r : runs)
    if (r.ok()) r.worth_x_samples = worth_x_samples(level_points, sc.spp, r.scores.mean.relmse);
  mark_pareto(runs);
  json runs_json = json::array();
  for (const RunResult& r : runs) runs_json.push_back(run_json(sc, r));
  write_pictures(c, s, runs, sj, runs_json);
  sj["runs"] = runs_json;
  sj["skipped"] = skipped;
  for (const json& l : levels) add_csv(c, sj, l, "level");
  for (const json& r : runs_json) add_csv(c, sj, r, "run");
  c.scenes.push_back(sj);
}

json scaling_section(Context& c, const std::vector<ReportScene>& scenes) {
  std::vector<int> sizes;
  for (int n = c.o.scaling_min; n <= c.o.scaling_max; n *= 2) sizes.push_back(n);
  json rows = json::array(), fits = json::array();
  // One source frame per input kind: the first still (else any flat frame), deep and light field.
  std::map<std::string, Frame> sources;
  std::map<std::string, std::string> source_names;
  for (const ReportScene& sc : scenes) {
    const std::string kind = sc.kind == "sequence" ? "still" : sc.kind;
    if ((kind == "still" || kind.empty()) && !sources.count("flat")) {
      sources["flat"] = read_frame(sc.noisy[sc.noisy.size() / 2]);
      source_names["flat"] = sc.id;
    }
    if (!sc.deep.empty() && !sc.deep[0].empty() && (kind == "deep" || kind == "lightfield" || kind.empty())) {
      Frame f = read_frame(sc.deep[0]);
      const std::string k = f.lightfield ? "lightfield" : f.deep ? "deep" : "";
      if (!k.empty() && !sources.count(k)) {
        sources[k] = std::move(f);
        source_names[k] = sc.id;
      }
    }
  }
  // Time against spp: the first scene of each kind rendered at several spp (flat stills at
  // 1-64, the light field at 4-16; the per-sample scenes have one), each level tiled to one size.
  std::map<std::string, std::vector<std::pair<int, Frame>>> by_spp;
  std::map<std::string, std::string> spp_names;
  for (const ReportScene& sc : scenes) {
    if (sc.levels.size() < 2) continue;
    const bool lf = sc.kind == "lightfield";
    const std::string k = lf ? "lightfield" : sc.kind == "deep" ? "deep" : "flat";
    if (by_spp.count(k)) continue;
    for (const ReportLevel& l : sc.levels) {
      const std::string& path = lf ? (l.deep.empty() ? std::string() : l.deep[0]) : l.paths[l.paths.size() / 2];
      if (path.empty()) continue;
      by_spp[k].push_back({l.spp, read_frame(path)});
    }
    spp_names[k] = sc.scene;
  }
  const int spp_side = std::min(512, std::max(c.o.scaling_min, c.o.scaling_max));
  json spp_rows = json::array();
  json src_json = json::object();
  for (const auto& [k, v] : source_names) src_json[k] = v;
  for (const std::string& name : c.filters) {
    auto f = make_catalog_filter(name);
    f->commit();
    const FilterInfo& info = f->info();
    const std::string kind = !info.deep_input ? "flat" : info.lightfield_input ? "lightfield" : "deep";
    if (!sources.count(kind) || !f->missing_passes(sources[kind]).empty()) continue;
    const std::vector<ScalingRow> rs =
        measure_scaling(*f, sources[kind], kind, sizes, c.threads, c.o.repeat, [&](const std::string& l) { c.log(l); });
    for (const ScalingRow& r : rs) {
      rows.push_back({{"filter", r.filter}, {"input", r.input}, {"width", r.width}, {"height", r.height},
                      {"pixels", double(r.width) * r.height}, {"seconds", r.seconds},
                      {"peak_memory_mb", nonneg(r.peak_memory_mb)}});
      c.csv.push_back({"scaling", source_names[kind], "", "", kind, r.filter, "", "true", number_text(r.seconds), "",
                       r.peak_memory_mb >= 0 ? number_text(r.peak_memory_mb) : "", "", "", "", "", "",
                       std::to_string(r.width), std::to_string(r.height), number_text(double(r.width) * r.height),
                       "in-process", std::to_string(c.threads), c.cpu});
    }
    for (const auto& level : by_spp[kind]) {
      const int spp = level.first;  // a plain variable: clang's C++17 cannot capture a structured binding
      const Frame& frame = level.second;
      if (!f->missing_passes(frame).empty()) continue;
      const ScalingRow r =
          measure_scaling(*f, frame, kind, {spp_side}, c.threads, c.o.repeat, [&](const std::string& l) {
            c.log(l + " (" + std::to_string(spp) + " spp)");
          }).front();
      spp_rows.push_back({{"filter", r.filter}, {"input", kind}, {"scene", spp_names[kind]}, {"spp", spp},
                          {"width", r.width}, {"height", r.height}, {"seconds", r.seconds},
                          {"peak_memory_mb", nonneg(r.peak_memory_mb)}});
    }
    const ScalingFit fit = fit_scaling(rs);
    fits.push_back({{"filter", fit.filter}, {"input", fit.input}, {"slope", fit.slope},
                    {"seconds_per_megapixel", fit.seconds_per_megapixel},
                    {"peak_memory_mb_per_megapixel", nonneg(fit.peak_memory_mb_per_megapixel)}});
  }
  return {{"method",
           "a sample frame mirrored (... c b a | a b c | c b a ...) to each size: every pass, the per-sample and "
           "light-field data alike, so that the work per pixel stays that of the sample; filter time only (in the "
           "process, no I/O), best of the repeats; peak = resident memory the run added"},
          {"sources", src_json}, {"threads", c.threads}, {"sizes", sizes}, {"rows", rows}, {"fits", fits},
          {"spp_method", "each render of one scene per input kind (" + std::to_string(spp_side) + "x" +
                             std::to_string(spp_side) + " by the same tiling), filter time against its spp"},
          {"spp_rows", spp_rows}};
}

// A run stopped by a signal leaves its OUT/.work-PID folder: removed by the next run when that
// process is gone.
void remove_stale_work_dirs(const fs::path& out) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(".work-", 0) != 0) continue;
    const long pid = std::strtol(name.c_str() + 6, nullptr, 10);
    if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove_all(e.path(), ec);
  }
}

std::string csv_line(const std::vector<std::string>& cells) {
  std::string line;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    std::string v = cells[i];
    if (v.find_first_of(",\"\n") != std::string::npos) {
      std::string q = "\"";
      for (char ch : v) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
      v = q + "\"";
    }
    line += (i ? "," : "") + v;
  }
  return line + "\n";
}

}  // namespace

std::string report_scripts_dir(const ReportOptions& options) {
  if (!options.report_dir.empty()) return options.report_dir;
  if (const char* env = std::getenv("MCRECON_REPORT_DIR")) return env;
#ifdef MCRECON_SOURCE_DIR
  return std::string(MCRECON_SOURCE_DIR) + "/report";
#else
  return "report";
#endif
}

ReportSummary run_report(const ReportOptions& o) {
  if (o.timing != "auto" && o.timing != "in-process" && o.timing != "command")
    throw Error(Errc::InvalidArgument, "--timing '" + o.timing + "': use auto, in-process or command");
  if (o.scaling_max != 0 && (o.scaling_min < 16 || o.scaling_max < o.scaling_min || o.scaling_max > 16384))
    throw Error(Errc::InvalidArgument, "--scaling-max " + std::to_string(o.scaling_max) + ": 0 (none) or " +
                                           std::to_string(o.scaling_min) + "..16384");
  for (int n : o.spp)
    if (n < 1) throw Error(Errc::InvalidArgument, "--spp " + std::to_string(n) + ": at least 1");
  if (o.threads < 0) throw Error(Errc::InvalidArgument, "--threads " + std::to_string(o.threads) + ": expected 0 (all cores) or a positive count");
  const int threads = o.threads > 0 ? std::min(o.threads, tbb::info::default_concurrency()) : tbb::info::default_concurrency();
  Context c(o, threads);
  c.filters = o.filters.empty() ? catalog_names() : o.filters;
  for (const std::string& f : c.filters) catalog_info(f);  // an unknown name fails before any work
  for (const std::string& p : o.peers) c.peers.push_back(parse_peer(p));

  std::vector<ReportScene> scenes;
  for (const ReportInput& in : o.inputs) {
    scenes.push_back(user_report_scene(in.name, in.noisy, in.reference, in.frames, in.spp));
    // Every file opens as an image before any work: a bad reference is found now, not after the
    // sample scenes ran.
    for (const auto& [flag, list] : {std::pair{"--input", &scenes.back().noisy}, std::pair{"--reference", &scenes.back().reference}})
      for (const std::string& path : *list) {
        try {
          check_image_file(path);
        } catch (const Error& e) {
          throw Error(e.code(), std::string(flag) + ": " + e.what());
        }
      }
  }
  if (o.with_samples) {
    const std::string dir = o.samples.empty() ? default_samples_dir() : o.samples;
    for (ReportScene& s : sample_report_scenes(dir, o.spp, o.scenes)) scenes.push_back(std::move(s));
  }
  if (scenes.empty()) throw Error(Errc::InvalidArgument, "report: nothing to report on (no --input and no sample scenes)");
  std::map<std::string, int> ids;
  for (ReportScene& s : scenes)
    if (ids[s.id]++) s.id += "_" + std::to_string(ids[s.id]);  // two user renders of one name

  // Nothing a run reads may be overwritten by what it writes.
  std::vector<std::string> inputs;
  for (const ReportScene& s : scenes) {
    inputs.insert(inputs.end(), s.noisy.begin(), s.noisy.end());
    inputs.insert(inputs.end(), s.reference.begin(), s.reference.end());
  }
  fs::create_directories(c.out);
  FolderLock lock(c.out);
  for (const char* f : {"results.json", "results.csv", "report.html"}) check_output_path((c.out / f).string(), inputs);
  for (const std::string& in : inputs)
    for (const char* sub : {"images", "errors", "plots"}) {
      const std::string under = fs::weakly_canonical(c.out / sub).string() + "/";
      if (fs::weakly_canonical(in).string().rfind(under, 0) == 0)
        throw Error(Errc::InvalidArgument, "--out '" + o.out + "': the input '" + in + "' lies in its " + sub +
                                               "/ folder, which the report writes");
    }

  if (o.builtin_peers) {
    const std::string script = report_scripts_dir(o) + "/peers/opencv_nlm.py";
    const CommandRun probe = fs::is_regular_file(script)
                                 ? run_timed_command({o.python, "-c", "import cv2, OpenImageIO"}, "/dev/null", 60)
                                 : CommandRun{0, -1, 1, false};
    if (probe.exit_code == 0 && !probe.timed_out)
      c.peers.push_back(parse_peer("opencv_nlm=" + o.python + " '" + script + "' --input {colour.exr} --output {output.exr}"));
    else
      c.log("peer opencv_nlm left out: " + o.python + " cannot import cv2 (Debian: python3-opencv) or " + script +
            " is missing");
  }
  c.command_timing = o.timing == "command" || (o.timing == "auto" && !c.peers.empty());
  remove_stale_work_dirs(c.out);
  WorkDir work{c.out / (".work-" + std::to_string(::getpid()))};
  fs::create_directories(work.path);
  c.timing = {o.cli, work.path.string(), c.threads, o.command_timeout};
  if (c.command_timing && (o.cli.empty() || !fs::is_regular_file(o.cli)))
    throw Error(Errc::InvalidArgument, "--timing command: the mcrecon CLI was not found ('" + o.cli +
                                           "'); in Python pass cli=PATH");

  const json machine = machine_json(c.threads);
  c.cpu = machine["cpu"].get<std::string>();
  c.log(std::string("timing: ") + (c.command_timing ? "every run as a command (peers present)" : "in the process"));
  for (std::size_t i = 0; i < scenes.size(); ++i) report_scene(c, scenes[i], int(i) + 1, int(scenes.size()));

  json results = {
      {"format", "mcrecon-report-1"},
      {"created", now_utc()},
      {"mcrecon", "mcrecon 0.1.0"},
      {"machine", machine},
      {"timing_note",
       c.command_timing
           ? "command: each run is a process (mcrecon denoise for the filters, the template for peers), timed by "
             "the wall clock from spawn to exit: start-up, reading the input, filtering and writing the output "
             "included; filter_seconds is mcrecon's own filter time (--timings). Peers get the passes exported "
             "before the clock starts."
           : "in-process: the filter's execute() summed over the frames, after the frames were read (no I/O); "
             "one run per setting"},
      {"memory_note",
       c.command_timing ? "peak resident memory of the process (getrusage of the child)"
                        : "resident memory the run added at its peak (Linux VmHWM, reset before the run), the kept "
                          "outputs left out"},
      {"scenes", c.scenes}};
  if (o.scaling_max > 0) results["scaling"] = scaling_section(c, scenes);

  ReportSummary sum;
  sum.results_json = (c.out / "results.json").string();
  sum.results_csv = (c.out / "results.csv").string();
  write_text_atomic(results.dump(1) + "\n", sum.results_json);
  std::string csv = csv_line({"section", "scene", "input", "spp", "kind", "filter", "parameters", "default", "seconds",
                              "filter_seconds", "peak_memory_mb", "relmse", "psnr", "ssim", "temporal_error",
                              "worth_x_samples", "width", "height", "pixels", "timing", "threads", "cpu"});
  for (const auto& row : c.csv) csv += csv_line(row);
  write_text_atomic(csv, sum.results_csv);
  sum.scenes = int(scenes.size());
  sum.runs = c.runs;
  sum.failed_runs = c.failed;
  return sum;
}

std::string render_report_page(const ReportOptions& o) {
  const std::string script = report_scripts_dir(o) + "/render_report.py";
  if (!fs::is_regular_file(script))
    throw Error(Errc::FileNotFound, "the report page script '" + script + "' is missing (set MCRECON_REPORT_DIR)");
  const CommandRun run = run_timed_command({o.python, script, o.out}, "", o.command_timeout);
  if (run.exit_code != 0 || run.timed_out)
    throw Error(Errc::Internal, "'" + o.python + " " + script + " " + o.out + "' failed (exit " +
                                    std::to_string(run.exit_code) + "): the results are in " + o.out +
                                    "/results.json; Debian's python3-matplotlib draws the plots");
  return (fs::path(o.out) / "report.html").string();
}

}  // namespace mcr
