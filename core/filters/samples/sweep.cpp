#include "filters/samples/sweep.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>

#include "filters/samples/sweep_kernel.h"
#include "filters/samples/sweep_samples.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

const FilterInfo& SweepFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "sweep";
    i.summary = "Front-to-back sweep over the individual samples (deep EXR): defocus, motion blur, transparency";
    i.reference = "Shirley et al. 2011, Alg. 1, 1B, 2, Appendices A and B, section 3.1";
    i.params = with_preparation_params({
        ParamSpec::Enum("algorithm", "sweep", {"sweep", "splat", "box"},
                        "sweep: Alg. 2 over the scales (front to back); splat: Alg. 1B, a box as wide as each "
                        "sample's diameter (up to width); box: Alg. 1, the 1-pixel box of the samples"),
        ParamSpec::Int("scales", 2, 1, 8,
                       "number of box scales, evenly spaced from 1 pixel to width: 2 = {1, width} (Alg. 2, "
                       "Appendix A), 4 with width 7 = {1, 3, 5, 7} (Appendix B)"),
        // Defaults chosen on the dof and motion per-sample scenes at 16 spp (README), reported on
        // the held-out dof_garden: width 3 (5 and 7 blur more than they denoise at 128 px) and
        // step_back 1 (of 0, 1, 2, 4, 16: the only one below the box on both).
        ParamSpec::Float("width", 3, 1, 31, "the widest box, pixels (the widest blur the sweep adds)"),
        ParamSpec::Bool("blend", true,
                        "a sample whose diameter lies between two scales is shared between them (Appendix A), "
                        "no visible break where an object goes out of focus"),
        ParamSpec::Float("power", 1, 0.25, 4, "each sample weight w becomes w^power; above 1 blurs less (fig. 5: 1.3)"),
        ParamSpec::Float("step_back", 1, 0, 1e6,
                         "k: the result stays within sqrt(k) standard errors of the pixel's own sample mean "
                         "(per channel, from its samples' spread): a clean pixel keeps its samples, a noisy one "
                         "the reconstruction; 0: off"),
        ParamSpec::Enum("diameter", "auto", {"auto", "blur", "coc", "motion", "coc_motion"},
                        "denoising diameter per sample: the blur channel, the circle of confusion, the motion "
                        "length, or the larger of the last two; auto: blur when present, else the circle of "
                        "confusion (when the camera is known) and the motion (when mx, my are present)"),
        ParamSpec::Enum("layered", "auto", {"auto", "on", "off"},
                        "depth-of-field layers instead of sorting (the same result, faster): needs the circle "
                        "of confusion as the only diameter and blend off; auto: whenever that holds"),
        ParamSpec::Float("lens_mm", 0, 0, 1e5, "focal length, mm (0: the file's mcrecon:lens_mm)"),
        ParamSpec::Float("fstop", 0, 0, 1e5, "f-number (0: the file's mcrecon:fstop)"),
        ParamSpec::Float("focus_distance", 0, 0, 1e9, "focus distance, scene units like Z (0: the file's mcrecon:focus_distance)"),
        ParamSpec::Float("sensor_width_mm", 0, 0, 1e5, "sensor width, mm (0: the file's mcrecon:sensor_width_mm)"),
    }, PrepSteps::none());
    i.steps = PrepSteps::none();  // the flat-image steps mean nothing per sample
    i.required = {Role::Colour};
    i.deep_input = true;
    i.nonfinite_policy =
        "per sample: non-finite colour or coverage (A) <= 0 drops the sample; depth 0, negative, NaN, inf or "
        ">= 1e9 is the background (sorted last); a non-finite diameter is 1, a non-finite position the pixel "
        "centre; a pixel no sample reaches gives 0";
    return i;
  }();
  return info;
}

namespace {

sweep::Diameter resolve(const std::string& mode, const DeepSamples& deep, const sweep::Camera& cam) {
  if (mode == "blur") return sweep::Diameter::Blur;
  if (mode == "coc") return sweep::Diameter::Coc;
  if (mode == "motion") return sweep::Diameter::Motion;
  if (mode == "coc_motion") return sweep::Diameter::CocMotion;
  const bool motion = deep.channel("mx") >= 0 && deep.channel("my") >= 0;
  if (deep.channel("blur") >= 0) return sweep::Diameter::Blur;
  if (cam.known()) return motion ? sweep::Diameter::CocMotion : sweep::Diameter::Coc;
  if (motion) return sweep::Diameter::Motion;
  return sweep::Diameter::Blur;  // gather() then names what is missing
}

}  // namespace

void SweepFilter::check_params() {
  if (params_.get_enum("layered") == "on" && params_.get_bool("blend"))
    throw Error(Errc::BadParameterValue, "filter 'sweep': layered=on needs blend=off (a blended sample belongs to two "
                                         "layers, whose order then matters)");
  if (params_.get_enum("layered") == "on" && params_.get_enum("algorithm") != "sweep")
    throw Error(Errc::BadParameterValue, "filter 'sweep': layered=on is a path of algorithm=sweep, not of algorithm=" +
                                             params_.get_enum("algorithm"));
}

std::vector<std::string> SweepFilter::own_unused() const {
  std::vector<std::string> u;
  const std::string alg = params_.get_enum("algorithm");
  unused_when(alg != "sweep", "scales", "with algorithm=" + alg, u);
  unused_when(alg != "sweep", "blend", "with algorithm=" + alg, u);
  unused_when(alg != "sweep", "power", "with algorithm=" + alg, u);
  unused_when(alg == "box", "width", "with algorithm=box", u);
  unused_when(alg == "box", "diameter", "with algorithm=box", u);
  return u;
}

void SweepFilter::run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) {
  (void)colour;
  if (!frame.deep)
    throw Error(Errc::MissingPass, "filter 'sweep' needs per-sample (deep EXR) input; '" + frame.path +
                                       "' is a flat image (README: the deep EXR convention)");
  const DeepSamples& deep = *frame.deep;
  if (deep.width != frame.width || deep.height != frame.height)
    throw Error(Errc::SizeMismatch, "'" + frame.path + "': the deep buffer is not the frame's size");
  sweep::Camera cam{params_.get_float("lens_mm"), params_.get_float("fstop"), params_.get_float("focus_distance"),
                    params_.get_float("sensor_width_mm")};
  cam.fill_from(deep, frame.path);
  const std::string alg = params_.get_enum("algorithm");
  const sweep::Diameter dsrc = alg == "box" ? sweep::Diameter::One : resolve(params_.get_enum("diameter"), deep, cam);
  const sweep::SampleSet set = sweep::gather(deep, dsrc, cam, frame.path);
  sweep::Options o;
  o.scales = sweep::Scales::even(int(params_.get_int("scales")), float(params_.get_float("width")));
  o.blend = params_.get_bool("blend");
  o.power = float(params_.get_float("power"));
  const std::string lay = params_.get_enum("layered");
  const bool can_layer = dsrc == sweep::Diameter::Coc && !o.blend;
  if (lay == "on" && !can_layer)
    throw Error(Errc::BadParameterValue,
                "filter 'sweep': layered=on needs the circle of confusion as the only diameter (diameter=coc, or "
                "auto with no blur channel and no motion); '" + frame.path + "' gives " +
                (dsrc == sweep::Diameter::Blur ? "the blur channel" : dsrc == sweep::Diameter::Motion ? "motion" :
                 "circle of confusion and motion"));
  layered_ = alg == "sweep" && can_layer && lay != "off";
  const float focus = float(cam.focus_distance);
  const float widest = alg == "box" ? 1.0f : (alg == "splat" ? float(params_.get_float("width")) : o.scales.widest());
  const int R = std::max(0, int(std::ceil(widest * 0.5f - 0.5f)));
  const int w = frame.width, h = frame.height;
  // Layered with odd integer widths: a box holds whole pixels, so each source pixel's samples
  // are summed per layer once, and an output pixel adds up its neighbours' sums.
  bool whole_pixels = layered_;
  for (float s : o.scales.widths) whole_pixels = whole_pixels && s == std::floor(s) && int(s) % 2 == 1;
  const int K = o.scales.size(), L = 2 * K - 1;
  std::vector<sweep::LayerSums::Acc> pixel_sums;
  if (whole_pixels) {
    pixel_sums.resize(std::size_t(w) * std::size_t(h) * std::size_t(L));
    parallel_rows(0, h, nthreads, [&](int y) {
      sweep::LayerSums one(K);
      for (int x = 0; x < w; ++x) {
        const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
        one.clear();
        for (std::uint64_t i = set.offsets[p]; i < set.offsets[p + 1]; ++i) {
          const sweep::StoredSample& st = set.samples[std::size_t(i)];
          sweep::Sample s;
          s.z = st.z;
          s.d = st.d;
          s.q = st.q;
          std::copy(st.rgb, st.rgb + 3, s.rgb);
          one.add(s, sweep::layer_of(s.z, s.d, o, focus), 0, o.power);
        }
        for (int l = 0; l < L; ++l) pixel_sums[p * std::size_t(L) + std::size_t(l)] = one.acc[std::size_t(l * K)];
      }
    });
  }
  // The narrowest box holding a neighbour pixel at offset (ox, oy): box j spans (w_j - 1)/2.
  auto narrowest = [&](int ox, int oy) {
    const int r = std::max(std::abs(ox), std::abs(oy));
    int m = 0;
    while (m < K - 1 && (int(o.scales.widths[std::size_t(m)]) - 1) / 2 < r) ++m;
    return m;
  };
  std::atomic<std::size_t> sorted{0}, stepped{0};
  const double step_k = params_.get_float("step_back");
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    std::vector<sweep::Sample> local;
    sweep::LayerSums sums(K);
    std::size_t sorted_row = 0, stepped_row = 0;
    for (int x = roi.x0; x < roi.x1; ++x) {
      if (whole_pixels) {
        sums.clear();
        for (int yy = std::max(0, y - R); yy <= std::min(h - 1, y + R); ++yy)
          for (int xx = std::max(0, x - R); xx <= std::min(w - 1, x + R); ++xx) {
            const int m = narrowest(xx - x, yy - y);
            const std::size_t p = std::size_t(yy) * std::size_t(w) + std::size_t(xx);
            for (int l = 0; l < L; ++l) {
              const sweep::LayerSums::Acc& a = pixel_sums[p * std::size_t(L) + std::size_t(l)];
              sweep::LayerSums::Acc& t = sums.acc[std::size_t(l * K + m)];
              t.q += a.q;
              t.qp += a.qp;
              for (int c = 0; c < 3; ++c) t.c[c] += a.c[c];
            }
          }
        float* o3 = out.pixel(x, y);
        sweep::combine_layers(sums, o, o3);
        if (step_k > 0) stepped_row += sweep::clamp_to_pixel(set, x, y, step_k, o3);
        continue;
      }
      local.clear();
      const float cx = float(x) + 0.5f, cy = float(y) + 0.5f;
      for (int yy = std::max(0, y - R); yy <= std::min(h - 1, y + R); ++yy)
        for (int xx = std::max(0, x - R); xx <= std::min(w - 1, x + R); ++xx) {
          const std::size_t p = std::size_t(yy) * std::size_t(w) + std::size_t(xx);
          for (std::uint64_t i = set.offsets[p]; i < set.offsets[p + 1]; ++i) {
            const sweep::StoredSample& st = set.samples[std::size_t(i)];
            sweep::Sample s;
            s.dx = st.x - cx;
            s.dy = st.y - cy;
            s.z = st.z;
            s.d = st.d;
            s.q = st.q;
            s.rgb[0] = st.rgb[0];
            s.rgb[1] = st.rgb[1];
            s.rgb[2] = st.rgb[2];
            local.push_back(s);
          }
        }
      float* o3 = out.pixel(x, y);
      const int n = int(local.size());
      if (alg == "box") {
        sweep::splat(local.data(), n, false, 1.0f, o3);
      } else if (alg == "splat") {
        sweep::splat(local.data(), n, true, widest, o3);
      } else if (layered_) {
        sweep::layered(local.data(), n, o, focus, o3);
      } else {
        bool did_sort = false;
        sweep::sweep(local.data(), n, o, o3, &did_sort);
        sorted_row += did_sort;
      }
      if (step_k > 0 && alg != "box") stepped_row += sweep::clamp_to_pixel(set, x, y, step_k, o3);
    }
    sorted += sorted_row;
    stepped += stepped_row;
  });
  sorted_ = sorted.load();
  const std::size_t pixels = std::size_t(roi.width()) * std::size_t(roi.height());
  if (alg == "sweep")
    note(layered_ ? "sweep: depth-of-field layers (no sort)"
                  : "sweep: " + std::to_string(sorted_) + " of " + std::to_string(pixels) +
                        " pixels sorted (the rest had one scale: nothing to reconstruct)");
  if (step_k > 0 && alg != "box")
    note("sweep: step_back kept " + std::to_string(stepped.load()) + " of " + std::to_string(pixels) +
         " pixels near their own samples' mean");
  if (set.dropped) note("sweep: " + std::to_string(set.dropped) + " samples with non-finite colour or coverage <= 0 left out");
}

}  // namespace mcr
