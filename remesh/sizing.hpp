#pragma once
/// The pieces of the sizing metric of Narain, Samii, O'Brien 2012 (section 4), each a 2 x 2
/// symmetric tensor in material space [1/m^2]; remesh.hpp declares sizing(), which combines them.
#include <vector>

#include <Eigen/Core>

#include "remesh/remesh.hpp"
#include "remesh/sheet_mesh.hpp"

namespace papersim::remesh {

/// Signed dihedral angle [rad] of every edge of the mesh at world positions `positions` (#V by 3),
/// indexed by OpenMesh edge index; 0 on boundary edges and where a face is degenerate in world
/// space (zero-length or collinear edges).
std::vector<double> edge_dihedral_angles(const SheetMesh& mesh, const Eigen::MatrixX3d& positions);

/// Discrete curvature (shape operator) of face f in material coordinates [1/m] from the dihedral
/// angles of its edges: S = sum_e theta_e |e| t_e t_e^T / (2 A), t_e the in-plane unit normal of
/// edge e and A the face's material area (Narain et al. 2012, eq. 5).
Eigen::Matrix2d face_curvature(const SheetMesh& mesh, int f, const std::vector<double>& angles);

/// ArcSim's compression metric [1/m^2]: the positive part of (-e + sqrt(e^T e - 4 c^2 adj(S^T S)))
/// / (2 c^2), with e = F^T F - I the Green strain (times 2) [-], curvature2 = S^T S [1/m^2] and
/// c = refine_compression [m]; it asks for edges l with l^2 |e| <= c^2 along compressed
/// directions, less where the face is already bent there.
Eigen::Matrix2d compression_metric(const Eigen::Matrix2d& green_strain,
                                   const Eigen::Matrix2d& curvature2, double c);

/// The anisotropic maximum of symmetric positive semi-definite 2 x 2 tensors: the smallest-trace
/// tensor M with M >= M_i for every i (ArcSim's tensor_max: writing M = r I + a diag(1, -1)
/// + b [[0, 1], [1, 0]], M >= M_i exactly when disk (a_i, b_i; r_i) lies inside disk (a, b; r), so M
/// is the smallest disk enclosing the disks). Zero for an empty list or all-zero tensors.
Eigen::Matrix2d tensor_max(const std::vector<Eigen::Matrix2d>& tensors);

/// Clamps the eigenvalues of a metric to [1/size_max^2, 1/size_min^2], then raises the smaller one
/// to at least aspect_min^2 times the larger.
Eigen::Matrix2d clamp_metric(const Eigen::Matrix2d& metric, const RemeshParams& params);

/// Per-vertex metric: the material-area-weighted mean of the metrics of the faces around it.
std::vector<Eigen::Matrix2d> vertex_metrics(const SheetMesh& mesh,
                                            const std::vector<Eigen::Matrix2d>& face_metrics);

/// Aspect ratio of a triangle [-]: 12 sqrt(3) area / perimeter^2 (1 for an equilateral triangle,
/// 0 for a degenerate one; negative when clockwise).
double aspect_ratio(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

}  // namespace papersim::remesh
