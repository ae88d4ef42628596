#pragma once
/// Wall-clock intervals for run statistics and progress reports.
#include <chrono>

namespace papersim {

/// Seconds of the steady clock since `t0`.
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace papersim
