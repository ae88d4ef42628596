#pragma once
/// Errors of the remesh module: typed exceptions for bad input and I/O.
#include <stdexcept>
#include <string>

namespace papersim::remesh {

/// A mesh that breaks a requirement (NaN, non-manifold edge, degenerate face, missing data).
struct MeshError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A parameter out of range; the message names it.
struct ParameterError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// A file that cannot be opened, read or written.
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace papersim::remesh
