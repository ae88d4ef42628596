#pragma once
/// Handles: material points of the sheet driven along keyframes by stiff springs, until their
/// release time. A handle is a material point (not a vertex), held through the barycentric
/// weights of the face that contains it, so it survives remeshing.
#include <array>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/energies/energy_term.hpp"

namespace papersim::simulation {

/// A keyframe of a handle: displacement from the point's initial world position.
struct HandleKeyframe {
  double time = 0.0;                                       ///< [s]
  Eigen::Vector3d displacement = Eigen::Vector3d::Zero();  ///< [m]
};

struct HandleSpec {
  Eigen::Vector2d material_point = Eigen::Vector2d::Zero();  ///< [m]
  std::vector<HandleKeyframe> keyframes;  ///< linear in between, held after the last; none = fixed
  double release_time = INF;              ///< [s] the handle lets go at this time
  double stiffness = 1e6;                 ///< spring stiffness [N/m]
  /// Which world components the handle drives (1) or leaves free (0): (0, 0, 1) sets only the
  /// height, so two lifted points may move towards each other as an inextensible sheet must.
  Eigen::Vector3d axes = Eigen::Vector3d::Ones();
};

/// Displacement of a handle at time t (linear interpolation of the keyframes) [m].
Eigen::Vector3d handle_displacement(const HandleSpec& spec, double t);

/// A handle whose world anchor (the initial world position of its material point, from which
/// the keyframe displacements are measured) was fixed at the start of the run, so the handle
/// means the same on every mesh the run passes through.
struct AnchoredHandle {
  HandleSpec spec;
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  ///< [m]
};

/// Anchors handles at the world positions their material points have in (mesh, positions).
/// @param positions 3N world positions [m]
/// @throw SceneError when a material point lies outside the sheet.
std::vector<AnchoredHandle> anchor_handles(const remesh::SheetMesh& mesh,
                                           const Eigen::VectorXd& positions,
                                           const std::vector<HandleSpec>& handles);

class HandleEnergy : public EnergyTerm {
 public:
  /// Binds each handle's material point to the face of `mesh` that holds it.
  /// @throw SceneError when a material point lies outside the sheet.
  HandleEnergy(const remesh::SheetMesh& mesh, const std::vector<AnchoredHandle>& handles);
  /// Handles anchored at the world positions of their material points in positions_t0 (3N) [m].
  /// @throw SceneError when a material point lies outside the sheet.
  HandleEnergy(const remesh::SheetMesh& mesh, const Eigen::VectorXd& positions_t0,
               const std::vector<HandleSpec>& handles);

  std::string name() const override { return "handles"; }
  void add_pattern(SparsityBuilder& pattern) const override;
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;

  /// World position of handle i's material point at x [m].
  Eigen::Vector3d point(int i, const Eigen::VectorXd& x) const;
  /// Target of handle i at time t [m].
  Eigen::Vector3d target(int i, double t) const;
  /// Distance from handle i's point to its target over the driven axes [m].
  double error(int i, const Eigen::VectorXd& x, double t) const;
  int size() const { return static_cast<int>(m_handles.size()); }
  bool active(int i, double t) const { return t < m_handles[i].spec.release_time; }

 private:
  struct Bound {
    HandleSpec spec;
    std::array<int, 3> v;
    Eigen::Vector3d w;      // barycentric weights
    Eigen::Vector3d start;  // initial world position [m]
  };
  std::vector<Bound> m_handles;
  double m_t1 = 0.0;
};

/// Locate a material point: face index and barycentric weights, or face -1 when outside.
struct MaterialLocation {
  int face = -1;
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();
};
MaterialLocation locate_material_point(const remesh::SheetMesh& mesh, const Eigen::Vector2d& p);

}  // namespace papersim::simulation
