#include "image/deep.h"

namespace mcr {

int DeepSamples::channel(const std::string& name) const {
  for (std::size_t i = 0; i < channel_names.size(); ++i)
    if (channel_names[i] == name) return int(i);
  return -1;
}

}  // namespace mcr
