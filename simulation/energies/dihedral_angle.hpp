#pragma once
/// Signed dihedral angle of a hinge (two triangles sharing an edge) and its exact first and
/// second derivatives, in closed form. The value/gradient follow Bridson, Marino & Fedkiw 2003
/// ("Simulation of clothing with folds and wrinkles", SCA 2003: the bending-force directions
/// u_1..u_4) and Tamstorf & Grinspun 2013 ("Discrete bending forces and their Jacobians",
/// Graphical Models 75(6)); the Hessian is derived in full in dihedral_angle.cpp.
///
/// Hinge layout: x0, x1 span the shared edge e = x1 - x0; xa and xb are the opposite vertices.
/// Face A = (x0, x1, xa) and face B = (x1, x0, xb), each counter-clockwise seen from its normal
///   n_a = (x1 - x0) x (xa - x0) / |..|,   n_b = (x0 - x1) x (xb - x1) / |..|.
/// theta = 0 when the hinge is flat, theta > 0 when xb lies on the side of n_a (the hinge folds
/// towards the normals: a valley seen from the normal side), |theta| = pi - interior angle.
/// theta is in (-pi, pi]; it jumps by 2 pi when the two faces pass through each other.
///
/// Preconditions: both faces have non-zero area (|e x (xa - x0)| > 0 and |e x (xb - x0)| > 0).
/// Nothing is checked, for speed: on a degenerate hinge theta is still finite (the atan2 of
/// zeros), but gradient and Hessian contain inf/NaN, since they scale as 1/height and
/// 1/height^2. Callers that can meet collapsed triangles should test the face areas first
/// (or check the assembled system for finiteness).
#include <Eigen/Core>

namespace papersim::simulation {

/// Signed dihedral angle [rad] in (-pi, pi] of the hinge (x0, x1, xa, xb) (positions [m]).
double dihedral_angle(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                      const Eigen::Vector3d& xa, const Eigen::Vector3d& xb);

/// Gradient of dihedral_angle with respect to (x0, x1, xa, xb) stacked, 12 x 1 [rad/m].
Eigen::Matrix<double, 12, 1> dihedral_angle_gradient(const Eigen::Vector3d& x0,
                                                     const Eigen::Vector3d& x1,
                                                     const Eigen::Vector3d& xa,
                                                     const Eigen::Vector3d& xb);

/// Exact Hessian of dihedral_angle with respect to (x0, x1, xa, xb) stacked, 12 x 12, exactly
/// symmetric (bit for bit) [rad/m^2]. Indefinite in general: project before use in Newton.
Eigen::Matrix<double, 12, 12> dihedral_angle_hessian(const Eigen::Vector3d& x0,
                                                     const Eigen::Vector3d& x1,
                                                     const Eigen::Vector3d& xa,
                                                     const Eigen::Vector3d& xb);

/// Value, gradient and Hessian at once, sharing the work (for the solver's hot loop).
/// theta [rad] is always written; grad (12 x 1 [rad/m]) and hess (12 x 12 [rad/m^2]) are
/// written only when non-null, so a caller that needs value and gradient skips the Hessian.
void dihedral_angle_derivatives(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                const Eigen::Vector3d& xa, const Eigen::Vector3d& xb, double& theta,
                                Eigen::Matrix<double, 12, 1>* grad,
                                Eigen::Matrix<double, 12, 12>* hess);

}  // namespace papersim::simulation
