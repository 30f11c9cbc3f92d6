#include "io/deep_writer.h"

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imagebuf.h>

#include <cstdlib>

#include "io/atomic_write.h"
#include "util/error.h"

namespace mcr {

using namespace OIIO;

void write_deep_samples(const DeepSamples& d, const std::string& path) {
  const std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  if (ext != ".exr" && ext != ".EXR")
    throw Error(Errc::InvalidArgument, "deep output '" + path + "': per-sample data is written as OpenEXR (.exr)");
  const std::size_t np = std::size_t(d.width) * std::size_t(d.height), nc = d.channel_names.size();
  if (d.width <= 0 || d.height <= 0 || nc == 0 || d.offsets.size() != np + 1 || d.values.size() != nc)
    throw Error(Errc::InvalidArgument, "deep output '" + path + "': the sample buffer's sizes do not agree");
  for (const auto& v : d.values)
    if (v.size() != d.total_samples())
      throw Error(Errc::InvalidArgument, "deep output '" + path + "': a channel holds another number of samples");
  ImageSpec spec(d.width, d.height, int(nc), TypeFloat);
  spec.channelnames.assign(d.channel_names.begin(), d.channel_names.end());
  spec.deep = true;
  spec.z_channel = d.channel("Z");
  spec.alpha_channel = d.channel("A");
  spec.attribute("compression", "zips");
  for (const auto& [name, text] : d.attributes) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (!text.empty() && end && *end == '\0') spec.attribute(name, float(v));
    else spec.attribute(name, text);
  }
  ImageBuf buf(spec);
  DeepData& dd = *buf.deepdata();
  std::vector<unsigned int> counts(np);
  for (std::size_t p = 0; p < np; ++p) counts[p] = unsigned(d.offsets[p + 1] - d.offsets[p]);
  dd.set_all_samples(counts);
  for (std::size_t p = 0; p < np; ++p)
    for (unsigned s = 0; s < counts[p]; ++s)
      for (std::size_t c = 0; c < nc; ++c) dd.set_deep_value(int64_t(p), int(c), int(s), d.values[c][d.offsets[p] + s]);
  write_atomic(buf, path, "openexr");
}

}  // namespace mcr
