#include <algorithm>
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "io/frame_reader.h"
#include "io/sequence.h"
#include "json_views.h"
#include "metrics/metrics.h"
#include "progress.h"
#include "util/error.h"
#include "validators.h"

namespace mcr::cli {

namespace {

struct CompareArgs {
  std::string reference, image, layer, ref_layer, frames;
  bool json = false;
  int threads = 0;
};

Frame frame_of(const std::string& path, const std::string& layer) {
  ReadOptions ro;
  ro.layer = layer;
  return read_frame(path, ro);
}

Image colour_of(const std::string& path, const std::string& layer) { return frame_of(path, layer).image(Role::Colour); }

nlohmann::json metrics_json(const ImageMetrics& m) {
  return {{"rmse", number(m.rmse)}, {"relmse", number(m.relmse)}, {"psnr", number(m.psnr)}, {"ssim", number(m.ssim)}};
}

void print_metrics(const ImageMetrics& m) {
  std::printf("rmse   %.8g\nrelmse %.8g\npsnr   %.8g\nssim   %.8g\n", m.rmse, m.relmse, m.psnr, m.ssim);
}

int run_compare(const CompareArgs& a) {
  const bool seq = is_sequence_pattern(a.image) || is_sequence_pattern(a.reference);
  if (!seq) {
    if (!a.frames.empty()) throw Error(Errc::InvalidArgument, "--frames needs sequence patterns (#### or %04d)");
    const Frame ref = frame_of(a.reference, a.ref_layer);
    const Frame img = frame_of(a.image, a.layer);
    const ImageMetrics m = compare_images(ref.image(Role::Colour), img.image(Role::Colour), a.threads);
    // The alpha's error where both have one and either is transparent somewhere (alpha=filter
    // filters it too); an opaque pair says nothing new.
    const Pass *ra = ref.find(Role::Alpha), *ia = img.find(Role::Alpha);
    auto opaque = [](const Pass* p) {
      return std::all_of(p->image.storage().begin(), p->image.storage().end(), [](float v) { return v == 1.0f; });
    };
    if (ra && ia && opaque(ra) && opaque(ia)) ra = ia = nullptr;
    if (a.json) {
      nlohmann::json j = metrics_json(m);
      if (ra && ia) j["alpha_mse"] = number(alpha_mse(ra->image, ia->image));
      std::cout << j.dump(2) << "\n";
    } else {
      print_metrics(m);
      if (ra && ia) std::printf("alpha_mse %.8g\n", alpha_mse(ra->image, ia->image));
    }
    return 0;
  }
  if (a.frames.empty()) throw Error(Errc::InvalidArgument, "comparing sequences needs --frames A-B");
  const FrameList r = parse_frame_list(a.frames);
  const int n = int(r.size());
  ImageMetrics mean{0, 0, 0, 0};
  double temporal = 0, temporal_ref = 0;
  nlohmann::json per_frame = nlohmann::json::array();
  Image prev, prev_ref;
  Progress progress("compare", n);
  for (int i = 0; i < n; ++i) {
    const int f = r.frames()[std::size_t(i)];
    const Image ref = colour_of(sequence_path(a.reference, f), a.ref_layer);
    const Image img = colour_of(sequence_path(a.image, f), a.layer);
    const ImageMetrics m = compare_images(ref, img, a.threads);
    mean.rmse += m.rmse / n;
    mean.relmse += m.relmse / n;
    mean.psnr += m.psnr / n;
    mean.ssim += m.ssim / n;
    nlohmann::json j = metrics_json(m);
    j["frame"] = f;
    if (!prev.empty()) {
      j["temporal_error"] = temporal_error(prev, img, a.threads);
      temporal += j["temporal_error"].get<double>();
      temporal_ref += temporal_error(prev_ref, ref, a.threads);
    }
    per_frame.push_back(j);
    prev = img;
    prev_ref = ref;
    progress.step(i + 1, "frame " + std::to_string(f));
  }
  progress.finish();
  const int pairs = std::max(1, n - 1);
  nlohmann::json out = metrics_json(mean);
  out["temporal_error"] = temporal / pairs;
  out["reference_temporal_error"] = temporal_ref / pairs;  // motion alone, for scale
  out["frames"] = per_frame;
  if (a.json) {
    std::cout << out.dump(2) << "\n";
  } else {
    print_metrics(mean);
    std::printf("temporal_error %.8g (reference %.8g)\n", temporal / pairs, temporal_ref / pairs);
  }
  return 0;
}

}  // namespace

Run add_compare(CLI::App& app) {
  auto a = std::make_shared<CompareArgs>();
  app.add_option("reference", a->reference, "reference render (or sequence pattern)")->required();
  app.add_option("image", a->image, "image to judge (or sequence pattern)")->required();
  app.add_option("--layer", a->layer, "view layer of the image");
  app.add_option("--reference-layer", a->ref_layer, "view layer of the reference");
  app.add_option("--frames", a->frames, "frame range A-B for sequences (adds temporal error)");
  add_threads_option(app, a->threads);
  app.add_flag("--json", a->json, "JSON with keys rmse, relmse, psnr, ssim (and alpha_mse for two stills with alpha, either below 1 somewhere)");
  return [a] { return run_compare(*a); };
}

}  // namespace mcr::cli
