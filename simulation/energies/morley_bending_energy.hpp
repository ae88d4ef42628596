#pragma once
/// Bending energy, Morley model: the Morley plate on any triangle mesh (nonlinear, with hinge
/// angles).
///
/// Per face f, a constant curvature tensor K_f (2x2 symmetric, material coordinates, Voigt
/// (K_xx, K_yy, K_xy) [1/m]) follows from one slope unknown s per edge: for the edge
/// (p_i, p_j) of f with opposite corner p_k, height h and the material outward normal n, every
/// quadratic height field z with Hessian K satisfies
///   dz/dn(edge midpoint) - grad(I_f z) . n = a^T K b / (2 h) =: R_f,k . K,  a = p_k - p_i,
///   b = p_k - p_j,
/// with I_f z the face's linear interpolant, so K_f = R_f^-1 s_f is exact for every quadratic
/// on every triangle: no grain, no dependence on orientation, no stencil and no soft modes.
/// The slopes of the two faces of an interior hinge add up to its dihedral angle theta (the
/// slope jump of the two linear interpolants), so the unknown per hinge is the split psi:
///   s_f = theta / 2 + psi,  s_g = theta / 2 - psi,
/// and per boundary edge the slope itself, s = psi. The energy is the plate energy
///   E(x) = min_psi sum_f A_f D_f / 2 [(1 - nu) |K_f - Kp_f|^2 + nu tr(K_f - Kp_f)^2]
///          + boundary terms,
/// with Kp_f the plastic curvature and D_f = D / (1 + weakening damage_f) (Narain et al.
/// 2013). It is a quadratic in (theta, psi) with coefficients fixed by the rest shape, so
/// psi*(theta) comes from one sparse solve with a matrix factored once, and by the envelope
/// theorem the gradient is sum_h dE/dtheta_h grad theta_h at psi*.
///
/// Boundary edges: a free boundary slope is the natural boundary condition (no moment across
/// the edge), right for a minimiser but it lets the energy of an imposed shape lose the
/// curvature only that slope sees (a cylinder on a 10 x 15 cm sheet at 5 mm: 2-5% low). A stiff
/// penalty ties each boundary slope to the slope the mean elastic curvature of the face's
/// interior neighbours gives there (the cylinder then within 2%, docs/elastica_30deg_diagnosis.md
/// section 5). Clamped faces (all corners held by a clamp) keep their slopes: s = 0 on their
/// edges, so the face across takes the whole angle.
///
/// Hessian: the psi are auxiliary unknowns of the Newton system (EnergyTerm::auxiliary_blocks):
/// the Gauss-Newton part of (x, psi) is sum over elements of [J_theta, I_psi]^T M [J_theta,
/// I_psi], PSD by construction, and its Schur complement on x is the condensed energy's. The
/// curvature part sum_h dE/dtheta_h Hess theta_h is added only with `exact_hessian` (projected
/// to PSD per hinge with `projected`), being O(theta) relative to the first.
/// `BendingHessian::exact` (unprojected) is for finite-difference tests.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/material.hpp"

namespace papersim::simulation {

class MorleyBendingEnergy final : public BendingEnergy {
 public:
  /// @param clamped_faces faces held rigidly, slopes included (a clamp's jaws).
  MorleyBendingEnergy(const remesh::SheetMesh& mesh, const Material& material,
                      BendingHessian hessian = BendingHessian::gauss_newton,
                      const std::vector<int>& clamped_faces = {});
  ~MorleyBendingEnergy() override;

  void add_pattern(SparsityBuilder& pattern) const override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;
  int auxiliary_blocks() const override { return (m_num_psi + 2) / 3; }
  void set_auxiliary_offset(int first_block) override { m_first_block = first_block; }

  /// Curvature tensor of every face at x, #F by 3 (K_xx, K_yy, K_xy) [1/m] (clamped faces:
  /// their plastic curvature).
  Eigen::MatrixX3d face_curvatures(const Eigen::VectorXd& x) const override;

  /// Curvature for the plastic return mapping, #F by 3 [1/m]: the least-squares fit of the hinge
  /// angles of the fit model (FitBendingEnergy::face_curvatures: exact for every constant
  /// curvature, a function of the shape alone); clamped faces report their plastic curvature.
  /// The condensed K_f of face_curvatures is not used: the slopes psi* move with the plastic
  /// state, so at a held shape a face that yielded draws the curvature of its neighbours and
  /// plastic flow localises face by face (measured: a 4 x 1 cm strip held at 2 k_y ended with
  /// plastic curvature 0 to 3x the expected value on alternate faces).
  Eigen::MatrixX3d yield_curvatures(const Eigen::VectorXd& x) const override;

  /// Replace the plastic state (#F by 3 curvature [1/m], #F damage). A change of plastic
  /// curvature alone updates the right-hand side of the slope system; a change of damage (so of
  /// stiffness) re-factors it numerically, reusing the symbolic analysis.
  /// @throw NumericError when the slope system cannot be factored
  void set_plastic_state(const Eigen::MatrixX3d& plastic_curvature,
                         const Eigen::VectorXd& damage) override;

  /// Numeric factorisations of the slope system so far (one at construction) [-].
  long factorizations() const { return m_factorizations; }

 private:
  /// A quadratic element: r = L (theta_ids, psi_ids) - c, energy r^T W r / 2.
  struct Element {
    std::vector<int> theta;                 // hinge indices
    std::vector<int> psi;                   // slope unknowns
    Eigen::MatrixXd L;                      // rows x (|theta| + |psi|)
    Eigen::VectorXd c;                      // offset (plastic curvature)
    Eigen::MatrixXd W;                      // rows x rows
    std::vector<int> vertices;              // union of the hinges' vertices (local order)
    std::vector<std::array<int, 4>> local;  // per hinge: local index of (v0, v1, a, b)
    std::vector<int> blocks;  // auxiliary blocks of the psi (local order, after the vertices)
    std::vector<std::pair<int, int>> psi_at;  // per psi: (local block, component)
    Eigen::MatrixXd M;                        // L^T W L
  };
  struct Face {
    Eigen::Matrix3d R, Rinv;  // R K = s
    int hinge[3] = {-1, -1, -1};
    double alpha[3] = {0, 0, 0};  // s_k = alpha_k theta + sigma_k psi
    int psi[3] = {-1, -1, -1};
    double sigma[3] = {0, 0, 0};
    double area = 0;
    bool clamped = false;
  };
  struct Factor;

  struct Penalty {
    int face = -1, edge = -1;     // the boundary edge (local index) it ties
    std::vector<int> neighbours;  // unclamped faces across the face's interior edges
  };
  /// Renumbers the slopes so that each 3x3 block holds slopes of one face where possible.
  void pack_slopes();
  void build_elements();
  /// Element weights from the faces' stiffness; assembles and factors C, A_psi_theta.
  void update_weights();
  /// Element offsets from the plastic curvature and the right-hand side b_psi.
  void update_offsets();
  /// theta and psi*(theta) at x.
  void unknowns(const Eigen::VectorXd& x, Eigen::VectorXd& theta, Eigen::VectorXd& psi) const;
  /// Element vectors without heap allocation: an element has at most 3 residual rows and
  /// MAX_ELEMENT_UNKNOWNS unknowns (checked in build_elements).
  static constexpr int MAX_ELEMENT_UNKNOWNS = 32;
  using ElementVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, MAX_ELEMENT_UNKNOWNS, 1>;
  ElementVector element_residual(const Element& e, const Eigen::VectorXd& theta,
                                 const Eigen::VectorXd& psi) const;

  std::vector<Face> m_faces;
  std::vector<Element> m_elements;   // one per unclamped face, then the boundary penalties
  std::vector<int> m_face_element;   // face -> its element, -1 for clamped faces
  std::vector<Penalty> m_penalties;  // element m_num_face_elements + i
  int m_num_face_elements = 0;
  std::vector<Eigen::Vector3d> m_plastic;
  std::vector<double> m_stiffness;            // A_f D_f
  Eigen::SparseMatrix<double> m_A_psi_theta;  // d2E / dpsi dtheta
  Eigen::VectorXd m_b_psi;                    // C psi* = b_psi - A_psi_theta theta
  std::unique_ptr<Factor> m_C;
  std::unique_ptr<BendingEnergy> m_measure;  // the fit model's curvature, for yield_curvatures
  int m_num_psi = 0;
  int m_first_block = -1;
  long m_factorizations = 0;
  mutable ElementSlots m_slots;  // the elements' places in the Hessian
};

}  // namespace papersim::simulation
