#pragma once
/// Smooth contact and friction functions shared by obstacle and self contact
/// (Li et al. 2020, "Incremental Potential Contact", eqs. 6 and 14-15).
#include <Eigen/Core>

namespace papersim::collision {

/// IPC log barrier b(d) = -(d - dhat)^2 ln(d / dhat) for 0 < d < dhat, 0 for d >= dhat,
/// +inf for d <= 0. d and dhat in metres; b is in m^2 (scale it by a stiffness [J/m^2]).
/// C2 at d = dhat (b, b', b'' all vanish there).
double barrier(double d, double dhat);
/// db/dd [m]; 0 for d >= dhat, -inf for d <= 0.
double barrier_first_derivative(double d, double dhat);
/// d2b/dd2 [-]; 0 for d >= dhat, +inf for d <= 0. Positive on (0, dhat).
double barrier_second_derivative(double d, double dhat);

/// Smoothed friction magnitude of IPC: f1(y) = -y^2/eps^2 + 2 y/eps for y < eps, 1 after;
/// y >= 0 a tangential displacement [m], eps > 0 the static-slip threshold [m]. [-]
double friction_f1(double y, double eps);
/// f1(y) / y, finite at y = 0 (= 2/eps) [1/m].
double friction_f1_over_y(double y, double eps);
/// (f1'(y) y - f1(y)) / y^3 = d/dy (f1(y) / y) * (1 / y), the rank-one part of the friction
/// Hessian [1/m^3]. Equals -1/(eps^2 y) for y < eps and -1/y^3 after; it is singular at y = 0
/// but always multiplied by u u^T with |u| = y, so 0 is returned for y <= 0 (the limit of the
/// product).
double friction_f2_term(double y, double eps);
/// The friction potential's y-integral f0 with f0' = f1, f0(y) = y for y >= eps, so
/// f0(0) = eps/3 and f0(eps) = eps [m] (Li et al. 2020, eq. 15).
double friction_f0(double y, double eps);

/// Gradient of f0(|u|) with respect to the 2-vector of tangential displacement u [m]:
/// f1(|u|)/|u| u [-]. The friction force of a contact is -mu lambda T * this.
Eigen::Vector2d friction_gradient(const Eigen::Vector2d& u, double eps);
/// Hessian of f0(|u|) with respect to u: f1/y I + (f1' y - f1)/y^3 u u^T [1/m]. It is
/// positive semi-definite for every u (eigenvalues f1/y and f1'(y) >= 0), so it needs no
/// projection; at u = 0 it is (2/eps) I.
Eigen::Matrix2d friction_hessian(const Eigen::Vector2d& u, double eps);

}  // namespace papersim::collision
