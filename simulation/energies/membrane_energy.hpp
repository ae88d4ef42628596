#pragma once
/// In-plane energy of constant-strain triangles: St. Venant-Kirchhoff stretching with the
/// paper's Eh and Poisson ratio (plane stress), plus the hard strain limit as a barrier on the
/// eigenvalues of the right Cauchy-Green tensor C = F^T F (F the 3x2 deformation gradient
/// relative to material coordinates).
///
/// Strain limit: E_limit = kappa A sum_i b(L - lambda_i(C)) with L = (1 + eps)^2 and b the IPC
/// log barrier, active once a principal stretch exceeds 1 + eps/2. The energy is infinite at
/// the limit, so a line search that rejects infinite energy never accepts a step past it. Being
/// a sum of a convex function of the eigenvalues, it is convex in C (Davis 1957), so its
/// Hessian in C is PSD and needs no projection.
///
/// Compression limit (`compression_limit`, off by default): E_comp = kappa A sum_i
/// b(lambda_i(C) - Lc) with Lc = (1 - eps_c)^2, active once a principal stretch falls below
/// 1 - eps_c/2, infinite at 1 - eps_c; convex in C as well (b convex and decreasing of the
/// concave lambda_min).
///
/// Element Hessians: J^T (d2W/dC2) J plus the geometric term (dW/dC contracted with the second
/// derivatives of C), exact. The geometric term is indefinite where dW/dC is (compression, or
/// the compression barrier's push); there the 9x9 element matrix is projected to PSD unless
/// the integrator asks for the exact Hessian (set_hessian_projection).
#include <array>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/energies/energy_term.hpp"
#include "simulation/material.hpp"

namespace papersim::simulation {

class MembraneEnergy : public EnergyTerm {
 public:
  /// @param material_coords #V by 2 [m]; faces #F by 3 counter-clockwise.
  MembraneEnergy(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces,
                 const Material& material);

  std::string name() const override { return "membrane"; }
  void add_pattern(SparsityBuilder& pattern) const override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian) const override;

  /// Principal stretches (s1 >= s2) of every face at x, #F by 2.
  Eigen::MatrixX2d principal_stretches(const Eigen::VectorXd& x) const;

  /// Energy, gradient and PSD Hessian of one triangle (x0, x1, x2 stacked).
  double element(int f, const Eigen::Matrix<double, 9, 1>& xs, Eigen::Matrix<double, 9, 1>* g,
                 Eigen::Matrix<double, 9, 9>* H) const;

  bool limit_enabled() const { return m_limit > 0 || m_limit_low > 0; }
  void set_hessian_projection(bool project) override { m_project = project; }

 private:
  struct Triangle {
    std::array<int, 3> v;
    Eigen::Matrix<double, 3, 2> w;  // F = sum_i x_i w_i^T (row i = w_i)
    double area;                    // rest area [m^2]
  };
  std::vector<Triangle> m_tris;
  double m_lambda, m_mu;   // plane-stress Lame parameters x thickness [N/m]
  double m_limit;          // L = (1 + eps)^2, 0 when disabled
  double m_dhat;           // barrier activation distance in lambda
  double m_limit_low = 0;  // Lc = (1 - compression_limit)^2, 0 when disabled
  double m_dhat_low = 0;   // its activation distance in lambda
  double m_kappa;          // barrier stiffness [J/m^2]
  bool m_project = true;   // element Hessians projected to PSD under compression
};

}  // namespace papersim::simulation
