// mcrecon lightfield: render a light-field sample file (issue #18) or its converged reference.
#include <OpenImageIO/imagebuf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "commands.h"
#include "generator.h"
#include "io/atomic_write.h"
#include "io/deep_writer.h"
#include "io/exr_output.h"
#include "io/output_guard.h"
#include "progress.h"
#include "util/error.h"

namespace mcr::cli {

namespace {

struct LightFieldArgs {
  std::string scene, output;
  int spp = 16, reference_spp = 1024, width = 128, height = 128, threads = 0;
  unsigned long long seed = 1;
  bool reference = false;
};

int samples_per_axis(int spp) { return int(std::lround(std::sqrt(double(spp)))); }

int run_lightfield(const LightFieldArgs& a) {
  check_exr_name(a.output);
  check_output_path(a.output, {});
  const auto gen = lfgen::make_scene(a.scene, a.width, a.height);
  const int l = samples_per_axis(a.reference ? a.reference_spp : a.spp);
  const std::string what = "lightfield " + a.scene + (a.reference ? " reference" : "");
  Progress progress(what, a.height);
  // About 20 lines in a log, whatever the height (a terminal shows one updating line).
  const int every = std::max(1, a.height / 20);
  auto on_rows = [&](int done) {
    if (done % every == 0 || done == a.height) progress.step(done, "rows");
  };
  if (a.reference) {
    const std::vector<float> rgb = lfgen::render_reference(*gen, l, a.seed, a.threads, on_rows);
    OIIO::ImageSpec spec(a.width, a.height, 3, OIIO::TypeFloat);
    spec.attribute("compression", "zip");
    spec.attribute("mcrecon:lf_scene", a.scene);
    spec.attribute("mcrecon:lf_reference_spp", l * l);
    OIIO::ImageBuf buf(spec);
    buf.set_pixels(OIIO::ROI(0, a.width, 0, a.height, 0, 1, 0, 3), OIIO::TypeFloat, rgb.data());
    write_atomic(buf, a.output, "openexr");
  } else {
    const LightField lf = lfgen::render_lightfield(*gen, l, a.seed, a.threads, on_rows);
    DeepSamples deep = encode_lightfield(lf);
    for (const auto& [name, text] : gen->attributes()) deep.attributes[name] = text;
    deep.attributes["mcrecon:lf_scene"] = a.scene;
    deep.attributes["mcrecon:lf_seed"] = std::to_string(a.seed);
    write_deep_samples(deep, a.output);
  }
  progress.finish(a.output + " (" + std::to_string(a.width) + "x" + std::to_string(a.height) + ", " +
                  std::to_string(l * l) + " samples per pixel)");
  return 0;
}

}  // namespace

Run add_lightfield(CLI::App& app) {
  auto a = std::make_shared<LightFieldArgs>();
  std::string names;
  for (const auto& n : lfgen::scene_names()) names += (names.empty() ? "" : "|") + n;
  app.add_option("--scene", a->scene, names)->required();
  CLI::Option* spp = app.add_option("--spp", a->spp, "samples per pixel, l*l on an l x l grid of strata (default 16)")
                         ->check(perfect_square(16));
  app.add_option("-o,--output", a->output, "output .exr: deep light-field samples, or with --reference the flat image")
      ->required();
  // A setting that would do nothing is refused (CLI11 names both options).
  CLI::Option* reference =
      app.add_flag("--reference", a->reference, "write the converged image (flat RGB) instead of the samples")->excludes(spp);
  app.add_option("--reference-spp", a->reference_spp, "samples per pixel of --reference (default 1024 = 32x32)")
      ->check(perfect_square(64))
      ->needs(reference);
  app.add_option("--width", a->width, "image width (default 128)")->check(whole_number(1, 8192));
  app.add_option("--height", a->height, "image height (default 128)")->check(whole_number(1, 8192));
  app.add_option("--seed", a->seed, "seed of the per-pixel jitter (same seed, same file)");
  add_threads_option(app, a->threads);
  return [a] { return run_lightfield(*a); };
}

}  // namespace mcr::cli
