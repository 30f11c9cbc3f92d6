#pragma once
// One pass of a synthetic frame, for the tests that build frames by hand.
#include <string>
#include <utility>

#include "image/pass.h"

namespace mcr::testutil {

inline Pass make_pass(Role role, const std::string& name, Image im, Space space = Space::None) {
  Pass p;
  p.role = role;
  p.name = name;
  p.space = space;
  p.image = std::move(im);
  return p;
}

}  // namespace mcr::testutil
