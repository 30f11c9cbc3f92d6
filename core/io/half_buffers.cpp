#include "io/half_buffers.h"

#include <algorithm>

#include "util/error.h"

namespace mcr {

Frame combine_halves(Frame first, const Frame& second) {
  if (first.width != second.width || first.height != second.height)
    throw Error(Errc::SizeMismatch, "half buffers of different sizes: '" + first.path + "' is " + std::to_string(first.width) +
                                        "x" + std::to_string(first.height) + ", '" + second.path + "' is " +
                                        std::to_string(second.width) + "x" + std::to_string(second.height));
  const Image& b = second.image(Role::Colour);
  Pass& colour = const_cast<Pass&>(first.get(Role::Colour));
  Image& a = colour.image;
  if (a.channels() < 3 || b.channels() < 3)
    throw Error(Errc::MissingPass, "half buffers need an RGB colour pass: '" + first.path + "', '" + second.path + "'");
  Pass var;
  var.role = Role::Variance;
  var.name = "half buffers";
  var.source = first.path + " + " + second.path;
  var.channels = {"variance.R", "variance.G", "variance.B"};
  var.image = Image(first.width, first.height, 3);
  for (int y = 0; y < first.height; ++y)
    for (int x = 0; x < first.width; ++x) {
      float* p = a.pixel(x, y);
      const float* q = b.pixel(x, y);
      float* v = var.image.pixel(x, y);
      for (int c = 0; c < 3; ++c) {
        const double d = double(p[c]) - double(q[c]);
        v[c] = float(std::min(d * d / 4.0, 3.0e38));  // beyond the float range: the largest float
        p[c] = float(0.5 * double(p[c]) + 0.5 * double(q[c]));
      }
    }
  first.put(std::move(var));
  return first;
}

}  // namespace mcr
