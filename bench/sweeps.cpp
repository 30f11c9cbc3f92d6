#include "sweeps.h"

#include <algorithm>
#include <map>
#include <sstream>

namespace mcr::bench {

namespace {

const std::map<std::string, Sweep>& table() {
  static const std::map<std::string, Sweep> t = {
      {"box", {"radius", {1, 2, 3, 4, 6}, {}}},
      {"gaussian", {"sigma", {0.5, 1, 1.5, 2, 3}, {}}},
      {"bilateral",
       {"spatial_sigma",
        {1, 2, 2.5, 3, 4, 5},
        {"colour_weight=noise firefly_k=2",
         "colour_sigma=0.5 normal_sigma=0.5 position_sigma=0.05 albedo_sigma=0.5 firefly_k=1",
         // first-order regression, without and with the albedo prefilter: the best found on
         // the glossy scene (0.00671 and 0.00659)
         "order=1 ridge=0.01 radius=6 colour_sigma=0.35 normal_sigma=0.5 position_sigma=0.08 albedo_sigma=1 firefly_k=1",
         "albedo_prefilter=0.2 order=1 ridge=0.005 radius=5 colour_sigma=0.45 normal_sigma=0.5 position_sigma=0.08 "
         "albedo_sigma=1 firefly_k=1",
         // and the noisy-render setting: a strong ridge, the order-0 result as colour guide
         "order=1 ridge=1 firefly_k=2", "order=1 ridge=1 firefly_k=1 albedo_prefilter=0.2"}}},
      {"atrous",
       {"iterations",
        {1, 2, 3, 4, 5, 6},
        // the second: tight position/colour stops with a 3-tap kernel, the best found on the
        // glossy scene (0.00703 there against 0.00828 for the defaults' best)
        {"colour_weight=noise firefly_k=2",
         "kernel_size=3 colour_sigma=0.7 normal_sigma=0.5 position_sigma=0.08 albedo_sigma=0.5 use_depth=on firefly_k=1",
         "kernel_size=3 colour_sigma=0.7 normal_sigma=0.5 position_sigma=0.08 albedo_sigma=0.5 use_depth=on firefly_k=1 "
         "albedo_prefilter=0.2"}}},
      {"guided", {"radius", {2, 4, 8, 12, 16, 24}, {}}},
      {"pwaf", {"max_radius", {4, 6, 8, 12}, {}}},
      {"bmfr", {"block_size", {16, 32, 64}, {}}},
  };
  return t;
}

}  // namespace

const Sweep& sweep_for(const std::string& filter) {
  static const Sweep none;
  const auto it = table().find(filter);
  return it == table().end() ? none : it->second;
}

std::vector<std::string> split_list(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);)
    if (!item.empty()) out.push_back(item);
  return out;
}

bool wanted(const std::vector<std::string>& list, const std::string& name) {
  return list.empty() || std::find(list.begin(), list.end(), name) != list.end();
}

std::string apply_variant(Filter& filter, const std::string& variant) {
  std::string text;
  std::stringstream vs(variant);
  for (std::string kv; vs >> kv;) {
    const std::size_t eq = kv.find('=');
    filter.set_text(kv.substr(0, eq), eq == std::string::npos ? "" : kv.substr(eq + 1));
    text += (text.empty() ? "" : " ") + kv;
  }
  return text;
}

std::vector<std::string> sweep_variants(const std::string& filter) {
  std::vector<std::string> v = {"", "firefly_k=2", "firefly_k=1"};
  for (const std::string& s : sweep_for(filter).variants) v.push_back(s);
  return v;
}

}  // namespace mcr::bench
