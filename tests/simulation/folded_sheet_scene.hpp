#pragma once
/// A scene that the self-contact and checkpoint tests share.
#include "simulation/scene.hpp"

namespace papersim::simulation::test_scenes {

/// A 12 x 4 cm sheet of soft paper (D = 2e-6 N m) on the ground; the two corners of its right
/// edge are lifted, carried over and brought down above the left half. At 0.5 s they are let go
/// vertically (still held in x and y): the top half falls onto the bottom half and rests on it.
/// 5 ms steps. At 4 mm edges (ten faces across) the fold's radius (a few mm) is resolved; at
/// 8 mm (five faces) the fold is sharper than the mesh, where the morley model is soft and the
/// sheet slides sideways instead of rolling over (docs/elastica_30deg_diagnosis.md section 6).
inline Scene sheet_folded_onto_itself(double edge_length, double duration) {
  Scene s;
  s.name = "fold";
  s.sheet.width = 0.12;
  s.sheet.height = 0.04;
  s.sheet.edge_length = edge_length;
  s.sheet.material.bending_stiffness = 2e-6;
  s.sheet.position = Eigen::Vector3d(0, 0, 1e-3);
  for (double y : {0.0, 0.04})
    for (int vertical : {1, 0}) {
      HandleSpec h;
      h.material_point = Eigen::Vector2d(0.12, y);
      h.keyframes = {{0.0, Eigen::Vector3d::Zero()},
                     {0.2, Eigen::Vector3d(-0.04, 0, 0.04)},
                     {0.4, Eigen::Vector3d(-0.1, 0, 0.015)},
                     {0.5, Eigen::Vector3d(-0.105, 0, 0.01)}};
      if (vertical) {
        h.release_time = 0.5;
      } else {
        h.axes = Eigen::Vector3d(1, 1, 0);
      }
      s.handles.push_back(h);
    }
  s.duration = duration;
  s.time_step = 0.005;
  return s;
}

}  // namespace papersim::simulation::test_scenes
