#pragma once
/// A lifting obstacle as a body of the step (collision::LiftSpec::coupled): its displacement q
/// from where its motion puts it at the step start is a rigid block of the Newton system
/// (Integrator, rigid_blocks), and this term is its own part of the incremental potential:
///   inertia  M / (2 h^2) |q - q_t0 - h v_t0|^2          (backward Euler, M = weight / |g|)
///   weight   -M g . q
///   stop     k b(r + q_z + c, s)                          (IPC log barrier, s = 1 mm)
/// with r the obstacle's rise above its keyframed path when the run's step began (set_rise), so
/// that r + q_z > -c: the obstacle does not go below its path by more than c = 10 micrometres,
/// as a roller held on a stop. k = weight / |b'(c, s)|, so left alone it rests on the stop
/// exactly on its path (r + q_z = 0), and is pressed below it only by more than its weight. The
/// sheet's contact (ObstacleContactEnergy::set_rigid_block) adds the barrier forces between the
/// two, so a step ends with the obstacle where its weight, inertia and the sheet's push balance.
/// Only the vertical motion is free: nothing else acts on q_x and q_y, which start at rest and
/// stay there.
#include "simulation/energies/energy_term.hpp"

namespace papersim::simulation {

class LiftBodyEnergy : public EnergyTerm {
 public:
  /// @param block the body's block in the Newton system (after the sheet's vertices)
  /// @param weight [N] (> 0); @param gravity [m/s^2] (non-zero)
  LiftBodyEnergy(int block, double weight, const Eigen::Vector3d& gravity);
  std::string name() const override { return "lift_body"; }
  void add_pattern(SparsityBuilder& pattern) const override;
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;
  /// The stop: q_z may close 90% of its gap to the path.
  double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;

  /// Rise of the obstacle above its keyframed path at the start of the run's step [m] (> -REST).
  void set_rise(double rise) { m_rise = rise; }
  static constexpr double STOP = 1e-3;  ///< s, the stop barrier's activation distance [m]
  static constexpr double REST = 1e-5;  ///< c, the gap to the stop on the keyframed path [m]

 private:
  double gap(const Eigen::VectorXd& x) const { return m_rise + x[3 * m_block + 2] + REST; }
  int m_block;
  double m_mass, m_stop_kappa;
  Eigen::Vector3d m_gravity;
  Eigen::Vector3d m_pred = Eigen::Vector3d::Zero();
  double m_h = 1e-3, m_rise = 0.0;
};

}  // namespace papersim::simulation
