#pragma once
// The FilterInfo fields the three light-field filters (sheared, sheared4d, aaf) share: no
// preparation steps, colour required (the flat estimate), deep light-field input, and what
// they do with non-finite input. Not a filter: part of their tables.
#include "filters/filter.h"

namespace mcr::lf {

void light_field_info(FilterInfo& info);

}  // namespace mcr::lf
