#pragma once
/// Smooth contact and friction functions shared by obstacle and self contact
/// (Li et al. 2020, "Incremental Potential Contact", eqs. 6 and 14-15).

namespace papersim::collision {

/// IPC log barrier b(d) = -(d - dhat)^2 ln(d / dhat) for 0 < d < dhat, 0 for d >= dhat,
/// +inf for d <= 0. d and dhat in metres; b is dimensionless (scale by a stiffness).
double barrier(double d, double dhat);
/// db/dd [1/m].
double barrier_first_derivative(double d, double dhat);
/// d2b/dd2 [1/m^2].
double barrier_second_derivative(double d, double dhat);

/// Smoothed friction magnitude of IPC: f1(y) = -y^2/eps^2 + 2 y/eps for y < eps, 1 after;
/// y a tangential displacement [m], eps the static-slip threshold [m].
double friction_f1(double y, double eps);
/// f1(y) / y, finite at y = 0 [1/m].
double friction_f1_over_y(double y, double eps);
/// d/dy (f1(y) / y) * (1 / y) used for the friction Hessian [1/m^3].
double friction_f2_term(double y, double eps);
/// The friction potential's y-integral f0 with f0' = f1, f0(eps) = eps/3 [m].
double friction_f0(double y, double eps);

}  // namespace papersim::collision
