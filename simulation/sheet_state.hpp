#pragma once
/// The sheet's dynamic state: world positions and velocities of the vertices, the time, and the
/// barrier stiffnesses the last step ended with (ObstacleContactEnergy, "Load rule";
/// SelfContactEnergy, "Adaptive stiffness").
#include <Eigen/Core>

namespace papersim::simulation {

struct SheetState {
  Eigen::VectorXd positions;   ///< 3N world positions [m], vertex v at 3v..3v+2
  Eigen::VectorXd velocities;  ///< 3N [m/s]
  double time = 0.0;           ///< [s]
  /// Stiffness of the obstacle barrier over the step that reached this state [Pa]; 0: none yet
  /// (the scene's `contact.stiffness`). Carried into the next step, which lets it fall only as
  /// fast as the contact load allows.
  double contact_stiffness = 0.0;
  /// Stiffness of the self-contact barrier over that step [Pa]; 0: none yet (the scene's
  /// `self_contact.stiffness`). It only grows, where two layers were pressed to within a
  /// nanometre-scale floor (SelfContactEnergy, "Adaptive stiffness").
  double self_contact_stiffness = 0.0;

  int num_vertices() const { return static_cast<int>(positions.size() / 3); }
  /// Positions as #V by 3.
  Eigen::MatrixX3d positions_matrix() const;
  Eigen::MatrixX3d velocities_matrix() const;
};

/// Flatten #V by 3 to 3N.
Eigen::VectorXd flatten(const Eigen::MatrixX3d& m);

}  // namespace papersim::simulation
