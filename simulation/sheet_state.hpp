#pragma once
/// The sheet's dynamic state: world positions and velocities of the vertices, and the time.
#include <Eigen/Core>

namespace papersim::simulation {

struct SheetState {
  Eigen::VectorXd positions;   ///< 3N world positions [m], vertex v at 3v..3v+2
  Eigen::VectorXd velocities;  ///< 3N [m/s]
  double time = 0.0;           ///< [s]

  int num_vertices() const { return static_cast<int>(positions.size() / 3); }
  /// Positions as #V by 3.
  Eigen::MatrixX3d positions_matrix() const;
  Eigen::MatrixX3d velocities_matrix() const;
};

/// Flatten #V by 3 to 3N.
Eigen::VectorXd flatten(const Eigen::MatrixX3d& m);

}  // namespace papersim::simulation
