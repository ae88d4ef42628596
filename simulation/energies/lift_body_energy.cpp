#include "simulation/energies/lift_body_energy.hpp"

#include <algorithm>
#include <cmath>

#include "collision/barrier.hpp"
#include "common/assert.hpp"

namespace papersim::simulation {

LiftBodyEnergy::LiftBodyEnergy(int block, double weight, const Eigen::Vector3d& gravity)
    : m_block(block), m_gravity(gravity) {
  PAPERSIM_ASSERT(weight > 0 && gravity.norm() > 0,
                  "LiftBodyEnergy: weight and gravity must be non-zero");
  m_mass = weight / gravity.norm();
  m_stop_kappa = weight / -collision::barrier_first_derivative(REST, STOP);
}

void LiftBodyEnergy::add_pattern(SparsityBuilder& pattern) const {
  const int b[1] = {m_block};
  pattern.add_clique(b, 1);
}

void LiftBodyEnergy::begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) {
  m_h = ctx.h;
  m_pred = x_t0.segment<3>(3 * m_block) + ctx.h * ctx.v_t0->segment<3>(3 * m_block);
}

double LiftBodyEnergy::value(const Eigen::VectorXd& x) const {
  const Eigen::Vector3d q = x.segment<3>(3 * m_block);
  const double g = gap(x);
  if (!(g > 0)) return INF;
  double e = 0.5 * m_mass / (m_h * m_h) * (q - m_pred).squaredNorm() - m_mass * m_gravity.dot(q);
  if (g < STOP) e += m_stop_kappa * collision::barrier(g, STOP);
  return e;
}

void LiftBodyEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                                     BlockSymmetricMatrix* hessian,
                                     HessianProjection /*projection*/) const {
  const Eigen::Vector3d q = x.segment<3>(3 * m_block);
  const double k = m_mass / (m_h * m_h);
  Eigen::Vector3d grad = k * (q - m_pred) - m_mass * m_gravity;
  Eigen::Matrix3d hess = k * Eigen::Matrix3d::Identity();
  const double g = gap(x);
  if (g < STOP) {
    grad.z() += m_stop_kappa * collision::barrier_first_derivative(g, STOP);
    hess(2, 2) += m_stop_kappa * collision::barrier_second_derivative(g, STOP);
  }
  gradient.segment<3>(3 * m_block) += grad;
  if (hessian) hessian->add_element<1>({m_block}, hess);
}

double LiftBodyEnergy::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  const double rate = -dx[3 * m_block + 2];
  return rate > 0 ? std::min(1.0, 0.9 * gap(x) / rate) : 1.0;
}

}  // namespace papersim::simulation
