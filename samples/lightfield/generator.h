#pragma once
// Light-field sample generators (issue #18): scenes that render, per pixel, l x l samples of
// f(x, y) on uniform jittered strata of y (one jitter per pixel, Yan et al. 2015 sec. 5), with
// the pixel's slope bounds and axes, in the convention of core/image/lightfield.h.
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "image/lightfield.h"
#include "vec3.h"

namespace mcr::lfgen {

// One pixel's l*l samples, sample k = i + l*j for stratum (i, j) (i along y1).
struct PixelSamples {
  std::vector<Vec3> value;      // f(x, y), not weighted by the light / lens
  std::vector<double> y1, y2;   // the sample's coordinate
  double smin = 0, smax = 0;    // over the pixel's samples that saw a slope; both 0 when none
  double e1x = 0, e1y = 0, e2x = 0, e2y = 0;
  double depth = 0;             // along the view ray to the receiver
  Vec3 p, n;                    // receiver position and unit normal
  Vec3 w1, w2;                  // world dual axes: a receiver displacement D is D . w_i in x units
  Vec3 mod;                     // soft shadows: the unoccluded light (the value with nothing in the way)
  // Soft shadows and depth of field together (LightField::lens): each sample's lens coordinate
  // and texture, the pixel's lens slope bounds. Empty / 0 for one effect.
  std::vector<double> u1, u2;
  std::vector<Vec3> texture;
  double dmin = 0, dmax = 0;
  void reset(int spp);
  // Widens [smin, smax] by one sample's slope (the first one sets both).
  void add_slope(double s);
  // Widens [dmin, dmax] alike (the lens bounds of a combined scene).
  void add_lens_slope(double s);
  bool has_slope = false, has_lens_slope = false;
};

// Coordinate of stratum i (of l) with jitter j in [0,1) on [-L, L]: -L + (i + j) 2L / l.
inline double stratum(int i, double j, int l, double L) { return -L + (i + j) * 2.0 * L / l; }

class LightFieldGenerator {
 public:
  virtual ~LightFieldGenerator() = default;
  virtual LightFieldEffect effect() const = 0;
  virtual double y_range() const = 0;
  virtual double sigma_y() const = 0;
  virtual int width() const = 0;
  virtual int height() const = 0;
  // Renders pixel (x, y) with l*l samples on the strata grid shifted by jitter (j1, j2).
  virtual void render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const = 0;
  // Extra header attributes ("mcrecon:*", as text) describing the scene (camera, light).
  virtual std::map<std::string, std::string> attributes() const { return {}; }
  // Soft shadows seen through a lens (the appendix's combined effects): render_pixel also fills
  // u1, u2, texture and the lens bounds; the lens coordinate spans [-u_range, u_range]^2 under
  // a Gaussian aperture of standard deviation sigma_u.
  virtual bool has_lens() const { return false; }
  virtual double u_range() const { return 1.0; }
  virtual double sigma_u() const { return 0.5; }

  // Weight of a sample at y in the converged pixel: the Gaussian light / aperture
  // exp(-|y|^2 / (2 sigma_y^2)) for soft shadows and dof, 1 for gi (its values already
  // carry the transfer over the pdf: the plain mean is the pixel).
  double reference_weight(double y1, double y2) const;
  // Sample k's weight in its converged pixel: reference_weight, times the aperture's Gaussian
  // of its lens coordinate with a lens.
  double sample_weight(const PixelSamples& ps, std::size_t k) const;
};

// The registry: scene names ("soft_shadows", "dof", "gi") and their default scenes.
std::vector<std::string> scene_names();
// Throws Error(InvalidArgument) naming `name` and the scene names.
std::unique_ptr<LightFieldGenerator> make_scene(const std::string& name, int width, int height);

// Throws Error(InvalidArgument) unless l (samples per axis) is in 1..64, the file format's range.
void check_samples_per_axis(int l);

// Called with the number of rows finished (from one thread at a time, in no fixed order).
using RowProgress = std::function<void(int rows_done)>;

// A 64-bit mix (splitmix64's finaliser): hashes that stand in for random numbers, the same on
// any thread count.
unsigned long long mix64(unsigned long long x);

// The pixel's jitter for a seed: a hash of (seed, salt, pixel), the same on any thread count.
void pixel_jitter(unsigned long long seed, unsigned salt, std::size_t pixel, double& j1, double& j2);

// Every pixel at l*l samples (l in 1..64), nthreads as util/parallel.h; the result is the same
// for a seed on any thread count. Geometry (P, N) is always filled.
LightField render_lightfield(const LightFieldGenerator& gen, int l, unsigned long long seed, int nthreads = 0,
                             const RowProgress& progress = {});

// The converged image, RGB interleaved, width*height*3: per pixel sum f w(y) / sum w(y) over
// l*l stratified samples (w: reference_weight), the jitter from `seed`.
std::vector<float> render_reference(const LightFieldGenerator& gen, int l, unsigned long long seed,
                                    int nthreads = 0, const RowProgress& progress = {});

}  // namespace mcr::lfgen
