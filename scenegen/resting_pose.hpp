#pragma once
/// Where the sheet rests: the support plane of its stable resting pose on a table, found from
/// its convex hull. The background plane of every scene is put on that plane.
#include <Eigen/Core>

#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// The stage: a right-handed frame on the support plane. Stage coordinates (x, y, z) map to the
/// world point origin + x ex + y ey + z up.
struct Stage {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< centre of mass projected on the plane [m]
  Eigen::Vector3d ex = Eigen::Vector3d::UnitX();     ///< in-plane axis (unit)
  Eigen::Vector3d ey = Eigen::Vector3d::UnitY();     ///< in-plane axis: world +y projected (unit)
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();     ///< plane normal towards the sheet (unit)
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();  ///< of the sheet [m]
  bool flat_sheet = false;  ///< the sheet is planar (hull degenerate)
  bool stable = true;       ///< false: no hull face holds the centre of mass (fallback used)
  int stable_faces = 0;     ///< number of hull faces that are stable poses

  /// World point of stage coordinates [m].
  Eigen::Vector3d to_world(const Eigen::Vector3d& s) const {
    return origin + s.x() * ex + s.y() * ey + s.z() * up;
  }
  /// World direction of a stage direction.
  Eigen::Vector3d dir_to_world(const Eigen::Vector3d& s) const {
    return s.x() * ex + s.y() * ey + s.z() * up;
  }
};

/// Stable resting pose: among the faces of the convex hull (CGAL) whose supporting plane has the
/// centre of mass projecting inside the hull's contact polygon, the one whose outward normal is
/// closest to world -z (the pose nearest to the mesh's own orientation). A planar sheet rests on
/// its own plane, printed side up when its normal has a +z component.
Stage find_resting_pose(const SheetMesh& mesh);

}  // namespace papersim::scenegen
