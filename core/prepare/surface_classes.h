#pragma once
// What a pixel's passes say about how far its demodulation and its history can be
// trusted (issue 15: bmfr 6x worse than its input on metal under a sun).
//
//   light_in_albedo: an albedo channel above 1. A reflectance is at most 1: the pass
//     holds light (Blender's Denoising Albedo follows a mirror's bounce; where that
//     sample hit the sun it reads ~200, the next sample 0.4).
//   mirror: the Glossy Color pass exceeds kMirrorRatio x the Diffuse Color pass and
//     kMirrorGloss (a metal: all its light comes by reflection). Its Denoising Albedo is
//     the albedo of whatever it reflects, sample by sample, so colour / albedo swings; and
//     what it shows does not move with its surface, so a history reprojected with the
//     surface trails (the sun's reflection slides over a sphere as the camera moves).
//     Needs both colour passes (Blender: Diffuse Color, Glossy Color); without them no
//     pixel is called a mirror and the notes say so.
//   background: the normal pass is exactly 0 (Blender's world behind everything: normal and
//     position 0, depth 1e10). Blender writes no motion there (Vector 0), so under a moving
//     camera an environment's bright spot (an HDRI's sun) would stay in the history of the
//     pixel it left (held-out `orbit`: 6.4 where the frame shows 0.29).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "image/pass.h"

namespace mcr {

constexpr float kMirrorRatio = 10.0f;
constexpr float kMirrorGloss = 0.02f;

struct SurfaceClasses {
  enum : std::uint8_t { kLightInAlbedo = 1, kMirror = 2, kBackground = 4 };
  std::vector<std::uint8_t> flags;  // per pixel, 0 = none
  std::size_t light_in_albedo = 0, mirror = 0, background = 0;
  bool colour_passes = false;  // Diffuse and Glossy Color present: mirrors detectable
  // A pixel whose albedo holds light or a mirror (bmfr keeps them out of its fit).
  bool any() const { return light_in_albedo + mirror > 0; }
  static constexpr std::uint8_t kOutOfFit = kLightInAlbedo | kMirror;
};

// Flags of every pixel of `frame` (a non-finite value never sets a flag).
void classify_surfaces(const Frame& frame, int nthreads, SurfaceClasses& out);

// out[i] = value where flags[i] & mask, else 0 (a per-pixel weight floor for one class).
void class_values(const SurfaceClasses& classes, std::uint8_t mask, float value, std::vector<float>& out);

}  // namespace mcr
