#pragma once
/// Errors of the collision module: typed exceptions for bad obstacle descriptions and files.
#include <stdexcept>
#include <string>

namespace papersim::collision {

/// An obstacle description that cannot be built: a non-positive or non-finite dimension, an
/// unknown kind, a grid that would exceed its memory limit. The message names the bad value.
struct ColliderError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A mesh file that cannot be opened or parsed, or whose mesh is not closed; the message names
/// the file (and the line, when parsing failed).
struct ColliderIoError : ColliderError {
  using ColliderError::ColliderError;
};

}  // namespace papersim::collision
