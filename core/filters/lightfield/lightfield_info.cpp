#include "filters/lightfield/lightfield_info.h"

namespace mcr::lf {

void light_field_info(FilterInfo& info) {
  info.steps = PrepSteps::none();  // the flat-image steps mean nothing per sample
  info.required = {Role::Colour};
  info.deep_input = true;
  info.lightfield_input = true;
  info.nonfinite_policy =
      "reading refuses non-finite coordinates, slope bounds, axes and modulation (naming the pixel) and replaces a "
      "non-finite sample value by its pixel's finite mean (counted in a note); a pixel whose weights sum to 0 or to "
      "a non-finite number keeps its own weighted samples";
}

}  // namespace mcr::lf
