#pragma once
// The features of the edge-avoiding filters (bilateral, atrous) and what they make of
// them: the per-feature parameter block (use_<f>, <f>_sigma) and the guides, planar
// copies (kernels/planes.h) of every feature pass in use with the coefficient
// k_f = 1 / (2 sigma_f^2) of its weight, gathered once per execute for the kernel
// (kernels/cross_bilateral.h).
//
// Features and their on/off convention (the help text of every use_<f>):
//   use_<f> = auto  used when the frame has the pass; when it has not, the weight is
//                   dropped with a note() (colour always exists: auto = on)
//           = on    required: a frame without the pass is an error (Errc::MissingPass)
//           = off   not used
//   <f>_sigma > 0   sigma of that weight, in the pass' units (colour: radiance as
//                   filtered, i.e. after demodulation; normal: unit vectors; position,
//                   depth: scene units; albedo: reflectance)
// Normals are Blender's filtered camera-space Denoising Normal (Prefer::Feature),
// positions world space, depth its first channel.
#include <functional>
#include <string>
#include <vector>

#include "image/pass.h"
#include "kernels/foveation.h"
#include "kernels/planes.h"
#include "util/params.h"

namespace mcr {

enum class Feature { Colour, Normal, Position, Albedo, Depth };
inline constexpr int kFeatureCount = 5;
const char* feature_name(Feature f);  // "colour", "normal", "position", "albedo", "depth"

struct FeatureDefaults {
  double sigma[kFeatureCount] = {2.0, 0.2, 0.2, 0.1, 0.1};
  const char* use[kFeatureCount] = {"auto", "auto", "auto", "auto", "off"};
};

// The per-feature block: use_<f> and <f>_sigma for the five features, in order.
ParamTable feature_params(const FeatureDefaults& defaults = {});
// {"colour_sigma", "normal_sigma", ...}: the names to pass to with_foveation().
std::vector<std::string> feature_sigma_names();

// What the block says about passes (no-op without it): `required` gets the use_<f>=on
// ones, each with its setting in `why` ("use_depth=on"); `off` the use_<f>=off ones.
void feature_needs(const ParamSet& params, std::vector<Role>& required, std::vector<std::string>& why,
                   std::vector<Role>& off);
// "<f>_sigma has no effect with use_<f>=off" (and its _outer twin) for the settings given.
std::vector<std::string> feature_unused(const ParamSet& params);

// The feature guides of one execute(): every enabled feature whose pass exists,
// copied to planes once. k_f(p) = 1/(2 sigma_f(p)^2) with the foveated sigma of
// each pixel, and 0 where p's own value of f is not finite (that pixel then
// ignores feature f as a centre); stored as one constant unless it varies.
struct Guides {
  struct Guide {
    Feature feature = Feature::Normal;
    int channels = 3;
    std::vector<float> c[3];  // non-finite values hold 0
    float k_const = 0.0f;     // k everywhere when the plane k is empty
    std::vector<float> k;
  };
  PlaneBox pb;
  bool colour = false;            // colour weight on
  float colour_a_const = 0.0f;    // sqrt(k) = 1/(sqrt(2) sigma) of the colour weight (unscaled colour) ...
  std::vector<float> colour_a;    // ... per pixel when foveated
  std::vector<Guide> list;        // enabled non-colour features present in the frame, Feature order
  std::vector<float> ok;          // 1 where every guide in list is finite, else 0
  std::vector<std::string> used;  // names of the features in use, colour first
  std::vector<std::string> skipped;  // present but constant or all non-finite (feature_activity.h): not used
};
// Reads use_<f>/<f>_sigma (and the _outer twins when foveated). Features set to
// "auto" whose pass is absent are dropped through note(); "on" ones throw MissingPass.
// A present pass (auto or on) that is constant over pb.box within
// constant_tolerance(sigma) (kernels/feature_activity.h: every weight within 1e-4 of 1)
// or has no finite value there is dropped too, with a note, and listed in `skipped`.
// Fills `g`, reusing the memory it holds from an earlier call.
void gather_guides(const Frame& frame, const ParamSet& params, const Foveation& fov, const std::string& filter,
                   const PlaneBox& pb, const std::function<void(std::string)>& note, int nthreads, Guides& g);

}  // namespace mcr
