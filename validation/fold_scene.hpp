#pragma once
/// The stress suite's 180-degree fold (VALIDATION.md 8): the left edge of a 12 x 4 cm tissue-like
/// sheet is clamped and its right edge carried over the sheet, brought down 3 mm above its left
/// half and let go vertically (still held in x and y), so the top layer falls onto the bottom
/// one. Shared by papersim_stress_suite and papersim_fold_remesh.
#include <Eigen/Core>

#include "simulation/scene.hpp"

namespace papersim::validation {

/// The fold scene on a uniform mesh of `edge_length` [m] (the stress suite uses 8 mm).
inline simulation::Scene fold_180_scene(double edge_length = 0.008) {
  simulation::Scene s;
  s.sheet.width = 0.12;
  s.sheet.height = 0.04;
  s.sheet.edge_length = edge_length;
  s.sheet.position = Eigen::Vector3d(0, 0, 1e-3);
  s.gravity = Eigen::Vector3d(0, 0, -9.8);
  s.duration = 0.8;
  s.time_step = 5e-3;
  s.ground = true;
  // Tissue-like (D = 2e-6 N m, bending length 1.4 cm): office paper (8 cm) would stand up in
  // a loop over 12 cm instead of lying folded with its layers in contact.
  s.sheet.material.bending_stiffness = 2e-6;
  for (double y : {0.0, 0.04})
    for (int vertical : {1, 0}) {
      simulation::HandleSpec h;
      h.material_point = Eigen::Vector2d(0.12, y);
      h.keyframes = {{0.0, Eigen::Vector3d::Zero()},
                     {0.2, Eigen::Vector3d(-0.04, 0, 0.04)},
                     {0.4, Eigen::Vector3d(-0.1, 0, 0.015)},
                     {0.5, Eigen::Vector3d(-0.105, 0, 0.003)}};
      if (vertical)
        h.release_time = 0.5;
      else
        h.axes = Eigen::Vector3d(1, 1, 0);
      s.handles.push_back(h);
    }
  simulation::ClampSpec left;  // the left edge is held, so the sheet folds instead of sliding
  left.region = Eigen::Vector4d(0, 0, 0.005, 0.04);
  s.clamps.push_back(left);
  return s;
}

}  // namespace papersim::validation
