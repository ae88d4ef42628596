#pragma once
/// Adds the wall time of a scope to a counter (for the per-term timings in meta.json).
#include <chrono>

namespace papersim::simulation {

class ScopedTimer {
 public:
  explicit ScopedTimer(double& total) : m_total(total), m_t0(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() {
    m_total += std::chrono::duration<double>(std::chrono::steady_clock::now() - m_t0).count();
  }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  double& m_total;
  std::chrono::steady_clock::time_point m_t0;
};

}  // namespace papersim::simulation
