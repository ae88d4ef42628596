#pragma once
/// Scenarios: named generators that turn (name, seed) into a scene with the random draws of
/// SCENARIOS.md. The same name and seed always give the same scene.
#include <cstdint>
#include <string>
#include <vector>

#include "simulation/scene.hpp"

namespace papersim::simulation {

/// Names of the scenarios this build knows.
std::vector<std::string> scenario_names();

/// Draw the scene of scenario `name` for `seed`.
/// @throw SceneError for an unknown name (listing the known ones).
Scene make_scenario(const std::string& name, std::uint64_t seed);

}  // namespace papersim::simulation
