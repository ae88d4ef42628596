#pragma once
/// The safety verdict of a finished run, shared by the scenario studies: no NaN, no
/// penetration of the ground or an obstacle, no self-intersection, stretch within the limit.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "simulation/run.hpp"
#include "simulation/scene.hpp"

namespace papersim::validation {

/// Smallest distances of a run's sheet to the ground and to the other obstacles [m] (+inf when
/// there is none), over the whole run.
struct ObstacleGaps {
  double ground = std::numeric_limits<double>::infinity();
  double obstacles = std::numeric_limits<double>::infinity();
};

/// Splits RunQuality::min_obstacle_distance into the ground (obstacle 0 when the scene has one)
/// and the rest.
inline ObstacleGaps obstacle_gaps(const simulation::Scene& scene, const simulation::RunQuality& q) {
  ObstacleGaps g;
  const auto& d = q.min_obstacle_distance;
  for (std::size_t o = 0; o < d.size(); ++o) {
    if (o == 0 && scene.ground)
      g.ground = d[o];
    else
      g.obstacles = std::min(g.obstacles, d[o]);
  }
  return g;
}

inline ObstacleGaps obstacle_gaps(const simulation::Scene& scene, const simulation::RunResult& r) {
  return obstacle_gaps(scene, r.quality);
}

/// "PASS", or "FAIL" and the first check that failed: NaN in the positions (`finite` false), a
/// gap to the ground or an obstacle that is not positive, a self-intersection, a principal
/// stretch above 1 + strain_limit, or one below 1 - compression_limit when the scene sets that
/// limit.
inline std::string safety_verdict(const simulation::Scene& scene, const simulation::RunQuality& q,
                                  bool finite) {
  const ObstacleGaps g = obstacle_gaps(scene, q);
  if (!finite) return "FAIL nan";
  if (!(g.obstacles > 0) || !(g.ground > 0)) return "FAIL penetration";
  if (q.self_intersections != 0) return "FAIL self-intersection";
  if (q.max_principal_stretch > 1 + scene.sheet.material.strain_limit) return "FAIL stretch";
  const double c = scene.sheet.material.compression_limit;
  if (c > 0 && q.min_principal_stretch < 1 - c) return "FAIL compression";
  return "PASS";
}

inline std::string safety_verdict(const simulation::Scene& scene, const simulation::RunResult& r) {
  return safety_verdict(scene, r.quality, r.state.positions.allFinite());
}

}  // namespace papersim::validation
