#include "pipeline/evaluate.h"

#include <chrono>

#include "io/frame_reader.h"
#include "io/sequence.h"
#include "util/error.h"

namespace mcr {

LoadedScene load_scene(const SampleScene& scene, int spp, const ProgressFn& progress) {
  auto it = scene.noisy.find(spp);
  if (it == scene.noisy.end())
    throw Error(Errc::MissingPass, "sample scene '" + scene.name + "' has no " + std::to_string(spp) + " spp render");
  LoadedScene out;
  out.name = scene.name;
  out.spp = spp;
  const int first = scene.is_sequence() ? scene.first_frame : 0, last = scene.is_sequence() ? scene.last_frame : 0;
  for (int f = first; f <= last; ++f) {
    const std::string noisy = scene.is_sequence() ? sequence_path(it->second, f) : it->second;
    const std::string ref = scene.is_sequence() ? sequence_path(scene.reference, f) : scene.reference;
    out.frames.push_back(read_frame(noisy));
    out.frames.back().frame_number = f;
    out.references.push_back(read_frame(ref).image(Role::Colour));
    if (progress) progress(f - first + 1, last - first + 1);
  }
  return out;
}

Evaluation evaluate(const LoadedScene& scene, Filter* filter, int nthreads, const ProgressFn& progress) {
  Evaluation ev;
  if (filter) filter->reset();
  ExecOptions exec;
  exec.nthreads = nthreads;
  const int n = int(scene.frames.size());
  Image previous;
  double temporal = 0;
  for (int i = 0; i < n; ++i) {
    const Frame& frame = scene.frames[std::size_t(i)];
    Image result;
    if (filter) {
      const auto t0 = std::chrono::steady_clock::now();
      result = filter->execute(frame, exec);
      ev.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    } else {
      result = frame.image(Role::Colour);
    }
    const ImageMetrics m = compare_images(scene.references[std::size_t(i)], result, nthreads);
    ev.metrics.rmse += m.rmse / n;
    ev.metrics.relmse += m.relmse / n;
    ev.metrics.psnr += m.psnr / n;
    ev.metrics.ssim += m.ssim / n;
    if (!previous.empty()) temporal += temporal_error(previous, result, nthreads);
    if (i == n / 2) ev.preview = result;
    if (n > 1) previous = std::move(result);
    if (progress) progress(i + 1, n);
  }
  if (n > 1) ev.temporal_error = temporal / (n - 1);
  return ev;
}

}  // namespace mcr
