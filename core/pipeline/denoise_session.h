#pragma once
// The file pipeline shared by the front ends: read passes -> run filter -> write,
// with per-stage timings. One session keeps one filter (and its temporal history)
// across the frames of a sequence.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "filters/filter.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"

namespace mcr {

struct StageTimes {
  double read_ms = 0, filter_ms = 0, write_ms = 0;
  double total_ms() const { return read_ms + filter_ms + write_ms; }
};

class DenoiseSession {
 public:
  // Makes the filter, sets every key=value (from its table) and commits: all
  // parameter errors surface here, before any file is touched.
  DenoiseSession(const std::string& filter, const std::vector<std::pair<std::string, std::string>>& params);

  Filter& filter() { return *filter_; }

  // Reads input, filters, and writes output unless output is empty (warm-up of
  // temporal history on frames that already have an output).
  StageTimes run(const std::string& input, const std::string& output, const ReadOptions& read,
                 const WriteOptions& write, const ExecOptions& exec);

 private:
  std::unique_ptr<Filter> filter_;
};

// The filter made, every key=value set (from its table) and committed: what a
// session starts with. For front ends that keep filters themselves (the OIIO plugin).
std::unique_ptr<Filter> make_committed_filter(const std::string& filter,
                                              const std::vector<std::pair<std::string, std::string>>& params);

// "radius=3 demodulate=false ...": every parameter value of the filter, as the
// "mcreconParameters" header attribute of an output.
std::string parameters_text(const Filter& filter);

// "key=value" -> pair; throws InvalidArgument.
std::pair<std::string, std::string> parse_key_value(const std::string& text, const std::string& option);

}  // namespace mcr
