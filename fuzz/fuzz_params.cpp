// Fuzz target: the parameter parser. Input = one byte choosing the filter, then lines of
// text. A line starting with '@' names a parameter of the filter's table by its next byte
// (so the fuzzer reaches every entry) and gives the rest as its value; any other line goes
// through parse_key_value as the CLI's --set does. Every line is also tried as a frame
// range and as a sequence pattern. Bad text must give mcr::Error, never a crash; values
// that are accepted must be in the table's range; a sequence pattern must give distinct
// frames distinct names.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "filters/registry.h"
#include "fuzz_check.h"
#include "io/sequence.h"
#include "pipeline/denoise_session.h"
#include "pipeline/reconstruction.h"

namespace {

using mcr::fuzz::fail;

void check_in_range(const mcr::Filter& f) {
  for (const mcr::ParamSpec& s : f.info().params) {
    const mcr::ParamSet& p = f.params();
    if (s.type == mcr::ParamType::Int) {
      const auto v = p.get_int(s.name);
      if (double(v) < s.min || double(v) > s.max) fail("an Int parameter outside its range was accepted");
    } else if (s.type == mcr::ParamType::Float) {
      const double v = p.get_float(s.name);
      if (!std::isfinite(v) || v < s.min || v > s.max) fail("a Float parameter outside its range was accepted");
    } else if (s.type == mcr::ParamType::Enum) {
      const std::string& v = p.get_enum(s.name);
      bool known = false;
      for (const std::string& c : s.choices) known = known || c == v;
      if (!known) fail("an Enum parameter outside its choices was accepted");
    }
  }
}

void try_sequence(const std::string& line, int frame) {
  try {
    const mcr::FrameList r = mcr::parse_frame_list(line);
    if (r.size() == 0 || r.size() > mcr::kMaxFrames) fail("parse_frame_list accepted no frame or too many");
    for (std::size_t i = 1; i < r.size(); ++i)
      if (r.frames()[i] <= r.frames()[i - 1]) fail("parse_frame_list accepted frames out of order");
    if (r.size() <= 10000 && mcr::parse_frame_list(r.text()).frames() != r.frames()) fail("FrameList::text does not read back");
  } catch (const mcr::Error& e) {
    mcr::fuzz::expect_user_error(e);
  }
  try {
    if (!mcr::is_sequence_pattern(line)) return;
    const int other = frame == 2147483647 ? frame - 1 : frame + 1;
    if (mcr::sequence_path(line, frame) == mcr::sequence_path(line, other))
      fail("sequence_path gives two frames the same name");
  } catch (const mcr::Error& e) {
    mcr::fuzz::expect_user_error(e);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const std::vector<std::string> names = mcr::filter_names();
  const std::string name = names[data[0] % names.size()];
  std::unique_ptr<mcr::Filter> filter = mcr::make_filter(name);
  const mcr::ParamTable& table = filter->info().params;

  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  std::vector<std::pair<std::string, std::string>> pairs;  // what the CLI would pass on
  std::size_t start = 0;
  int line_no = 0;
  while (start <= text.size()) {
    const auto nl = text.find('\n', start);
    const std::string line = text.substr(start, nl == std::string::npos ? std::string::npos : nl - start);
    static const int kFrames[] = {1, 0, -1, 12345, 2147483646, -2147483647 - 1};
    const int frame = kFrames[line_no++ % 6];
    try_sequence(line, frame);
    try {
      std::string key, value;
      if (line.size() >= 2 && line[0] == '@') {
        key = table[std::uint8_t(line[1]) % table.size()].name;
        value = line.substr(2);
      } else {
        std::tie(key, value) = mcr::parse_key_value(line, "--set");
      }
      filter->set_text(key, value);
      pairs.emplace_back(key, value);
    } catch (const mcr::Error& e) {
      mcr::fuzz::expect_user_error(e);
    }
    if (nl == std::string::npos) break;
    start = nl + 1;
  }
  check_in_range(*filter);
  try {
    filter->commit();
    (void)filter->needs();
    (void)mcr::parameters_text(*filter);
    // The same settings the way the front ends apply them.
    (void)mcr::make_committed_filter(name, pairs);
  } catch (const mcr::Error& e) {
    mcr::fuzz::expect_user_error(e);
  }
  return 0;
}
