// A sequence through the file pipeline, before against now (issue 19, point 4): frames
// per second of `mcrecon denoise` over a 1280x720, 28-channel, half-float zip EXR sequence
// (the `anim` sample's frames resized, with noise added so the files compress like renders:
// ~37 MB each), read -> filter -> write one after the other with every EXR through OpenImageIO
// (zlib inside OpenEXR 3.1: the path before), then through the scanline I/O (libdeflate), then
// with the next frame's read and the last frame's write overlapping the filter
// (DenoiseSession::run_sequence).
//
//   mcrecon_bench_sequence [--frames N] [--repeat N] [--filter NAME] [--keep DIR]
//
// --keep DIR keeps the frames (in_0001.exr ...) and uses any already there: a sequence made
// elsewhere (e.g. with oiiotool, with other channel types) can be measured the same way.
//
// Then the output compressions' cost: one filtered frame written with each (best of `repeat`),
// milliseconds and megabytes, so `--compression` can be chosen knowing what it costs.
//
// The paths run in one process, alternating, best of `repeat`; the machine may be shared, so
// the load average is printed before and after.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "io/exr_scanline_io.h"
#include "io/sample_manifest.h"
#include "io/sequence.h"
#include "pipeline/denoise_session.h"

namespace fs = std::filesystem;
using namespace mcr;

namespace {

std::string load_average() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

// The anim sample's frame k resized to 1280x720 with noise, written as the renderer would.
void make_frame(const std::string& src, const std::string& dst, int seed) {
  OIIO::ImageBuf in(src);
  OIIO::ImageSpec spec = in.spec();
  OIIO::ImageBuf big = OIIO::ImageBufAlgo::resize(in, "triangle", 0, OIIO::ROI(0, 1280, 0, 720, 0, 1, 0, spec.nchannels));
  OIIO::ImageBufAlgo::noise(big, "gaussian", 0.0f, 0.05f, false, seed);
  big.set_write_format(OIIO::TypeHalf);
  big.specmod().attribute("compression", "zip");
  if (!big.write(dst)) {
    std::fprintf(stderr, "cannot write %s: %s\n", dst.c_str(), big.geterror().c_str());
    std::exit(1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 8, repeat = 2;
  std::string filter = "bmfr", keep;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--frames")) frames = std::max(2, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--repeat")) repeat = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--filter")) filter = argv[i + 1];
    else if (!std::strcmp(argv[i], "--keep")) keep = argv[i + 1];
  }
  const fs::path dir = keep.empty() ? fs::temp_directory_path() / ("mcrecon_bench_sequence_" + std::to_string(getpid())) : fs::path(keep);
  fs::create_directories(dir / "out");
  const std::string anim = default_samples_dir() + "/anim/anim_1spp_####.exr";
  const std::string input = (dir / "in_####.exr").string(), output = (dir / "out" / "o_####.exr").string();
  std::fprintf(stderr, "making %d frames of 1280x720 in %s\n", frames, dir.c_str());
  for (int f = 1; f <= frames; ++f)
    if (!fs::exists(sequence_path(input, f))) make_frame(sequence_path(anim, (f - 1) % 16 + 1), sequence_path(input, f), f);
  std::printf("sequence: %d frames 1280x720, 28 channels, zip, %.1f MB per frame; filter %s; load before: %s\n",
              frames, double(fs::file_size(sequence_path(input, 1))) / 1e6, filter.c_str(), load_average().c_str());
  std::vector<DenoiseSession::Job> jobs;
  for (int f = 1; f <= frames; ++f) jobs.push_back({sequence_path(input, f), sequence_path(output, f), ReadOptions{}});
  // Three ways, alternating within each repeat: the serial path with every EXR through
  // OpenImageIO (the product before issue 19's point 4), the serial path with the scanline I/O
  // (io/exr_scanline_io.h), and the pipelined path with it (`mcrecon denoise` pipelines with 4
  // threads or more, else runs serially).
  struct Way {
    const char* label;
    bool scanline_io, piped;
  };
  const Way ways[3] = {{"serial, OpenImageIO I/O (before)", false, false},
                       {"serial, scanline I/O", true, false},
                       {"pipelined, scanline I/O", true, true}};
  double best[3] = {1e30, 1e30, 1e30};
  StageTimes stages[3];
  for (int r = 0; r < repeat; ++r)
    for (int w = 0; w < 3; ++w) {
      set_exr_scanline_io(ways[w].scanline_io);
      DenoiseSession session(filter, {});
      StageTimes sum;
      const auto t0 = std::chrono::steady_clock::now();
      session.run_sequence(jobs, WriteOptions{}, ExecOptions{}, ways[w].piped, [&](std::size_t, const StageTimes& t) {
        sum.read_ms += t.read_ms / frames;
        sum.filter_ms += t.filter_ms / frames;
        sum.write_ms += t.write_ms / frames;
      });
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (s < best[w]) best[w] = s, stages[w] = sum;
    }
  set_exr_scanline_io(true);
  for (int w = 0; w < 3; ++w)
    std::printf("%-34s %6.2f frames/s (%5.0f ms per frame; stages read %.0f, filter %.0f, write %.0f ms)\n",
                ways[w].label, frames / best[w], 1000 * best[w] / frames, stages[w].read_ms, stages[w].filter_ms,
                stages[w].write_ms);
  std::printf("against the serial OpenImageIO I/O: serial scanline I/O %.2fx, pipelined %.2fx frames per second "
              "(pipelining alone %.2fx); load after: %s\n",
              best[0] / best[1], best[0] / best[2], best[1] / best[2], load_average().c_str());
  {
    DenoiseSession session(filter, {});
    const std::string one = (dir / "out" / "compression.exr").string();
    std::printf("output compression (RGBA float, 1280x720, one %s frame; read + filter not counted):\n", filter.c_str());
    for (const char* c : {"zip", "zip:1", "zips", "piz", "rle", "none", "dwaa", "b44"}) {
      WriteOptions w;
      w.compression = c;
      double ms = 1e30;
      for (int r = 0; r < repeat; ++r) ms = std::min(ms, session.run(jobs[0].input, one, ReadOptions{}, w, ExecOptions{}).write_ms);
      std::printf("  %-6s %6.0f ms  %6.1f MB%s\n", c, ms, double(fs::file_size(one)) / 1e6,
                  std::string(c) == "dwaa" || std::string(c) == "b44" ? "  (lossy)" : "");
    }
  }
  if (keep.empty()) fs::remove_all(dir);
  return 0;
}
