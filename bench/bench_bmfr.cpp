// BMFR (Koskela et al. 2019): run time per stage at 1280x720 and run time against error
// on the sample animation.
//
//   mcrecon_bench_bmfr [--threads N] [--repeat N] [--frames N] [--quality-only] [--speed-only]
//                      [--default-only]   (speed: the default configuration only)
//                      [--try "key=value ..."]... [--only-tries]   (extra bmfr configurations)
//
// Speed: the `anim` frames (1 spp) upscaled bilinearly to 1280x720 (x4; motion vectors scaled too),
// run as a sequence; per-stage and total milliseconds per frame, best of `repeat` passes
// over the sequence (each pass after a reset, first frame of each pass excluded: it has no
// history), wall and process CPU time (all threads; the stage CPU times come from
// BmfrFilter::stage_cpu_ms()): on a shared machine the CPU columns are the steadier ones. Beside it, the time to read the same multi-pass frame from an EXR and write the
// RGBA result (the I/O floor a file pipeline pays anyway). The machine is shared: the load
// average is printed before and after.
// Quality: mean relMSE / SSIM over frames 9-16 (second half) and temporal error over the
// consecutive pairs inside 9-16, for the noisy input, phase I alone, bmfr (block sizes,
// feature sets, TAA off) and the other registered filters on the phase I (accumulated) input
// (what `mcrecon denoise --accumulate` gives them).
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "filters/temporal/bmfr.h"
#include "filters/registry.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "io/sample_manifest.h"
#include "metrics/metrics.h"
#include "pipeline/evaluate.h"
#include "temporal/accumulation.h"
#include "util/error.h"

namespace {

using namespace mcr;
using clk = std::chrono::steady_clock;

double cpu_ms() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

double ms_since(clk::time_point t0) { return std::chrono::duration<double, std::milli>(clk::now() - t0).count(); }

std::string loadavg() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

Image upscale(const Image& in, int f, float value_scale = 1.0f) {
  const int w = in.width() * f, h = in.height() * f, ch = in.channels();
  Image out(w, h, ch);
  for (int y = 0; y < h; ++y) {
    const float sy = std::clamp((float(y) + 0.5f) / float(f) - 0.5f, 0.0f, float(in.height() - 1));
    const int y0 = std::min(int(sy), in.height() - 1), y1 = std::min(y0 + 1, in.height() - 1);
    const float fy = sy - float(y0);
    for (int x = 0; x < w; ++x) {
      const float sx = std::clamp((float(x) + 0.5f) / float(f) - 0.5f, 0.0f, float(in.width() - 1));
      const int x0 = std::min(int(sx), in.width() - 1), x1 = std::min(x0 + 1, in.width() - 1);
      const float fx = sx - float(x0);
      for (int c = 0; c < ch; ++c) {
        const float v = (1 - fy) * ((1 - fx) * in.at(x0, y0, c) + fx * in.at(x1, y0, c)) +
                        fy * ((1 - fx) * in.at(x0, y1, c) + fx * in.at(x1, y1, c));
        out.at(x, y, c) = v * value_scale;
      }
    }
  }
  return out;
}

Frame upscale_frame(const Frame& in, int f) {
  Frame out = in;
  out.width = in.width * f;
  out.height = in.height * f;
  out.extra.clear();
  for (Pass& p : out.passes) p.image = upscale(p.image, f, p.role == Role::Motion ? float(f) : 1.0f);
  return out;
}

struct Row {
  std::string label;
  double relmse = 0, ssim = 0, temporal = 0, ms = 0;
};

void print_row(const Row& r) {
  std::printf("  %-36s %9.5f %8.4f %9.5f %9.2f\n", r.label.c_str(), r.relmse, r.ssim, r.temporal, r.ms);
}

// Frames 9..16 (indices 8..15) of the sequence.
Row judge(const std::string& label, const LoadedScene& scene, const std::vector<Image>& results, double ms) {
  Row r;
  r.label = label;
  r.ms = ms;
  const int n = int(results.size()), first = n / 2;
  for (int i = first; i < n; ++i) {
    const ImageMetrics m = compare_images(scene.references[std::size_t(i)], results[std::size_t(i)], 0);
    r.relmse += m.relmse / (n - first);
    r.ssim += m.ssim / (n - first);
    if (i > first) r.temporal += temporal_error(results[std::size_t(i - 1)], results[std::size_t(i)], 0) / (n - first - 1);
  }
  return r;
}

std::vector<Image> run_filter(Filter& f, const std::vector<Frame>& frames, int threads, double& ms) {
  f.reset();
  ExecOptions eo;
  eo.nthreads = threads;
  std::vector<Image> out;
  const auto t0 = clk::now();
  for (const Frame& fr : frames) out.push_back(f.execute(fr, eo));
  ms = ms_since(t0) / double(frames.size());
  return out;
}

std::vector<std::string> g_tries;  // --try "k=v k=v": extra bmfr configurations
bool g_only_tries = false;
bool g_default_only = false;  // --default-only: the speed table's first configuration only

void quality(int threads) {
  const std::vector<SampleScene> scenes = load_sample_manifest(default_samples_dir());
  const SampleScene* anim = nullptr;
  for (const auto& s : scenes)
    if (s.name == "anim") anim = &s;
  if (!anim) {
    std::printf("quality: no 'anim' scene in the samples\n");
    return;
  }
  for (const auto& [spp, pattern] : anim->noisy) {
    const LoadedScene scene = load_scene(*anim, spp);
    std::printf("\nquality: anim %d spp, %dx%d, frames %d-%d judged (mean relMSE, mean SSIM, temporal error, ms/frame on %d threads)\n",
                spp, scene.frames.front().width, scene.frames.front().height, int(scene.frames.size()) / 2 + 1,
                int(scene.frames.size()), threads);
    std::printf("  %-36s %9s %8s %9s %9s\n", "method", "relMSE", "SSIM", "temporal", "ms");
    std::vector<Image> noisy;
    for (const Frame& f : scene.frames) noisy.push_back(f.image(Role::Colour).channel_range(0, 3));
    print_row(judge("noisy input", scene, noisy, 0));
    // Phase I alone: the input the other filters get with --accumulate.
    TemporalAccumulator acc;
    std::vector<Frame> accumulated = scene.frames;
    std::vector<Image> acc_images;
    const auto t0 = clk::now();
    for (Frame& f : accumulated) {
      Pass c = f.get(Role::Colour);
      const Image a = acc.accumulate(f, c.image.channel_range(0, 3), threads);
      for (std::size_t i = 0; i < a.pixel_count(); ++i)
        for (int k = 0; k < 3; ++k) c.image.data()[i * std::size_t(c.image.channels()) + std::size_t(k)] = a.data()[i * 3 + std::size_t(k)];
      f.put(c);
      acc_images.push_back(a);
    }
    print_row(judge("accumulated (phase I only)", scene, acc_images, ms_since(t0) / double(accumulated.size())));

    struct Config {
      std::string label;
      std::vector<std::pair<std::string, std::string>> params;
    };
    std::vector<Config> configs = {{"bmfr (defaults: auto block, taa)", {}},
                                   {"bmfr block_size=32", {{"block_size", "32"}}},
                                   {"bmfr block_size=16", {{"block_size", "16"}}},
                                   {"bmfr block_size=64", {{"block_size", "64"}}},
                                   {"bmfr features=first_order", {{"features", "first_order"}}},
                                   {"bmfr features=with_albedo", {{"features", "with_albedo"}}},
                                   {"bmfr features=with_depth", {{"features", "with_depth"}}},
                                   {"bmfr taa=false", {{"taa", "false"}}},
                                   {"bmfr offsets=false", {{"offsets", "false"}}},
                                   {"bmfr albedo_demodulation=false", {{"albedo_demodulation", "false"}}}};
    if (g_only_tries) configs.clear();
    for (const std::string& t : g_tries) {
      Config c{"bmfr " + t, {}};
      std::size_t pos = 0;
      while (pos < t.size()) {
        std::size_t end = t.find(' ', pos);
        if (end == std::string::npos) end = t.size();
        const std::string kv = t.substr(pos, end - pos);
        const std::size_t eq = kv.find('=');
        if (eq != std::string::npos) c.params.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
        pos = end + 1;
      }
      configs.push_back(c);
    }
    for (const Config& c : configs) {
      auto f = make_filter("bmfr");
      for (const auto& kv : c.params) f->set_text(kv.first, kv.second);
      f->commit();
      double ms = 0;
      const std::vector<Image> out = run_filter(*f, scene.frames, threads, ms);
      print_row(judge(c.label, scene, out, ms));
    }
    for (const std::string& name : image_filter_names()) {
      if (name == "bmfr" || g_only_tries) continue;
      for (bool demod : {false, true}) {
        try {
          auto f = make_filter(name);
          if (demod) f->set("demodulate", true);
          f->commit();
          double ms = 0;
          const std::vector<Image> out = run_filter(*f, accumulated, threads, ms);
          print_row(judge(name + (demod ? " demodulate" : "") + " on accumulated", scene, out, ms));
        } catch (const Error& e) {
          std::printf("  %-36s skipped: %s\n", name.c_str(), e.what());
        }
      }
    }
  }
}

void write_multipass(const std::string& path, const Frame& f) {
  // Blender-like multilayer channel names so read_frame maps the roles.
  struct G {
    Role role;
    const char* group;
    std::vector<const char*> ch;
  };
  const std::vector<G> groups = {{Role::Colour, "ViewLayer.Combined", {"R", "G", "B", "A"}},
                                 {Role::Albedo, "ViewLayer.Denoising Albedo", {"R", "G", "B"}},
                                 {Role::Normal, "ViewLayer.Normal", {"X", "Y", "Z"}},
                                 {Role::Position, "ViewLayer.Position", {"X", "Y", "Z"}},
                                 {Role::Motion, "ViewLayer.Vector", {"X", "Y", "Z", "W"}}};
  std::vector<std::string> names;
  std::vector<const Image*> srcs;
  std::vector<int> idx;
  for (const G& g : groups) {
    const Image& im = g.role == Role::Normal || g.role == Role::Position ? f.image(g.role, Prefer::Geometry) : f.image(g.role);
    for (int c = 0; c < int(g.ch.size()); ++c) {
      names.push_back(std::string(g.group) + "." + g.ch[std::size_t(c)]);
      srcs.push_back(&im);
      idx.push_back(std::min(c, im.channels() - 1));
    }
  }
  const int nc = int(names.size());
  std::vector<float> px(std::size_t(f.width) * f.height * nc);
  for (std::size_t i = 0; i < std::size_t(f.width) * f.height; ++i)
    for (int c = 0; c < nc; ++c) px[i * nc + c] = srcs[std::size_t(c)]->data()[i * std::size_t(srcs[std::size_t(c)]->channels()) + std::size_t(idx[std::size_t(c)])];
  OIIO::ImageSpec spec(f.width, f.height, nc, OIIO::TypeDesc::FLOAT);
  spec.channelnames = names;
  spec.attribute("compression", "zip");
  auto out = OIIO::ImageOutput::create(path);
  if (!out || !out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, px.data()) || !out->close())
    throw Error(Errc::WriteFailed, "bench: cannot write '" + path + "'");
}

void speed(int threads, int repeat, int nframes) {
  const std::vector<SampleScene> scenes = load_sample_manifest(default_samples_dir());
  const SampleScene* anim = nullptr;
  for (const auto& s : scenes)
    if (s.name == "anim") anim = &s;
  if (!anim) return;
  const LoadedScene scene = load_scene(*anim, 1);
  std::vector<Frame> frames;
  // Integer factor to 1280 pixels wide (x4 for the 320x180 sample), so 720p for 16:9.
  const int factor = std::max(1, 1280 / scene.frames.front().width);
  for (int i = 0; i < nframes && i < int(scene.frames.size()); ++i)
    frames.push_back(upscale_frame(scene.frames[std::size_t(i)], factor));
  std::printf("\nspeed: %dx%d (anim 1 spp upscaled x%d), %zu frames, %d threads, best of %d passes; load before: %s\n",
              frames[0].width, frames[0].height, factor, frames.size(), threads, repeat, loadavg().c_str());
  std::printf("  wall ms per frame (best pass), then process CPU ms (all threads) per stage and per frame\n");
  std::printf("  %-28s %7s %7s %7s %7s %7s %7s | %6s %6s %6s %6s %6s %9s\n", "config", "phaseI", "fit", "phIII",
              "detail", "taa", "total", "cI", "cfit", "cIII", "cdet", "ctaa", "cpu/frame");
  struct Config {
    std::string label;
    std::vector<std::pair<std::string, std::string>> params;
  };
  const std::vector<Config> configs = {{"default (auto = 32 at 720p)", {}},
                                       {"residual_k=0 (no detail)", {{"residual_k", "0"}}},
                                       {"block_size=16", {{"block_size", "16"}}},
                                       {"block_size=64", {{"block_size", "64"}}},
                                       {"features=first_order", {{"features", "first_order"}}},
                                       {"features=with_albedo", {{"features", "with_albedo"}}}};
  ExecOptions eo;
  eo.nthreads = threads;
  for (const Config& c : configs) {
    if (g_default_only && &c != &configs.front()) break;
    auto f = make_filter("bmfr");
    for (const auto& kv : c.params) f->set_text(kv.first, kv.second);
    f->commit();
    auto* b = dynamic_cast<BmfrFilter*>(f.get());
    constexpr int S = BmfrFilter::kStages;  // the stages, then the whole frame
    double best[S + 1], best_cpu = 1e30, best_scpu[S];
    std::fill(best, best + S + 1, 1e30);
    std::fill(best_scpu, best_scpu + S, 1e30);
    for (int r = 0; r < repeat; ++r) {
      f->reset();
      double sum[S + 1] = {}, scpu[S] = {};
      int counted = 0;
      double cpu = 0;
      for (std::size_t i = 0; i < frames.size(); ++i) {
        const double c0 = cpu_ms();
        const auto t0 = clk::now();
        f->execute(frames[i], eo);
        const double total = ms_since(t0);
        if (i == 0) continue;
        cpu += cpu_ms() - c0;
        for (int s = 0; s < S; ++s) sum[s] += b->stage_ms()[std::size_t(s)];
        for (int s = 0; s < S; ++s) scpu[s] += b->stage_cpu_ms()[std::size_t(s)];
        sum[S] += total;
        ++counted;
      }
      for (int s = 0; s <= S; ++s) best[s] = std::min(best[s], sum[s] / std::max(1, counted));
      best_cpu = std::min(best_cpu, cpu / std::max(1, counted));
      for (int s = 0; s < S; ++s) best_scpu[s] = std::min(best_scpu[s], scpu[s] / std::max(1, counted));
    }
    std::printf("  %-28s %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f | %6.2f %6.2f %6.2f %6.2f %6.2f %9.2f\n", c.label.c_str(),
                best[0], best[1], best[2], best[3], best[4], best[5], best_scpu[0], best_scpu[1], best_scpu[2], best_scpu[3],
                best_scpu[4], best_cpu);
  }
  // I/O floor: read the multi-pass frame, write the RGBA result.
  const std::string dir = (std::filesystem::temp_directory_path() / "mcrecon_bench_bmfr").string();
  std::filesystem::create_directories(dir);
  const std::string in = dir + "/frame.exr", out = dir + "/result.exr";
  write_multipass(in, frames.back());
  double best_read = 1e30, best_write = 1e30;
  const Image rgb = frames.back().image(Role::Colour).channel_range(0, 3);
  for (int r = 0; r < repeat; ++r) {
    auto t0 = clk::now();
    const Frame f = read_frame(in);
    best_read = std::min(best_read, ms_since(t0));
    t0 = clk::now();
    write_result(out, rgb, f);
    best_write = std::min(best_write, ms_since(t0));
  }
  std::printf("  I/O of the same frame (EXR zip, %ju bytes in): read %.2f ms, write RGBA result %.2f ms\n",
              std::uintmax_t(std::filesystem::file_size(in)), best_read, best_write);
  std::printf("  load after: %s\n", loadavg().c_str());
  std::filesystem::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 2, repeat = 5, frames = 6;
  bool do_quality = true, do_speed = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() { return i + 1 < argc ? std::atoi(argv[++i]) : 0; };
    if (a == "--threads") threads = next();
    else if (a == "--repeat") repeat = std::max(1, next());
    else if (a == "--frames") frames = std::max(2, next());
    else if (a == "--quality-only") do_speed = false;
    else if (a == "--try" && i + 1 < argc) g_tries.push_back(argv[++i]);
    else if (a == "--only-tries") g_only_tries = true;
    else if (a == "--speed-only") do_quality = false;
    else if (a == "--default-only") g_default_only = true;
    else {
      std::fprintf(stderr, "usage: mcrecon_bench_bmfr [--threads N] [--repeat N] [--frames N] [--quality-only] [--speed-only] [--default-only]\n");
      return 2;
    }
  }
  try {
    if (do_quality) quality(threads);
    if (do_speed) speed(threads, repeat, frames);
  } catch (const mcr::Error& e) {
    std::fprintf(stderr, "mcrecon_bench_bmfr: %s\n", e.what());
    return 1;
  }
  return 0;
}
