// The scene registry: one line per scene, no name chains elsewhere.
#include <utility>

#include "dof.h"
#include "generator.h"
#include "gi.h"
#include "soft_shadows.h"
#include "soft_shadows_dof.h"
#include "util/error.h"

namespace mcr::lfgen {

namespace {
using Factory = std::unique_ptr<LightFieldGenerator> (*)(int, int);
const std::vector<std::pair<std::string, Factory>>& registry() {
  static const std::vector<std::pair<std::string, Factory>> r = {
      {"soft_shadows", make_soft_shadows},
      {"dof", make_dof},
      {"gi", make_gi},
      {"soft_shadows_dof", make_soft_shadows_dof},
  };
  return r;
}
}  // namespace

std::vector<std::string> scene_names() {
  std::vector<std::string> names;
  for (const auto& [name, f] : registry()) names.push_back(name);
  return names;
}

std::unique_ptr<LightFieldGenerator> make_scene(const std::string& name, int width, int height) {
  if (width < 1 || height < 1)
    throw Error(Errc::InvalidArgument, "light-field scene size " + std::to_string(width) + "x" + std::to_string(height) + ": expected at least 1x1");
  for (const auto& [n, f] : registry())
    if (n == name) return f(width, height);
  std::string names;
  for (const auto& n : scene_names()) names += (names.empty() ? "" : ", ") + n;
  throw Error(Errc::InvalidArgument, "unknown light-field scene '" + name + "'; scenes: " + names);
}

}  // namespace mcr::lfgen
