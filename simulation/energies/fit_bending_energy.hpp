#pragma once
/// Bending energy, fit model: calibrated to the Kirchhoff plate for constant curvature on any mesh.
///
/// Per face f, a curvature tensor K_f (2x2 symmetric, material coordinates, Voigt
/// (K_xx, K_yy, K_xy) [1/m]) is fitted by least squares to the dihedral angles of a stencil of
/// hinges: the face's own interior edges and those of its edge neighbours (up to nine; boundary
/// faces add the hinges of faces sharing a vertex until K is determined). The map
/// from a constant curvature K to the angle of hinge (v0, v1, a, b) is exact for the quadratic
/// height field z = p^T K p / 2 over the material plane (small slopes):
///   theta = -1/2 sum_{i<j} l_i l_j (p_i - p_j)^T K (p_i - p_j) / h_b,
/// with l the barycentric coordinates of p_b in the triangle (p_0, p_1, p_a) and h_b the
/// distance of p_b from the hinge line. Stacking these rows gives B_f (|S| x 3) and
/// K_f = P_f theta with P_f = (B^T B)^-1 B^T, exact for every constant curvature field whatever
/// the triangulation (no grain, no dependence on orientation). The energy is the plate energy
///   E = sum_f A_f D_f / 2 [(1 - nu) |K_f - Kp_f|^2 + nu tr(K_f - Kp_f)^2 + |R_f theta|^2],
/// where the last term, the fit residual (I - B P) theta scaled to curvature units, vanishes
/// for every constant curvature and penalises angle patterns no smooth surface makes: without
/// it, per-face recovery admits soft hourglass modes (a strip sagged 1.5-3x too far).
/// with Kp_f the plastic curvature and D_f = D / (1 + weakening damage_f) (Narain et al. 2013).
///
/// Hessian: the Gauss-Newton part sum M_hk grad theta_h grad theta_k^T is PSD by construction;
/// the curvature part sum c_h Hess theta_h is added only with `exact_hessian` (then the element
/// matrix is projected to PSD by eigen-decomposition), because it is O(theta) relative to the
/// first and costs an eigen-decomposition per face. `BendingHessian::exact` (unprojected) is for
/// finite-difference tests.
#include <array>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/material.hpp"

namespace papersim::simulation {

class FitBendingEnergy final : public BendingEnergy {
 public:
  /// @throw NumericError when a face's stencil cannot determine its curvature (a mesh with
  ///        fewer than three interior edges).
  FitBendingEnergy(const remesh::SheetMesh& mesh, const Material& material,
                   BendingHessian hessian = BendingHessian::gauss_newton);

  void add_pattern(SparsityBuilder& pattern) const override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;

  /// Curvature tensor of every face at x, #F by 3 (K_xx, K_yy, K_xy) [1/m].
  Eigen::MatrixX3d face_curvatures(const Eigen::VectorXd& x) const override;

  /// Replace the plastic state (#F by 3 curvature [1/m], #F damage).
  void set_plastic_state(const Eigen::MatrixX3d& plastic_curvature,
                         const Eigen::VectorXd& damage) override;

 private:
  struct Face {
    std::vector<int> hinges;                // stencil hinges
    std::vector<int> vertices;              // union of their vertices (local order)
    std::vector<std::array<int, 4>> local;  // per hinge: local index of (v0, v1, a, b)
    Eigen::MatrixXd P;                      // 3 x |S|: K = P theta (least squares)
    Eigen::MatrixXd R;                      // |S| x |S|: scaled fit residual (hourglass control)
    Eigen::MatrixXd M;                      // |S| x |S|: P^T Q P + R^T R, d2E/dtheta2 / stiffness
    double area = 0;                        // [m^2]
    double stiffness = 0;                   // A D_f [N m^3]
    Eigen::Vector3d plastic = Eigen::Vector3d::Zero();
  };
  void build_stencil(int f, const CurvatureStencils& stencils, const Eigen::MatrixX3i& faces,
                     const Eigen::MatrixX2d& X);
  double face_energy(const Face& face, const Eigen::VectorXd& theta) const;

  std::vector<Face> m_faces;
  mutable ElementSlots m_slots;  // the faces' places in the Hessian
};

}  // namespace papersim::simulation
