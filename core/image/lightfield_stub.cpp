// TEMPORARY link stub (branch lf-filt): decode_lightfield / is_lightfield are main's
// (core/image/lightfield.cpp); this branch forked before they landed. Delete this file when
// merging lf-filt into main. The definitions are weak, so main's own ones win at link time if
// the file is forgotten. Only what the light-field filters' wrappers call is here.
#include "image/lightfield.h"
#include "util/error.h"

namespace mcr {

__attribute__((weak)) bool is_lightfield(const DeepSamples& deep) {
  return deep.attributes.count("mcrecon:lightfield") != 0;
}

__attribute__((weak)) LightField decode_lightfield(const DeepSamples& deep, const std::string& path,
                                                   std::size_t* nonfinite_values) {
  (void)deep;
  (void)nonfinite_values;
  throw Error(Errc::Internal, "'" + path + "': light-field decoding is not on this branch yet (lf-filt link stub)");
}

}  // namespace mcr
