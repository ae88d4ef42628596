#pragma once
/// Per-vertex terms of the incremental potential, with lumped masses m_v = rho_A A_v.
///   inertia  1/(2 h^2) |x - x_pred|^2_M, x_pred = x_t0 + h v_t0   (backward Euler)
///   damping  c/(2 h)   |x - x_t0|^2_M                              (drag force -c m v)
///   gravity  -sum_v m_v g . x_v
#include "simulation/energies/energy_term.hpp"

namespace papersim::simulation {

/// Lumped vertex masses [kg]: a third of each incident face's material area times rho_A.
Eigen::VectorXd lumped_masses(const Eigen::MatrixX2d& material_coords,
                              const Eigen::MatrixX3i& faces, double density);

class InertiaEnergy : public EnergyTerm {
 public:
  explicit InertiaEnergy(Eigen::VectorXd masses) : m_mass(std::move(masses)) {}
  std::string name() const override { return "inertia"; }
  void add_pattern(SparsityBuilder&) const override {}
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;

 private:
  Eigen::VectorXd m_mass, m_x_pred;
  double m_h = 1e-3;
};

class DampingEnergy : public EnergyTerm {
 public:
  /// @param coefficient c [1/s]
  DampingEnergy(Eigen::VectorXd masses, double coefficient)
      : m_mass(std::move(masses)), m_c(coefficient) {}
  std::string name() const override { return "damping"; }
  void add_pattern(SparsityBuilder&) const override {}
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;

 private:
  Eigen::VectorXd m_mass, m_x_t0;
  double m_c, m_h = 1e-3;
};

class GravityEnergy : public EnergyTerm {
 public:
  /// @param gravity [m/s^2]
  GravityEnergy(Eigen::VectorXd masses, const Eigen::Vector3d& gravity)
      : m_mass(std::move(masses)), m_g(gravity) {}
  std::string name() const override { return "gravity"; }
  void add_pattern(SparsityBuilder&) const override {}
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;

 private:
  Eigen::VectorXd m_mass;
  Eigen::Vector3d m_g;
};

}  // namespace papersim::simulation
