#include "simulation/scenario.hpp"

#include <cmath>
#include <random>

#include "simulation/errors.hpp"

namespace papersim::simulation {

namespace {

/// Uniform draws from a 64-bit Mersenne Twister. std::uniform_real_distribution is not
/// specified bit-for-bit across standard libraries, so draws are made from raw 53-bit integers.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : m_rng(seed) {}
  double uniform(double a, double b) { return a + (b - a) * unit(); }
  double unit() { return static_cast<double>(m_rng() >> 11) * 0x1.0p-53; }
  bool chance(double p) { return unit() < p; }

 private:
  std::mt19937_64 m_rng;
};

/// Pull (SCENARIOS.md): an A4 sheet on the ground; two points (one with probability 5%) anywhere
/// on it are lifted linearly to U[0.03, 0.08] m over 1 s under gravity U[-100, -9.8] m/s^2.
/// The handles set the points' height; their horizontal position is free.
Scene pull(std::uint64_t seed) {
  Draw d(seed);
  Scene s;
  s.name = "pull";
  s.scenario = "pull";
  s.seed = static_cast<long long>(seed);
  s.sheet.position = Eigen::Vector3d(0, 0, 1e-3);
  s.gravity = Eigen::Vector3d(0, 0, d.uniform(-100, -9.8));
  s.duration = 1.0;
  s.time_step = 1e-2;
  s.sheet.edge_length = 1e-2;
  s.ground = true;
  s.ground_friction = 0.3;
  const int points = d.chance(0.05) ? 1 : 2;
  for (int i = 0; i < points; ++i) {
    HandleSpec h;
    double lift = 0;
    // Two points at material distance r cannot end at heights more than r apart on an
    // inextensible sheet: such draws are avoided by construction (the second point is drawn
    // again until |lift difference| <= 0.8 r), instead of stretching the sheet to its limit.
    for (int attempt = 0; attempt < 1000; ++attempt) {
      h.material_point = Eigen::Vector2d(d.uniform(0, s.sheet.width), d.uniform(0, s.sheet.height));
      lift = d.uniform(0.03, 0.08);
      if (i == 0) break;
      const HandleSpec& first = s.handles.front();
      const double r = (h.material_point - first.material_point).norm();
      if (std::abs(lift - first.keyframes.back().displacement.z()) <= 0.8 * r) break;
    }
    h.keyframes = {{0.0, Eigen::Vector3d::Zero()}, {1.0, Eigen::Vector3d(0, 0, lift)}};
    // Only the height is driven: two points lifted to different heights move towards each
    // other, as an inextensible sheet must.
    h.axes = Eigen::Vector3d(0, 0, 1);
    s.handles.push_back(h);
  }
  return s;
}

}  // namespace

std::vector<std::string> scenario_names() { return {"pull"}; }

Scene make_scenario(const std::string& name, std::uint64_t seed) {
  if (name == "pull") return pull(seed);
  std::string known;
  for (const auto& n : scenario_names()) known += (known.empty() ? "" : ", ") + n;
  throw SceneError("unknown scenario '" + name + "' (known: " + known + ")");
}

}  // namespace papersim::simulation
