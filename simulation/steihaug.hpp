#pragma once
/// Steihaug-Toint truncated conjugate gradients (Steihaug 1983; Nocedal and Wright, Numerical
/// Optimization, 2nd ed., Algorithm 7.2): approximately minimises the quadratic model
/// m(z) = -b.z + z.H z / 2 of a symmetric, possibly indefinite H in the trust region
/// ||z||_M <= radius, with a symmetric positive definite preconditioner M given by its inverse.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace papersim::simulation {

struct SteihaugResult {
  Eigen::VectorXd z;
  int iterations = 0;  ///< products with H
  enum class End { converged, negative_curvature, boundary, iterations } end = End::converged;
  double model = 0;  ///< m(z) - m(0) [energy]
};

/// @param multiply_h  v -> H v
/// @param multiply_m  v -> M v (for the trust region's norm)
/// @param solve_m     v -> M^-1 v
/// @param y0          M^-1 b, already known to the caller (the preconditioned first direction)
/// @param eta         stop when the residual's M^-1 norm falls below eta times its start
/// The first iterate is y0 scaled to H's curvature along it; with radius >= ||y0||_M and H = M
/// the result is y0 after one iteration. Every iterate lowers the model, so the result is a
/// descent direction of the function whose gradient is -b.
template <class MultiplyH, class MultiplyM, class SolveM>
SteihaugResult steihaug(MultiplyH&& multiply_h, MultiplyM&& multiply_m, SolveM&& solve_m,
                        const Eigen::VectorXd& b, const Eigen::VectorXd& y0, double radius,
                        int max_iterations, double eta) {
  SteihaugResult out;
  Eigen::VectorXd z = Eigen::VectorXd::Zero(b.size()), r = b, y = y0, d = y0;
  double ry = r.dot(y);
  const double ry0 = ry;
  // The step tau >= 0 along d to the boundary ||z + tau d||_M = radius (z is inside).
  const auto to_boundary = [&] {
    const Eigen::VectorXd md = multiply_m(d);
    const double a = d.dot(md), half_b = z.dot(md), c = z.dot(multiply_m(z)) - radius * radius;
    if (!(a > 0)) return 0.0;  // d has no length in the M norm: stay at z
    return (-half_b + std::sqrt(std::max(0.0, half_b * half_b - a * c))) / a;
  };
  for (int j = 0; j < max_iterations; ++j) {
    out.iterations = j + 1;
    const Eigen::VectorXd hd = multiply_h(d);
    const double kappa = d.dot(hd);
    if (kappa <= 0) {
      z += to_boundary() * d;
      out.end = SteihaugResult::End::negative_curvature;
      break;
    }
    const double alpha = ry / kappa;
    const Eigen::VectorXd z_next = z + alpha * d;
    if (z_next.dot(multiply_m(z_next)) >= radius * radius) {
      z += to_boundary() * d;
      out.end = SteihaugResult::End::boundary;
      break;
    }
    z = z_next;
    r -= alpha * hd;
    y = solve_m(r);
    const double ry_next = r.dot(y);
    if (ry_next <= eta * eta * ry0) break;
    if (j + 1 == max_iterations) {
      out.end = SteihaugResult::End::iterations;
      break;
    }
    d = y + (ry_next / ry) * d;
    ry = ry_next;
  }
  out.model = -b.dot(z) + 0.5 * z.dot(multiply_h(z));
  out.z = std::move(z);
  return out;
}

}  // namespace papersim::simulation
