// TEMPORARY link stub (branch lf-filt): decode_lightfield / is_lightfield are being written on
// main (core/image/lightfield.cpp). Delete this file when that lands; a duplicate symbol at
// link time says it is time. Only what the light-field filters' wrappers call is here.
#include "image/lightfield.h"
#include "util/error.h"

namespace mcr {

bool is_lightfield(const DeepSamples& deep) { return deep.attributes.count("mcrecon:lightfield") != 0; }

LightField decode_lightfield(const DeepSamples& deep, const std::string& path, std::size_t* nonfinite_values) {
  (void)deep;
  (void)nonfinite_values;
  throw Error(Errc::Internal, "'" + path + "': light-field decoding is not on this branch yet (lf-filt link stub)");
}

}  // namespace mcr
