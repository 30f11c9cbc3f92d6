// Fuzz target: every filter on small random frames. The input decodes to a filter, a size
// (1..24 x 1..24), which feature passes are present, valid parameter values (defaults,
// range ends, values inside), an roi, the instruction set, and pixel values that include
// NaN, +-Inf, +-FLT_MAX, denormals and huge and tiny numbers (the bytes after the header
// repeat as a pattern over every pass). execute() runs once (temporal filters: twice, then
// once more after reset()). A finding: a sanitizer report, Errc::Internal, an output of
// the wrong size, or any non-finite output value.
#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "filters/registry.h"
#include "fuzz_check.h"
#include "util/isa.h"

namespace {

using mcr::fuzz::fail;

// A valid value of s, chosen by the input (or its default).
mcr::ParamValue choose(const mcr::ParamSpec& s, FuzzedDataProvider& in) {
  const std::uint8_t how = in.ConsumeIntegral<std::uint8_t>();
  const double t = in.ConsumeIntegral<std::uint8_t>() / 255.0;
  if ((how & 1) == 0) return s.default_value;
  const int pick = (how >> 1) % 4;
  switch (s.type) {
    case mcr::ParamType::Bool: return bool(pick & 1);
    case mcr::ParamType::Enum: return s.choices[std::size_t(t * 255) % s.choices.size()];
    case mcr::ParamType::Int: {
      const auto lo = std::int64_t(s.min), hi = std::int64_t(s.max);
      if (pick == 0) return lo;
      if (pick == 1) return hi;
      return std::min(hi, lo + std::int64_t(t * 255) % std::min<std::int64_t>(hi - lo + 1, 256));
    }
    case mcr::ParamType::Float: {
      if (pick == 0) return s.min;
      if (pick == 1) return s.max;
      double v = s.min + t * (s.max - s.min);
      if (pick == 3 && s.min > 0) v = std::exp(std::log(s.min) + t * (std::log(s.max) - std::log(s.min)));
      return std::clamp(v, s.min, s.max);
    }
  }
  return s.default_value;
}

// The pixel pattern: two bytes per value, a class and a value byte, cycling over `bytes`.
struct Pattern {
  std::vector<std::uint8_t> bytes;
  std::size_t next = 0;
  float value() {
    if (bytes.size() < 2) return 0.5f;
    const std::uint8_t cls = bytes[next % bytes.size()], b = bytes[(next + 1) % bytes.size()];
    const float u = float((b + 37 * (next / 2)) % 256) / 255.0f;  // varies as the pattern repeats
    next += 2;
    switch (cls % 16) {
      case 8: return -10.0f * u;
      case 9: return 0.0f;
      case 10: return std::numeric_limits<float>::quiet_NaN();
      case 11: return std::numeric_limits<float>::infinity();
      case 12: return -std::numeric_limits<float>::infinity();
      case 13: return (b & 1) ? FLT_MAX : -FLT_MAX;
      case 14: return (b & 1) ? 1e-40f : 1e-30f * u;  // denormal, tiny
      case 15: return 1e30f * u;
      default: return u;
    }
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  static const std::vector<std::string> names = mcr::filter_names();
  const std::string name = names[in.ConsumeIntegralInRange<std::size_t>(0, names.size() - 1)];
  const int w = in.ConsumeIntegralInRange(1, 24), h = in.ConsumeIntegralInRange(1, 24);
  const auto present = in.ConsumeIntegral<std::uint16_t>();
  const int isa_level = std::min(in.ConsumeIntegralInRange(0, 2), int(mcr::best_isa()));
  const int nthreads = in.ConsumeIntegralInRange(1, 2);
  mcr::ExecOptions opts;
  opts.nthreads = nthreads;
  if (in.ConsumeBool()) {
    opts.roi.x0 = in.ConsumeIntegralInRange(0, w - 1);
    opts.roi.x1 = in.ConsumeIntegralInRange(opts.roi.x0 + 1, w);
    opts.roi.y0 = in.ConsumeIntegralInRange(0, h - 1);
    opts.roi.y1 = in.ConsumeIntegralInRange(opts.roi.y0 + 1, h);
  }

  std::unique_ptr<mcr::Filter> filter = mcr::make_filter(name);
  for (const mcr::ParamSpec& s : filter->info().params) {
    try {
      filter->set(s.name, choose(s, in));
    } catch (const mcr::Error& e) {
      std::fprintf(stderr, "%s: %s\n", name.c_str(), e.what());
      fail("a valid parameter value was refused");
    }
  }
  try {
    filter->commit();
  } catch (const mcr::Error& e) {  // a combination the filter refuses (min above max, ...)
    mcr::fuzz::expect_user_error(e);
    return 0;
  }

  Pattern pattern{in.ConsumeRemainingBytes<std::uint8_t>()};
  mcr::Frame frame;
  frame.width = w;
  frame.height = h;
  frame.path = "fuzz.exr";
  int bit = 0;
  for (mcr::Role r : mcr::kAllRoles) {
    if (r != mcr::Role::Colour && !(present >> bit++ & 1)) continue;
    mcr::Pass p;
    p.role = r;
    p.name = mcr::role_name(r);
    p.image = mcr::Image(w, h, mcr::role_channels(r));
    for (float& v : p.image.storage()) v = pattern.value();
    frame.passes.push_back(std::move(p));
  }

  if (filter->info().deep_input) {
    // A per-sample buffer: 0..3 samples per pixel, every channel of the convention (README)
    // from the pattern, non-finite values included.
    auto deep = std::make_shared<mcr::DeepSamples>();
    deep->width = w;
    deep->height = h;
    deep->channel_names = {"R", "G", "B", "Z", "A", "dx", "dy", "blur", "mx", "my"};
    deep->offsets.assign(std::size_t(w) * std::size_t(h) + 1, 0);
    for (std::size_t p = 0; p + 1 < deep->offsets.size(); ++p) {
      const float a = std::fabs(pattern.value());
      deep->offsets[p + 1] = deep->offsets[p] + (a < 1e6f ? std::uint64_t(a * 7.0f) % 4 : 3);
    }
    deep->values.assign(deep->channel_names.size(), std::vector<float>(deep->total_samples()));
    for (auto& channel : deep->values)
      for (float& v : channel) v = pattern.value();
    frame.deep = deep;
  }

  mcr::ScopedIsa isa(static_cast<mcr::Isa>(isa_level));
  const int runs = filter->info().temporal ? 3 : 1;
  for (int run = 0; run < runs; ++run) {
    if (run == 2) filter->reset();
    mcr::Image out;
    try {
      out = filter->execute(frame, opts);
    } catch (const mcr::Error& e) {  // a pass it needs is absent
      mcr::fuzz::expect_user_error(e);
      return 0;
    }
    if (out.width() != w || out.height() != h || out.channels() != 3) fail("the output has the wrong size");
    for (float v : out.storage())
      if (!std::isfinite(v)) {
        std::fprintf(stderr, "%s (run %d): output %g\n", name.c_str(), run, double(v));
        fail("a non-finite value left the filter");
      }
  }
  return 0;
}
