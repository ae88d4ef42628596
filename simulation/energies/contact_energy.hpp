#pragma once
/// Contact of sheet vertices with obstacles (signed distance fields) and Coulomb friction.
///
/// Contact: E = sum_v sum_o kappa A_v b(phi_o(x_v), dhat) with the IPC log barrier b
/// (Li et al. 2020, eq. 6); kappa = stiffness / dhat, so that the contact pressure at gap d is
/// stiffness |b'(d)| / dhat: `stiffness` is the pressure at about half the thickness [Pa]. A
/// sheet resting under its weight rho_A g with stiffness = rho_A g sits at about 0.55 dhat. The Hessian keeps b'' grad phi grad phi^T and drops b' Hess phi (exact for planes; for
/// curved obstacles the dropped term is the obstacle curvature times the contact force).
/// Friction (lagged per time step, IPC eqs. 14-16): normal force magnitudes and tangent bases
/// are frozen at the step start; the tangential slip u = T^T (x - x_t0 - h v_obstacle) pays
/// mu lambda f0(|u|), with f0 the C1 smoothing of |u| below eps_v h.
/// CCD: along the segment x_v -> x_v + a dx_v, a point cannot reach an obstacle before it moved
/// by its distance phi (phi is 1-Lipschitz); sphere tracing gives a conservative largest a.
#include <memory>
#include <vector>

#include "collision/collider.hpp"
#include "simulation/energies/energy_term.hpp"

namespace papersim::simulation {

struct ContactParams {
  double dhat = 3e-4;          ///< barrier activation distance (contact thickness) [m]
  double stiffness = 1.0;      ///< pressure scale of the barrier [Pa] (see above)
  double eps_velocity = 1e-3;  ///< slip speed below which friction is static-like [m/s]
};

class ObstacleContactEnergy : public EnergyTerm {
 public:
  /// @param vertex_areas material area per vertex [m^2] (a third of the incident faces)
  ObstacleContactEnergy(Eigen::VectorXd vertex_areas,
                        std::vector<std::shared_ptr<const collision::Collider>> obstacles,
                        const ContactParams& params);

  std::string name() const override { return "contact"; }
  void add_pattern(SparsityBuilder&) const override {}
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian) const override;
  double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;

  /// Smallest signed distance of any vertex to obstacle o at the end-of-step time [m].
  double min_distance(int o, const Eigen::VectorXd& x) const;
  /// Number of vertices with friction active in the current step.
  int active_friction() const { return static_cast<int>(m_friction.size()); }
  /// Sum of normal contact force magnitudes at the step start [N].
  double normal_force() const { return m_normal_force; }
  int num_obstacles() const { return static_cast<int>(m_obstacles.size()); }

 private:
  struct FrictionPoint {
    int vertex, obstacle;
    double mu_lambda;                  // mu x normal force [N]
    Eigen::Matrix<double, 3, 2> T;     // tangent basis
    Eigen::Vector3d origin;            // x_t0 + h v_obstacle [m]
  };
  bool near_bounds(int o, const Eigen::Vector3d& p) const;
  double kappa(int v) const { return m_params.stiffness / m_params.dhat * m_area[v]; }

  Eigen::VectorXd m_area;
  std::vector<std::shared_ptr<const collision::Collider>> m_obstacles;
  ContactParams m_params;
  std::vector<collision::Aabb> m_bounds;  // at the step end, inflated by dhat
  std::vector<FrictionPoint> m_friction;
  double m_t1 = 0.0, m_eps = 1e-6, m_normal_force = 0.0;
};

}  // namespace papersim::simulation
