#pragma once
/// Bending energy: the interface of the two discretisations and the factory that picks one by
/// Material::bending_model.
///   - morley (default): the Morley plate, one slope unknown per edge condensed out of the state
///     (morley_bending_energy.hpp); consistent on every mesh (heavy elastica within 0.4% along
///     the grid and at 30 degrees to it at 2.5 mm);
///   - fit: a per-face curvature tensor fitted to a stencil of hinge angles, with a residual
///     penalty against hourglass modes (fit_bending_energy.hpp); cheaper, but 2-5% stiff at 30
///     degrees to the mesh grain at 2.5 mm (docs/elastica_30deg_diagnosis.md).
#include <array>
#include <memory>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/energies/energy_term.hpp"
#include "simulation/material.hpp"

namespace papersim::simulation {

enum class BendingHessian { gauss_newton, projected, exact };

/// Plate energy density in Voigt form: D/2 [(1 - nu)|K|^2 + nu tr(K)^2] = D/2 k^T Q k with
/// k = (K_xx, K_yy, K_xy).
Eigen::Matrix3d plate_energy_matrix(double nu);

class BendingEnergy : public EnergyTerm {
 public:
  std::string name() const override { return "bend"; }
  /// Curvature tensor of every face at x, #F by 3 (K_xx, K_yy, K_xy) [1/m].
  virtual Eigen::MatrixX3d face_curvatures(const Eigen::VectorXd& x) const = 0;
  /// Curvature tensor of every face at x as the plastic return mapping measures it, #F by 3
  /// [1/m]: a function of the shape alone, never of the plastic state (a measure that moves
  /// with the plastic state lets plastic flow feed on itself). Default: face_curvatures.
  virtual Eigen::MatrixX3d yield_curvatures(const Eigen::VectorXd& x) const {
    return face_curvatures(x);
  }
  /// Replace the plastic state (#F by 3 curvature [1/m], #F damage).
  virtual void set_plastic_state(const Eigen::MatrixX3d& plastic_curvature,
                                 const Eigen::VectorXd& damage) = 0;
  /// Signed dihedral angle of every interior hinge [rad].
  Eigen::VectorXd hinge_angles(const Eigen::VectorXd& x) const;
  const remesh::Hinges& hinges() const { return m_hinges; }

 protected:
  BendingEnergy(const remesh::SheetMesh& mesh, const Material& material, BendingHessian hessian);

  remesh::Hinges m_hinges;
  Eigen::Matrix3d m_Q;  // plate energy density in Voigt: e = k^T Q k (plate_energy_matrix)
  double m_D, m_weakening;
  BendingHessian m_hessian_kind;
};

/// theta = row . (K_xx, K_yy, K_xy) for the height field z = p^T K p / 2 over the hinge
/// (p0, p1, pa, pb) in material coordinates (small slopes): the height of p_b over the plane of
/// (p0, p1, pa) over its distance from the hinge line. Exact for every constant curvature.
Eigen::RowVector3d hinge_curvature_row(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                       const Eigen::Vector2d& pa, const Eigen::Vector2d& pb);

/// Stencils of hinges that fit a face's curvature (the fit bending model, the arc membrane):
/// K = P theta with P the least-squares inverse of the stencil's hinge_curvature_row rows.
class CurvatureStencils {
 public:
  /// @param face_hinges remesh::face_hinges of the mesh; faces #F by 3; X material coordinates.
  CurvatureStencils(const remesh::Hinges& hinges, const Eigen::MatrixX3i& face_hinges,
                    const Eigen::MatrixX3i& faces, const Eigen::MatrixX2d& X);
  /// Appends face g's interior edges not yet in `stencil`.
  void add_face_hinges(std::vector<int>& stencil, int g) const;
  /// Appends the hinges of the faces of every hinge in `stencil` (the edge neighbours).
  void add_neighbour_hinges(std::vector<int>& stencil) const;
  /// The stencil's rows, #S by 3 (theta = rows K for a constant curvature K).
  Eigen::MatrixXd rows(const std::vector<int>& stencil) const;
  /// True when the rows determine K (three or more, of rank 3 to 1e-6).
  bool determined(const std::vector<int>& stencil) const;
  /// While not determined, at most twice: adds the hinges of every face with a corner among the
  /// stencil's vertices and face f's (boundary faces). Returns determined(stencil) at the end.
  bool grow_until_determined(std::vector<int>& stencil, int f) const;

 private:
  const remesh::Hinges& m_hinges;
  const Eigen::MatrixX3i& m_face_hinges;
  const Eigen::MatrixX3i& m_faces;
  const Eigen::MatrixX2d& m_X;
  std::vector<std::vector<int>> m_vertex_faces;  // faces with corner v, ascending
};

/// The local indices of hinge h's (v0, v1, a, b) in `vertices`, appending those not yet there
/// (an element's local vertex list).
std::array<int, 4> local_hinge(const remesh::Hinges& hinges, int h, std::vector<int>& vertices);

/// Positions of hinge v = (v0, v1, a, b) in x.
inline void gather_hinge(const Eigen::VectorXd& x, const Eigen::Vector4i& v, Eigen::Vector3d* p) {
  for (int k = 0; k < 4; ++k) p[k] = x.segment<3>(3 * v[k]);
}

/// Signed dihedral angle of every hinge at x [rad].
Eigen::VectorXd hinge_angles_at(const remesh::Hinges& hinges, const Eigen::VectorXd& x);

/// Angles of every hinge at x with their gradients (12 per hinge, over (v0, v1, a, b)) and,
/// when asked, their Hessians.
struct HingeDerivatives {
  Eigen::VectorXd theta;
  std::vector<Eigen::Matrix<double, 12, 1>> gradients;
  std::vector<Eigen::Matrix<double, 12, 12>> hessians;  // empty unless asked
};
HingeDerivatives hinge_derivatives(const remesh::Hinges& hinges, const Eigen::VectorXd& x,
                                   bool with_hessians);

/// The model material.bending_model names. `clamped_faces`: faces a clamp holds, slopes
/// included (the Morley model keeps their slopes; the fit model has no slope unknowns and
/// ignores them).
std::unique_ptr<BendingEnergy> make_bending_energy(
    const remesh::SheetMesh& mesh, const Material& material,
    BendingHessian hessian = BendingHessian::gauss_newton,
    const std::vector<int>& clamped_faces = {});

}  // namespace papersim::simulation
