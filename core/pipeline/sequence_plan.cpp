#include "pipeline/sequence_plan.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <filesystem>
#include <limits>

#include "io/exr_output.h"
#include "io/input_limits.h"
#include "util/error.h"

namespace mcr {

std::vector<FrameJob> plan_sequence(const FrameList& frames, const std::vector<bool>& done, bool temporal, int warmup) {
  if (done.size() != frames.size()) throw Error(Errc::InvalidArgument, "plan_sequence: one done flag per frame");
  const std::vector<int>& f = frames.frames();
  std::vector<FrameJob> jobs;
  if (!temporal) {
    for (std::size_t i = 0; i < f.size(); ++i)
      if (!done[i]) jobs.push_back({f[i], true});
    return jobs;
  }
  const auto first_todo = std::find(done.begin(), done.end(), false);
  if (first_todo == done.end()) return jobs;  // all done: nothing to replay
  const std::size_t k0 = std::size_t(first_todo - done.begin());
  const std::size_t k1 = f.size() - 1 - std::size_t(std::find(done.rbegin(), done.rend(), false) - done.rbegin());
  // The warm-up frames before the list (consecutive: a temporal run's frames are), then every
  // done frame up to the first one to write.
  for (long long g = (long long)f[0] - std::max(0, warmup); g < f[0]; ++g)
    if (g >= (long long)std::numeric_limits<int>::min()) jobs.push_back({int(g), false});
  for (std::size_t i = 0; i < k0; ++i) jobs.push_back({f[i], false});
  for (std::size_t i = k0; i <= k1; ++i) jobs.push_back({f[i], !done[i]});
  return jobs;
}

std::vector<Chunk> plan_chunks(const FrameList& frames, int chunk, int warmup) {
  if (chunk < 1) throw Error(Errc::InvalidArgument, "--chunk " + std::to_string(chunk) + ": a chunk holds 1 frame or more");
  if (warmup < 0) throw Error(Errc::InvalidArgument, "--warmup " + std::to_string(warmup) + ": give 0 or more frames");
  std::vector<Chunk> chunks;
  const std::vector<int>& f = frames.frames();
  for (std::size_t i = 0; i < f.size(); i += std::size_t(chunk)) {
    const std::size_t end = std::min(f.size(), i + std::size_t(chunk));
    const long long before = (long long)f[i] - frames.first();
    chunks.push_back({FrameList(std::vector<int>(f.begin() + long(i), f.begin() + long(end))),
                      int(std::min<long long>(warmup, before))});
  }
  return chunks;
}

std::string input_stamp(const std::string& input) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(input, ec);
  return std::filesystem::path(input).filename().string() + " " + (ec ? std::string("?") : std::to_string(size)) +
         " bytes";
}

std::string stale_output_reason(const std::string& output, const std::string& filter, const std::string& parameters,
                                const std::string& input) {
  // The header first: an output of another run is redone without decoding its pixels.
  std::string had_filter, had_params, had_input;
  {
    std::unique_ptr<OIIO::ImageInput> in;
    try {
      in = open_image(output);  // a header that asks for more than the file can hold is not read
    } catch (const Error& e) {
      return std::string("unreadable: ") + e.what();
    }
    had_filter = in->spec().get_string_attribute("mcreconFilter");
    had_params = in->spec().get_string_attribute("mcreconParameters");
    had_input = in->spec().get_string_attribute("mcreconInput");
  }
  if (had_filter.empty()) return "not an mcrecon output (no mcreconFilter in its header)";
  if (had_filter != filter) return "made by " + had_filter + ", this run is " + filter;
  if (had_params != parameters) return "made with other parameters (" + had_params + ")";
  const std::string now = input_stamp(input);
  if (had_input != now) return "made from another input (" + (had_input.empty() ? "not recorded" : had_input) + ", now " + now + ")";
  const std::string unreadable = incomplete_file_reason(output);
  return unreadable.empty() ? "" : "unreadable: " + unreadable;
}

}  // namespace mcr
