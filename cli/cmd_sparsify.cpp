#include <cstdio>
#include <regex>

#include "commands.h"
#include "io/atomic_write.h"
#include "io/exr_output.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "sparse/expanded_grid.h"
#include "util/error.h"
#include "validators.h"

namespace mcr::cli {

namespace {

struct SparsifyArgs {
  std::string input, output, layer, gaze = "0.5,0.5";
  double density = 0.25, fovea = 0.1;
};

int run_sparsify(const SparsifyArgs& a) {
  static const std::regex re(R"(^\s*([0-9.eE+-]+)\s*,\s*([0-9.eE+-]+)\s*$)");
  std::smatch m;
  if (!std::regex_match(a.gaze, m, re)) throw Error(Errc::InvalidArgument, "--gaze expects X,Y in [0,1], got '" + a.gaze + "'");
  ExpandedGridParams p;
  p.gaze_x = std::stod(m[1]);
  p.gaze_y = std::stod(m[2]);
  p.density = a.density;
  p.fovea_radius = a.fovea;
  check_exr_name(a.output);
  check_output_path(a.output, {a.input});
  ReadOptions ro;
  ro.layer = a.layer;
  ro.keep_extra = true;
  const Frame frame = read_frame(a.input, ro);
  const ExpandedGrid grid(frame.width, frame.height, p);
  const auto mask = grid.mask();
  const Frame sparse = sparsify(frame, mask);
  WriteOptions wo;
  wo.keep_passes = true;
  write_result(a.output, sparse.image(Role::Colour), sparse, wo);
  std::size_t n = 0;
  for (auto v : mask) n += v;
  std::fprintf(stderr, "mcrecon: %s: %zu of %zu pixels sampled (%.1f%%), fovea radius %.1f px, expansion k = %.4g\n",
               a.output.c_str(), n, mask.size(), 100.0 * double(n) / double(mask.size()),
               p.fovea_radius * std::hypot(double(frame.width), double(frame.height)), grid.k());
  return 0;
}

}  // namespace

Run add_sparsify(CLI::App& app) {
  auto a = std::make_shared<SparsifyArgs>();
  app.add_option("input", a->input, "full render")->required();
  app.add_option("-o,--output", a->output, "sparse render with a sample_count pass (0 = hole)")->required();
  app.add_option("--density", a->density, "fraction of pixels sampled")->check(number_in(1e-4, 1.0));
  app.add_option("--gaze", a->gaze, "gaze point X,Y as fractions of width and height");
  app.add_option("--fovea-radius", a->fovea, "fully sampled radius, fraction of the diagonal")->check(number_in(0.0, 2.0));
  app.add_option("--layer", a->layer, "view layer");
  return [a] { return run_sparsify(*a); };
}

}  // namespace mcr::cli
