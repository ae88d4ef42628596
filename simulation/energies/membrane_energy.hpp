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
/// the caller asks for the exact Hessian (HessianProjection::none).
///
/// Arc model (Material::membrane_model `arc`): a flat triangle's edge is the chord of the
/// surface the bending discretisation describes, and on a surface of normal curvature k along
/// it the chord of an arc of length s is s (1 - k^2 s^2 / 24 + ...). Measured on chords, a mesh
/// bent smoothly across edges that do not run along the bend's axis is compressed by
/// (k l)^2 / 24, which no placement of its vertices removes: the stiff membrane then resists the
/// bend (membrane locking; docs/remeshing.md, "Membrane locking"). The arc model measures each
/// edge as the arc instead: its squared length is the chord's plus
///   delta_e = psi(s_e) L_e^4 k_e^2 / 12,
/// with L_e the material length, k_e = t_e^T K_e t_e the normal curvature along the material
/// direction t_e, and K_e the mean of the curvatures of the edge's faces, each fitted to the
/// hinge angles of its own edges (as the fit bending model does; its edge neighbours' hinges too
/// where the face's own do not determine it). One delta per edge, shared by its two faces, keeps
/// the corrected lengths one set that a smooth surface can have. psi(s) = 1 / (1 + (s / s_c)^4),
/// s_e = h_e |K_e| (Frobenius norm; h_e = sqrt(2 x the mean area of the edge's faces), the same
/// for every edge of a regular lattice, so the fade does not tell a diagonal from a side), fades
/// the correction out above s_c = 0.5 rad, where a hinge is a crease the faces do not resolve
/// and a flat face's edge is its own length. A face's three
/// deltas give C' = C + G delta (G maps edge-length changes to C). The St. Venant-Kirchhoff
/// energy is evaluated at C'; the strain limits stay on the chords' C (a hard limit on what the
/// mesh draws). Each face then couples the vertices of its own and its neighbours' stencils. The
/// Hessian adds the dependence through each K_e (its 3 x 3 part projected to PSD when
/// projecting), and the hinge angles' second derivatives only for the exact Hessian.
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
  /// The model material.membrane_model names (the arc model needs the mesh's hinges).
  MembraneEnergy(const remesh::SheetMesh& mesh, const Material& material);

  std::string name() const override { return "membrane"; }
  void add_pattern(SparsityBuilder& pattern) const override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;

  /// Principal stretches (s1 >= s2) of every face at x, #F by 2 (of the chords, as the limits
  /// see them, under either model).
  Eigen::MatrixX2d principal_stretches(const Eigen::VectorXd& x) const;

  /// Green strain (C - I) / 2 of every face at x, #F by 3 (e_xx, e_yy, e_xy): of the chords'
  /// C under the chord model, of the arcs' C' under the arc model (the strain the stretching
  /// energy measures; a face bent smoothly is unstrained although its chords are shorter).
  Eigen::MatrixX3d green_strains(const Eigen::VectorXd& x) const;

  /// Under the arc model, each vertex's curvature: the area-weighted mean of its faces' fitted
  /// curvatures (Voigt K_xx, K_yy, K_xy in material space, #V by 3) [1/m]. Empty (0 rows) under
  /// the chord model.
  Eigen::MatrixX3d vertex_curvatures(const Eigen::VectorXd& x) const;

  /// The arc model's correction of an edge's squared length [m^2]: psi(size |K|) L^4 k^2 / 12,
  /// with L its material length, q = (tx^2, ty^2, 2 tx ty) of its material direction, k = q K
  /// the normal curvature along it and `size` the fade's length (sqrt(2 x the faces' mean area)).
  static double arc_correction(double L, double size, const Eigen::RowVector3d& q,
                               const Eigen::Vector3d& K) {
    return arc_delta(L, size, q, K, false).value;
  }

  /// Energy, gradient and Hessian of one triangle (x0, x1, x2 stacked); the Hessian projected
  /// to PSD when `project`.
  double element(int f, const Eigen::Matrix<double, 9, 1>& xs, Eigen::Matrix<double, 9, 1>* g,
                 Eigen::Matrix<double, 9, 9>* H, bool project) const;

  bool arc() const { return !m_arcs.empty(); }
  bool limit_enabled() const { return m_limit > 0 || m_limit_low > 0; }

 private:
  struct Triangle {
    std::array<int, 3> v;
    Eigen::Matrix<double, 3, 2> w;  // F = sum_i x_i w_i^T (row i = w_i)
    double area;                    // rest area [m^2]
  };
  /// Per face, its curvature K = P theta_S (Voigt K_xx, K_yy, K_xy) fitted to its stencil S.
  struct CurvatureFit {
    std::vector<int> hinges;
    Eigen::MatrixXd P;  // 3 x |S| (3 x 0 when the mesh cannot determine it: no correction)
  };
  /// Per face, the arc model's data.
  struct Arc {
    std::vector<int> vertices;              // local: the face's corners, then the stencils' others
    std::vector<int> hinges;                // the union of the stencils of `faces`
    std::vector<std::array<int, 4>> local;  // per hinge: local index of (v0, v1, a, b)
    std::vector<int> faces;                 // the face, then its edge neighbours
    std::vector<int>
        fit_local;  // per face of `faces` in turn, per hinge of its fit: index in `local`
    /// Edge j (opposite corner j): material length, (tx^2, ty^2, 2 tx ty), and the weights of
    /// `faces` in its curvature (1/2 each across an interior edge, 1 on the boundary).
    Eigen::Vector3d length;
    Eigen::Vector3d size;  // the fade's length: sqrt(2 x the mean area of the edge's faces) [m]
    Eigen::Matrix3d Q;
    Eigen::Matrix<double, 3, Eigen::Dynamic> weight;
    Eigen::Matrix3d G;  // dC'/d delta in Voigt (C00, C11, C01)
  };
  /// delta of an edge of material length L and direction q = (tx^2, ty^2, 2 tx ty) as a
  /// function of its curvature K (Voigt): value, gradient and Hessian in K.
  struct Delta {
    double value = 0;
    Eigen::Vector3d gradient;
    Eigen::Matrix3d hessian;
  };
  /// An arc element's derivatives and the work matrices behind them, reused from face to face.
  struct ArcWork {
    Eigen::Matrix<double, 12, Eigen::Dynamic> M;   // 12 x n: dC'/dx, then dK_e/dx of edges 0-2
    Eigen::Matrix<double, 3, Eigen::Dynamic> Dd;   // 3 x n: d delta_e / dx
    Eigen::Matrix<double, 12, 12> D;               // the second derivatives M is contracted with
    Eigen::Matrix<double, 12, Eigen::Dynamic> DM;  // D M (or L^T M, D = L L^T)
    Eigen::VectorXd g;                             // gradient over the local vertices
    Eigen::VectorXd coefficient;                   // per hinge of the element: its Hessian's weight
    Eigen::MatrixXd H;                             // Hessian over the local vertices
  };
  static Delta arc_delta(double L, double size, const Eigen::RowVector3d& q,
                         const Eigen::Vector3d& K, bool derivatives);
  void build_arcs(const remesh::SheetMesh& mesh);
  /// Every face's fitted curvature K (Voigt, 3 x #F) from the hinge angles.
  Eigen::Matrix3Xd face_curvatures(const Eigen::VectorXd& theta) const;
  /// The deltas of face f's three edges (with their derivatives in K when `derivatives`).
  void arc_deltas(int f, const Eigen::Matrix3Xd& K, bool derivatives, Delta d[3]) const;
  /// One arc element's energy; with `work`, its gradient (and with `hessian` its Hessian,
  /// projected to PSD when `project`) in it.
  double arc_element(int f, const Eigen::VectorXd& x, const Eigen::Matrix3Xd& K,
                     const std::vector<Eigen::Matrix<double, 12, 1>>* grads,
                     const std::vector<Eigen::Matrix<double, 12, 12>>* hesses, ArcWork* work,
                     bool hessian, bool project) const;

  std::vector<Triangle> m_tris;
  std::vector<Arc> m_arcs;  // empty under the chord model
  std::vector<CurvatureFit> m_fits;
  remesh::Hinges m_hinges;
  double m_lambda, m_mu;         // plane-stress Lame parameters x thickness [N/m]
  double m_limit;                // L = (1 + eps)^2, 0 when disabled
  double m_dhat;                 // barrier activation distance in lambda
  double m_limit_low = 0;        // Lc = (1 - compression_limit)^2, 0 when disabled
  double m_dhat_low = 0;         // its activation distance in lambda
  double m_kappa;                // barrier stiffness [J/m^2]
  mutable ElementSlots m_slots;  // the elements' places in the Hessian (arcs or triangles)
};

}  // namespace papersim::simulation
