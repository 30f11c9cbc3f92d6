#pragma once
// Temporal history for the plugin: which reconstruction (accumulation stage +
// filter) runs a frame, and whether it keeps the history of the frame before.
//
// The rule: a temporal reconstruction (Reconstruction::temporal(): a temporal
// filter, or accumulation) continues its history on a frame only when the previous
// frame this process filtered in the same stream was the frame number just before
// it. A stream is one settings key (filter, canonical parameter values,
// accumulate, layer, pass overrides) plus one name pattern (the file name with its
// last run of digits replaced by '#'). In every other case (first frame of a
// stream, a gap, a frame read again or backwards, a name with no frame number, or
// a failed frame before) the reconstruction is reset() first. Non-temporal ones
// never carry anything between frames.
//
// No OpenImageIO here: the logic is unit-tested with a fake filter.
#include <functional>
#include <list>
#include <memory>
#include <optional>
#include <string>

#include "pipeline/reconstruction.h"

namespace mcr::plugin {

struct FrameName {
  std::string pattern;  // "dir/anim_1spp_####.exr"
  std::optional<long long> number;  // 5 for "anim_1spp_0005.exr"; none without digits
};

// The last run of digits in the file name (not the directory) is the frame number.
FrameName split_frame_number(const std::string& path);

class StreamHistory {
 public:
  using Factory = std::function<std::unique_ptr<Reconstruction>()>;
  explicit StreamHistory(std::size_t max_streams = 8) : max_streams_(max_streams) {}

  struct Lease {
    Reconstruction* reconstruction = nullptr;  // valid until the next acquire()
    bool continued = false;    // true: history of frame N-1 is kept
  };

  // The reconstruction for `path` in the stream `settings_key`; `make` builds one
  // (committed filter) when the stream is new. Calls reset() unless it continues.
  // Call done() or failed() after running it.
  Lease acquire(const std::string& settings_key, const std::string& path, const Factory& make);
  // The frame ran: the next frame number continues it.
  void done();
  // The frame threw: history is unknown, the next frame starts fresh.
  void failed();

  std::size_t streams() const { return streams_.size(); }

 private:
  struct Stream {
    std::string key;
    std::unique_ptr<Reconstruction> reconstruction;
    std::optional<long long> last;  // frame number of the last frame that ran
  };
  std::list<Stream> streams_;  // most recently used first
  std::size_t max_streams_;
  Stream* current_ = nullptr;
  std::optional<long long> current_number_;
};

}  // namespace mcr::plugin
