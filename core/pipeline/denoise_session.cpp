#include "pipeline/denoise_session.h"

#include <chrono>

#include "io/exr_output.h"
#include "io/output_guard.h"
#include "pipeline/sequence_plan.h"
#include "util/error.h"

namespace mcr {

namespace {
double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

std::pair<std::string, std::string> parse_key_value(const std::string& text, const std::string& option) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error(Errc::InvalidArgument, option + " expects KEY=VALUE, got '" + text + "'");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

DenoiseSession::DenoiseSession(const std::string& filter,
                               const std::vector<std::pair<std::string, std::string>>& params, bool accumulate)
    : reconstruction_(make_committed_filter(filter, params), accumulate) {}

StageTimes DenoiseSession::run(const std::string& input, const std::string& output, const ReadOptions& read,
                               const WriteOptions& write, const ExecOptions& exec) {
  if (write.keep_components) check_keep_components(reconstruction_.filter().params());
  if (!read.second_half.empty() && reconstruction_.light_passes())
    // Two half buffers are merged by their colour pass only (io/half_buffers.h): the light
    // passes would come from the first half alone.
    throw Error(Errc::InvalidArgument, "--half '" + read.second_half + "' with components=light_passes: the halves' "
                                       "light passes are not merged; denoise one render with components=light_passes, "
                                       "or the halves with components=beauty");
  if (!output.empty()) {
    // Every front end's file run passes here: the output is checked against every
    // input of the run (the render and any loose pass file) before anything is read.
    std::vector<std::string> inputs = loose_pass_files(read);
    inputs.push_back(input);
    check_output_path(output, inputs);
    check_write(output, write);  // Python and the add-on too: what the name says, or an error
  }
  StageTimes t;
  auto t0 = std::chrono::steady_clock::now();
  Frame frame = read_frame(input, read);
  t.read_ms = ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  // The frame is ours: with accumulation its colour becomes the accumulated one, which
  // the writer never reads (it takes alpha and the other channels from it).
  std::vector<ComponentImage> components;
  const Image result = reconstruction_.run_in_place(frame, exec, write.keep_components ? &components : nullptr);
  t.filter_ms = ms_since(t0);

  if (!output.empty()) {
    t0 = std::chrono::steady_clock::now();
    WriteOptions w = write;
    w.attributes.emplace_back("mcreconFilter", reconstruction_.filter().info().name);
    w.attributes.emplace_back("mcreconParameters", reconstruction_.parameters_text());
    w.attributes.emplace_back("mcreconInput", input_stamp(input));  // --resume checks all three
    for (const ComponentImage& c : components)
      w.layers.emplace_back(component_layer_prefix(frame.layer) + c.name, &c.rgb);
    write_result(output, result, frame, w);
    t.write_ms = ms_since(t0);
  }
  return t;
}

}  // namespace mcr
