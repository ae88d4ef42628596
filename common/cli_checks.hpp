#pragma once
// Range and emptiness checks for CLI11 options that name the bad value in a short line. CLI11's own
// NonNegativeNumber and PositiveNumber report "not in range 0.000000 to" the largest double,
// written out in full (309 digits). Header only: include it where CLI11 is linked.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <string>

namespace papersim::common {

/// A finite number >= 0 (`strictly`: > 0).
inline CLI::Validator number_at_least_zero(bool strictly) {
  return CLI::Validator(
      [strictly](std::string& value) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(value.c_str(), &end);
        if (value.empty() || end == value.c_str() || *end != '\0' || !std::isfinite(x))
          return "'" + value + "' is not a number";
        if (strictly ? x <= 0 : x < 0)
          return "'" + value + "' must be " + (strictly ? "> 0" : ">= 0");
        return {};
      },
      strictly ? "POSITIVE" : "NONNEGATIVE");
}

/// A finite number >= 0.
inline CLI::Validator non_negative() { return number_at_least_zero(false); }

/// A finite number > 0.
inline CLI::Validator positive() { return number_at_least_zero(true); }

/// A text that is not empty (a path: "" is no file or folder).
inline CLI::Validator non_empty() {
  return CLI::Validator(
      [](std::string& v) { return v.empty() ? std::string("must not be empty") : std::string(); },
      "NONEMPTY");
}

}  // namespace papersim::common
