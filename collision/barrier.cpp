#include "collision/barrier.hpp"

#include <cmath>
#include <limits>

namespace papersim::collision {

// Li et al. 2020, eq. 6: b(d) = -(d - dhat)^2 ln(d / dhat).
double barrier(double d, double dhat) {
  if (d <= 0.0) return std::numeric_limits<double>::infinity();
  if (d >= dhat) return 0.0;
  const double s = d - dhat;
  return -s * s * std::log(d / dhat);
}

// b'(d) = (dhat - d) (2 ln(d/dhat) - dhat/d + 1).
double barrier_first_derivative(double d, double dhat) {
  if (d <= 0.0) return -std::numeric_limits<double>::infinity();
  if (d >= dhat) return 0.0;
  return (dhat - d) * (2.0 * std::log(d / dhat) - dhat / d + 1.0);
}

// b''(d) = -2 ln(d/dhat) + (dhat - d)(3 d + dhat) / d^2.
double barrier_second_derivative(double d, double dhat) {
  if (d <= 0.0) return std::numeric_limits<double>::infinity();
  if (d >= dhat) return 0.0;
  return -2.0 * std::log(d / dhat) + (dhat - d) * (3.0 * d + dhat) / (d * d);
}

// Li et al. 2020, eq. 14 (smoothed Coulomb magnitude).
double friction_f1(double y, double eps) {
  if (y >= eps) return 1.0;
  return y * (2.0 / eps - y / (eps * eps));
}

double friction_f1_over_y(double y, double eps) {
  if (y >= eps) return 1.0 / y;
  return 2.0 / eps - y / (eps * eps);
}

// (f1'(y) y - f1(y)) / y^3: -1/(eps^2 y) below eps, -1/y^3 above. Singular at y = 0, but the
// caller multiplies it by u u^T with |u| = y, so the product vanishes there: return 0.
double friction_f2_term(double y, double eps) {
  if (y <= 0.0) return 0.0;
  if (y >= eps) return -1.0 / (y * y * y);
  return -1.0 / (eps * eps * y);
}

// Integral of f1 with f0(y) = y for y >= eps (continuous at eps), Li et al. 2020, eq. 15.
double friction_f0(double y, double eps) {
  if (y >= eps) return y;
  return -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0;
}

Eigen::Matrix2d friction_hessian(const Eigen::Vector2d& u, double eps) {
  const double y = u.norm();
  Eigen::Matrix2d h = friction_f1_over_y(y, eps) * Eigen::Matrix2d::Identity();
  if (y > 0.0) h += friction_f2_term(y, eps) * (u * u.transpose());
  return h;
}

Eigen::Vector2d friction_gradient(const Eigen::Vector2d& u, double eps) {
  return friction_f1_over_y(u.norm(), eps) * u;
}

}  // namespace papersim::collision
