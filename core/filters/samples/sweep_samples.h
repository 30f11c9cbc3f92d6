#pragma once
// The sweep's view of a deep buffer: every sample with its position, depth, denoising
// diameter and weight, in pixel order, and the camera that gives a circle of confusion.
#include <cstdint>
#include <string>
#include <vector>

#include "image/deep.h"

namespace mcr::sweep {

// Thin-lens camera (../shared/notes/blender.md, verified against Cycles within ~0.5 px):
// coc_px = (lens_mm/1000 / fstop) * |z - focus| / (z * focus) * (lens_mm / sensor_width_mm) * width_px.
struct Camera {
  double lens_mm = 0, fstop = 0, focus_distance = 0, sensor_width_mm = 0;
  bool known() const { return lens_mm > 0 && fstop > 0 && focus_distance > 0 && sensor_width_mm > 0; }
  // z = +inf gives the limit (the background).
  double coc(double z, int width_px) const;
  // Header attributes mcrecon:lens_mm, ... for the fields still 0; a value that is there but
  // is not a positive number is an error naming the attribute and the file.
  void fill_from(const DeepSamples& deep, const std::string& path);
};

enum class Diameter { One, Blur, Coc, Motion, CocMotion };  // One: 1 for every sample (Alg. 1)

struct StoredSample {
  float x, y;  // absolute position in pixels (pixel index + offset in the pixel)
  float z;     // +inf for the background
  float d;     // denoising diameter, pixels
  float q;     // coverage / finite samples in its pixel
  float rgb[3];
};

struct SampleSet {
  int width = 0, height = 0;
  std::vector<StoredSample> samples;
  std::vector<std::uint64_t> offsets;  // width*height+1
  std::size_t dropped = 0;            // samples with non-finite colour or coverage <= 0
  std::size_t background = 0;         // depth 0, non-finite, negative or >= 1e9
};

// The step back: keeps out[c] within sqrt(k) standard errors of the pixel's own sample mean
// (coverage-weighted), per channel, where the pixel has 2 samples or more. A clean pixel
// (many samples, little spread) keeps its own mean, a noisy one the reconstruction. Returns
// true when a channel was moved.
bool clamp_to_pixel(const SampleSet& set, int x, int y, double k, float out[3]);

// Background depth: 0, inf or >= 1e9 (the convention in the README), NaN and negative too.
bool is_background(float z);

// Throws MissingPass naming the channel and file when R, G, B, Z (or what `d` needs: blur;
// mx, my; a known camera) are absent.
SampleSet gather(const DeepSamples& deep, Diameter d, const Camera& cam, const std::string& path);

}  // namespace mcr::sweep
