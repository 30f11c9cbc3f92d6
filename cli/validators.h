#pragma once
// Option checks whose messages repeat what was typed and give the range readably (CLI11's
// Range prints DBL_MAX as 300 digits and 1e-4 as 0.000100). CLI11 prefixes the option name.
#include <CLI/CLI.hpp>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <string>

#include "util/params.h"

namespace mcr::cli {

// A whole number in [lo, hi] (an int option: hi at most INT_MAX).
inline CLI::Validator whole_number(long long lo, long long hi = INT_MAX) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        errno = 0;
        char* end = nullptr;
        const long long v = std::strtoll(text.c_str(), &end, 10);
        if (text.empty() || *end != '\0' || errno == ERANGE || v < lo || v > hi)
          return "expects a whole number in " + range + ", got '" + text + "'";
        return "";
      },
      "INT in " + range);
}

// A finite number in [lo, hi].
inline CLI::Validator number_in(double lo, double hi) {
  const std::string range = "[" + number_text(lo) + ", " + number_text(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi)
          return "expects a number in " + range + ", got '" + text + "'";
        return "";
      },
      "NUMBER in " + range);
}

// A sample count l*l with l in 1..max_l (light-field samples sit on an l x l grid of strata).
inline CLI::Validator perfect_square(int max_l) {
  std::string squares;
  for (int l = 1; l <= max_l; ++l)
    if (l <= 4 || l == max_l) squares += (squares.empty() ? "" : l == max_l ? ", ..., " : ", ") + std::to_string(l * l);
  const std::string what = "expects a perfect square l*l with l in 1.." + std::to_string(max_l) + " (" + squares + ")";
  return CLI::Validator(
      [max_l, what](std::string& text) -> std::string {
        errno = 0;
        char* end = nullptr;
        const long long v = std::strtoll(text.c_str(), &end, 10);
        long long l = 0;
        while ((l + 1) * (l + 1) <= v && l < max_l) ++l;
        if (text.empty() || *end != '\0' || errno == ERANGE || v < 1 || l * l != v)
          return what + ", got '" + text + "'";
        return "";
      },
      "l*l, l in 1.." + std::to_string(max_l));
}

}  // namespace mcr::cli
