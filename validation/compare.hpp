#pragma once
/// Error norms between two simulated sheets of the same material rectangle (a coarse run against
/// a fine reference), for convergence and run-time-against-error studies:
///  - material correspondence: each vertex of the test sheet is located in the reference's
///    material triangulation, the reference's world position there is interpolated
///    (barycentric), and the distance is taken; RMS and max over the test vertices;
///  - the same two norms after the rigid motion that best aligns the test's vertices with their
///    reference points (least squares, Kabsch): the error of the shape alone, without where the
///    sheet lies (a sheet that slid along a cylinder's axis, a direction in which the draped
///    shape does not change, has a large position error and a small shape error);
///  - symmetric Hausdorff distance between the two triangulated surfaces, from vertices to the
///    other surface's triangles in both directions (exact point-triangle distances).
#include <Eigen/Core>
#include <stdexcept>

namespace papersim::validation {

struct SheetGeometry {
  Eigen::MatrixX2d material;   ///< #V by 2 [m]
  Eigen::MatrixX3d positions;  ///< #V by 3 [m]
  Eigen::MatrixX3i faces;      ///< #F by 3
};

struct SheetDifference {
  double rms = 0.0;          ///< RMS position error at the same material points [m]
  double max = 0.0;          ///< max position error at the same material points [m]
  double rms_aligned = 0.0;  ///< RMS error after the best rigid alignment (shape error) [m]
  double max_aligned = 0.0;  ///< max error after the best rigid alignment [m]
  double hausdorff = 0.0;    ///< symmetric vertex-to-surface Hausdorff distance [m]
  int outside = 0;           ///< test vertices outside the reference's material domain (skipped)
};

struct CompareError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// The rotation R and translation t minimising sum_i |R p_i + t - q_i|^2 (Kabsch; a proper
/// rotation, det R = 1). p and q are #N by 3, N >= 1.
void best_rigid_motion(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& q, Eigen::Matrix3d& R,
                       Eigen::Vector3d& t);

/// Differences of `test` against `reference` (see the file comment). Material points of the
/// test within 1e-9 m of the reference's domain count as inside.
/// @throw CompareError when no test vertex lies in the reference's material domain.
SheetDifference compare_sheets(const SheetGeometry& reference, const SheetGeometry& test);

}  // namespace papersim::validation
