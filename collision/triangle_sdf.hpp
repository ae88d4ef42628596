#pragma once
/// The minimum of an obstacle's signed distance over a whole sheet triangle, not only at its
/// vertices, so features smaller than the sheet's edges (a gable ridge, a 5 mm sphere) cannot
/// slip between vertices.
///
/// Method: best-first branch and bound on a 4-way midpoint subdivision of the triangle. Each
/// sub-triangle is evaluated at its centroid c; because the field is 1-Lipschitz, every point of
/// the sub-triangle has phi >= phi(c) - R, R the largest centroid-to-corner distance (scaled by
/// `lipschitz` for grid fields, whose interpolant can be slightly steeper than 1). Sub-triangles
/// whose bound exceeds `cutoff` (out of contact) or the best value found are dropped; the others
/// are split until R <= `resolution`. The best sample is then polished by a few projected
/// gradient steps inside the triangle. The result carries both the smallest value found (an
/// upper bound on the true minimum, attained at `barycentric`) and a certified lower bound.
/// A triangle far from the obstacle costs one query.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <vector>

#include "collision/collider.hpp"

namespace papersim::collision {

/// Controls of triangle_min_distance.
struct TriangleSdfParams {
  /// Sub-triangles whose lower bound exceeds this are not refined (use the contact thickness
  /// dhat: beyond it the barrier is zero) [m].
  double cutoff = 1e-3;
  /// Stop splitting when a sub-triangle's circumradius is below this; the lower bound is then
  /// within about `resolution` of the minimum. Take it below the smallest obstacle feature [m].
  double resolution = 5e-4;
  /// Lipschitz constant assumed for the field (1 for exact fields; a little more for grids) [-].
  double lipschitz = 1.0;
  /// Budget of field queries per triangle [-].
  int max_evaluations = 2048;
  /// Projected gradient steps used to polish the best sample [-].
  int polish_iterations = 10;
};

/// Minimum of the signed distance over a triangle.
struct TriangleSdfResult {
  double distance = std::numeric_limits<double>::infinity();  ///< smallest phi found [m]
  double lower_bound =
      -std::numeric_limits<double>::infinity();  ///< phi >= this on the triangle [m]
  /// weights of a, b, c of the minimiser
  Eigen::Vector3d barycentric = Eigen::Vector3d::Constant(1.0 / 3.0);
  Eigen::Vector3d point = Eigen::Vector3d::Zero();      ///< world minimiser [m]
  Eigen::Vector3d gradient = Eigen::Vector3d::UnitZ();  ///< unit field gradient there (world)
  int evaluations = 0;                                  ///< field queries used
};

/// Minimum of `collider`'s signed distance over the triangle (a, b, c) (world, [m]) with the
/// obstacle at `pose` (= collider.motion.pose(t)). Thread-safe. For a contact force at the
/// minimiser use phi(sum w_i x_i) with the returned weights w held fixed: its gradient with
/// respect to vertex i is w_i * gradient.
TriangleSdfResult triangle_min_distance(const Collider& collider, const Eigen::Vector3d& a,
                                        const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                        const Eigen::Affine3d& pose,
                                        const TriangleSdfParams& params = {});

/// One face of a mesh in contact range.
struct FaceSdfContact {
  int face = -1;             ///< index into the triangle list
  TriangleSdfResult result;  ///< its minimum
};

/// triangle_min_distance for every face of a triangle mesh (positions [m] world, faces as
/// vertex indices), keeping the faces whose minimum found is below params.cutoff. Faces are
/// processed in parallel (TBB); the output is ordered by face index.
std::vector<FaceSdfContact> mesh_edges_faces_vs_sdf(const Collider& collider,
                                                    const std::vector<Eigen::Vector3d>& positions,
                                                    const std::vector<Eigen::Vector3i>& faces,
                                                    const Eigen::Affine3d& pose,
                                                    const TriangleSdfParams& params = {});

}  // namespace papersim::collision
