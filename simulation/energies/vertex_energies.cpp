#include "simulation/energies/vertex_energies.hpp"

#include <cmath>

namespace papersim::simulation {

Eigen::VectorXd lumped_masses(const Eigen::MatrixX2d& X, const Eigen::MatrixX3i& F,
                              double density) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(X.rows());
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector2d e1 = X.row(F(f, 1)) - X.row(F(f, 0));
    const Eigen::Vector2d e2 = X.row(F(f, 2)) - X.row(F(f, 0));
    const double a = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    for (int k = 0; k < 3; ++k) m[F(f, k)] += density * a / 3;
  }
  return m;
}

void InertiaEnergy::begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) {
  m_h = ctx.h;
  m_x_pred = x_t0 + ctx.h * (*ctx.v_t0);
}

double InertiaEnergy::value(const Eigen::VectorXd& x) const {
  double e = 0;
  for (int v = 0; v < m_mass.size(); ++v)
    e += m_mass[v] * (x.segment<3>(3 * v) - m_x_pred.segment<3>(3 * v)).squaredNorm();
  return 0.5 * e / (m_h * m_h);
}

void InertiaEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& g,
                                    BlockSymmetricMatrix* H,
                                    HessianProjection /*projection*/) const {
  Eigen::VectorXd d(3 * m_mass.size());  // the sheet's entries (x may hold rigid blocks after them)
  for (int v = 0; v < m_mass.size(); ++v) {
    const double k = m_mass[v] / (m_h * m_h);
    g.segment<3>(3 * v) += k * (x.segment<3>(3 * v) - m_x_pred.segment<3>(3 * v));
    d.segment<3>(3 * v).setConstant(k);
  }
  if (H) H->add_diagonal(d);
}

void DampingEnergy::begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) {
  m_h = ctx.h;
  m_x_t0 = x_t0;
}

double DampingEnergy::value(const Eigen::VectorXd& x) const {
  double e = 0;
  for (int v = 0; v < m_mass.size(); ++v)
    e += m_mass[v] * (x.segment<3>(3 * v) - m_x_t0.segment<3>(3 * v)).squaredNorm();
  return 0.5 * m_c * e / m_h;
}

void DampingEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& g,
                                    BlockSymmetricMatrix* H,
                                    HessianProjection /*projection*/) const {
  Eigen::VectorXd d(3 * m_mass.size());  // the sheet's entries (x may hold rigid blocks after them)
  for (int v = 0; v < m_mass.size(); ++v) {
    const double k = m_c * m_mass[v] / m_h;
    g.segment<3>(3 * v) += k * (x.segment<3>(3 * v) - m_x_t0.segment<3>(3 * v));
    d.segment<3>(3 * v).setConstant(k);
  }
  if (H) H->add_diagonal(d);
}

double GravityEnergy::value(const Eigen::VectorXd& x) const {
  double e = 0;
  for (int v = 0; v < m_mass.size(); ++v) e -= m_mass[v] * m_g.dot(x.segment<3>(3 * v));
  return e;
}

void GravityEnergy::add_derivatives(const Eigen::VectorXd&, Eigen::VectorXd& g,
                                    BlockSymmetricMatrix*, HessianProjection /*projection*/) const {
  for (int v = 0; v < m_mass.size(); ++v) g.segment<3>(3 * v) -= m_mass[v] * m_g;
}

}  // namespace papersim::simulation
