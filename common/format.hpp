#pragma once
/// Numbers in messages: short and exact enough to recognise (std::to_string(1e300) has 301 digits).
#include <cstdio>
#include <string>

namespace papersim::common {

/// `value` with up to 6 significant digits ("0.25", "1e+300", "inf").
inline std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

}  // namespace papersim::common
