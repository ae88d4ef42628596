#pragma once
/// Time left in a long job from its progress: at the rate of its last tenth.
#include <cstddef>
#include <utility>
#include <vector>

namespace papersim::common {

/// The ETA of a job whose steps can grow dearer as it goes (the crumple's last second takes four
/// fifths of its wall time): the rest of the job at the rate of its last tenth (of all of it so
/// far, before a tenth is done). The mean rate over the whole job would promise far too soon.
class RecentRateEta {
 public:
  /// Progress `fraction` in [0, 1] done after `seconds`; returns the seconds left (0 before any
  /// progress). Call with non-decreasing fractions and times.
  double update(double fraction, double seconds) {
    // The latest report a tenth of the job back (or the start).
    std::size_t from = 0;
    while (from + 1 < m_seen.size() && m_seen[from + 1].first <= fraction - window) ++from;
    const auto [f0, s0] = m_seen[from];
    m_seen.erase(m_seen.begin(), m_seen.begin() + static_cast<std::ptrdiff_t>(from));
    m_seen.emplace_back(fraction, seconds);
    return fraction > f0 ? (seconds - s0) * (1 - fraction) / (fraction - f0) : 0.0;
  }

  static constexpr double window = 0.1;  ///< the share of the job whose rate counts

 private:
  std::vector<std::pair<double, double>> m_seen{{0.0, 0.0}};  // (fraction, seconds), oldest first
};

}  // namespace papersim::common
