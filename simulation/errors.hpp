#pragma once
/// Errors of the simulation module.
#include <stdexcept>
#include <string>

namespace papersim::simulation {

/// Bad scene or option: names the key and the file.
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Numeric breakdown: NaN in the state, a matrix that cannot be factored, a step that cannot be
/// taken even at the smallest time step.
struct NumericError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace papersim::simulation
