#pragma once
/// The pieces of the sizing metric of Narain, Samii, O'Brien 2012 (section 4), each a 2 x 2
/// symmetric tensor in material space [1/m^2]; remesh.hpp declares sizing(), which combines them.
#include <Eigen/Core>
#include <vector>

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
/// / (2 c^2), with e = (F^T F - I) / 2 the Green strain [-], curvature2 = S^T S [1/m^2] and
/// c = refine_compression [m]; it asks for edges l with l^2 |e| <= c^2 along compressed
/// directions, less where the face is already bent there.
Eigen::Matrix2d compression_metric(const Eigen::Matrix2d& green_strain,
                                   const Eigen::Matrix2d& curvature2, double c);

/// The compression metric at the resolution of a face (Narain et al. 2012 resolve the buckles
/// that compression makes; a mesh resolves a buckle only as fine as its own edges). Along each
/// eigendirection d of `arcsim` (compression_metric, eigenvalue mu, asking for l_a = 1/sqrt(mu))
/// the face spans h = max_i |u_i . d| over its material edges u_i (#columns of `edges`, [m]).
/// The compression the face holds is what its edges could not turn into bending: a buckle of
/// the shortest wavelength the face can carry, 2 h, taking up Green strain G = c^2 / l_a^2 has
/// peak curvature 2 pi sqrt(G) / h, and spans the dihedral angle `angle` per edge on edges
///   l = angle h / (2 pi sqrt(G)) = l_a angle h / (2 pi c).
/// The metric asks for the longer of l_a and l: so it refines a face only when its compression
/// is more than it could turn into a buckle with edges that each span `angle` (G >
/// (angle / 2 pi)^2, 1.0e-3 at 0.2 rad), and by the factor that buckle needs rather than to
/// buckles of amplitude c at once; on faces finer than 2 pi c / angle (3.1 mm at the
/// defaults) it is ArcSim's metric unchanged.
Eigen::Matrix2d compression_metric_at_resolution(const Eigen::Matrix2d& arcsim,
                                                 const Eigen::Matrix<double, 2, 3>& edges, double c,
                                                 double angle);

/// The anisotropic maximum of symmetric positive semi-definite 2 x 2 tensors: the smallest-trace
/// tensor M with M >= M_i for every i (ArcSim's tensor_max: writing M = r I + a diag(1, -1)
/// + b [[0, 1], [1, 0]], M >= M_i exactly when disk (a_i, b_i; r_i) lies inside disk (a, b; r), so
/// M is the smallest disk enclosing the disks). Zero for an empty list or all-zero tensors.
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
