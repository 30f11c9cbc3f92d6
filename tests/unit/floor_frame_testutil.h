#pragma once
// A flat floor seen by a static camera (every pixel its own history), for the temporal
// filter tests (bmfr's highlights, its detail stage): colour and albedo as given, world
// positions on a grid, the normal facing up, no motion; with `colour_passes`, Diffuse Color =
// `diffuse` and Glossy Color 1 (mirror-like where diffuse is 0).
#include "pass_testutil.h"

namespace mcr::testutil {

inline Frame floor_frame(const Image& colour, const Image& albedo, bool colour_passes = false, float diffuse = 1.0f) {
  const int w = colour.width(), h = colour.height();
  Image pos(w, h, 3), nrm(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      pos.at(x, y, 0) = 0.02f * float(x);
      pos.at(x, y, 1) = 0.02f * float(y);
      pos.at(x, y, 2) = 1.0f;
      nrm.at(x, y, 2) = 1.0f;
    }
  Frame f;
  f.width = w;
  f.height = h;
  f.path = "synthetic.exr";
  f.passes.push_back(make_pass(Role::Colour, "Combined", colour));
  f.passes.push_back(make_pass(Role::Position, "Position", pos, Space::World));
  f.passes.push_back(make_pass(Role::Normal, "Normal", nrm, Space::World));
  f.passes.push_back(make_pass(Role::Albedo, "Denoising Albedo", albedo));
  f.passes.push_back(make_pass(Role::Motion, "Vector", Image(w, h, 4)));
  if (colour_passes) {
    f.passes.push_back(make_pass(Role::DiffuseColour, "DiffCol", Image(w, h, 3, diffuse)));
    f.passes.push_back(make_pass(Role::GlossyColour, "GlossCol", Image(w, h, 3, 1.0f)));
  }
  return f;
}

}  // namespace mcr::testutil
