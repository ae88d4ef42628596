#pragma once
/// The simulation's veto on remeshing edits: an edit may not create a triangle that exceeds the
/// strain limit, comes within a tenth of the contact thickness of an obstacle, or comes within a
/// tenth of the self-contact thickness of (or passes through) the rest of the sheet. The barriers
/// are finite there, so the next step starts from a feasible state; the solver's invariants
/// (no penetration, no self-intersection, stretch within the limit) hold across the remesh.
///
/// What each kind of edit can break: a split inserts a vertex at the material midpoint of an edge
/// and its world position at the world midpoint, so its new triangles lie in the planes of the
/// old ones with the same deformation gradient; only the new vertex can come close to a curved
/// obstacle (the chord cuts into it). Flips and collapses move triangles: they are checked for
/// strain, obstacles (centroid and edge midpoints against the distance field, and exactly
/// against a sphere and a polytope's corners and edges, which can pass between those points: a
/// gable's ridge or a small sphere's top under a large new face) and the rest of the sheet. On a
/// bent sheet a flip or a collapse makes triangles whose world shape differs from their material
/// shape (a chord is shorter than its arc), and the stiff membrane turns even a small strain into a
/// large energy (Eh = 5e5 N/m: 0.1% strain over 1 cm^2 stores 25 uJ, the order of a sheet's whole
/// bending energy), so such edits are refused unless their strain stays within
/// `strain_tolerance`: coarsening happens where the sheet is flat. Within the obstacle barrier's
/// reach a new point may not lie deeper than the two corners it lies between ("barrier"): a
/// split's vertex on a chord across a convex obstacle would start the next step with a barrier
/// force many times its neighbours' and kick the sheet away (docs/remeshing.md, "Passes that
/// kicked the sheet off its obstacle").
#include <array>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "collision/collider.hpp"
#include "remesh/remesh.hpp"

namespace papersim::simulation {

struct RemeshVetoParams {
  double strain_limit = 0.005;  ///< largest principal stretch 1 + strain_limit [-]
  /// Flips and collapses may not make a face whose principal stretches leave
  /// [1 - strain_tolerance, 1 + strain_tolerance] [-].
  double strain_tolerance = 2e-4;
  double obstacle_gap = 3e-5;  ///< closest a new point may come to an obstacle [m]
  /// Reach of the obstacle barrier (the contact's dhat) [m]; <= 0 off. Within it a new point (a
  /// split's vertex, a new face's edge midpoint) may not be closer to an obstacle than the mean
  /// of the distances of the two corners it lies between (less 1e-3 of the reach): refining a
  /// chord across a convex obstacle would start the next step with a barrier force many times
  /// the neighbours' ("barrier").
  double obstacle_reach = 0.0;
  double self_gap = 3e-5;  ///< closest a new triangle may come to the sheet [m]; <= 0 off
  double time = 0.0;       ///< obstacles' time [s]
};

class RemeshVeto {
 public:
  /// @param positions world positions of the mesh the pass starts from (#V by 3) [m]
  RemeshVeto(std::vector<std::shared_ptr<const collision::Collider>> obstacles,
             const remesh::SheetMesh& mesh, const Eigen::MatrixX3d& positions,
             const RemeshVetoParams& params);

  /// Under the arc membrane: each vertex's curvature in material space (Voigt K_xx, K_yy, K_xy;
  /// #V of the starting mesh, MembraneEnergy::vertex_curvatures) [1/m]. Flips and collapses are
  /// then held to the tolerance on the strain the arc membrane measures (each new edge as long as
  /// the arc over it, with the mean curvature of the face's corners from the starting mesh), not
  /// on the chords', which are shorter wherever the sheet bends.
  void set_vertex_curvatures(Eigen::MatrixX3d curvatures) { m_curvatures = std::move(curvatures); }

  /// Empty to allow the edit, else the reason ("stretch", "obstacle", "self").
  std::string operator()(const remesh::EditProposal& edit) const;

 private:
  std::string stretch_reason(const remesh::EditProposal& edit) const;
  /// Principal stretches of new face f of `edit`, of its arcs under set_vertex_curvatures.
  Eigen::Vector2d arc_stretches(const remesh::EditProposal& edit, size_t f) const;
  bool near_obstacle(const Eigen::Vector3d& p) const;
  bool deeper_in_barrier(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                         const Eigen::Vector3d& b) const;
  bool deeper_in_barrier(const Eigen::Matrix3d& triangle) const;
  bool near_polytope_features(const Eigen::Matrix3d& triangle) const;
  bool near_sphere(const Eigen::Matrix3d& triangle) const;
  bool near_sheet(const remesh::EditProposal& edit, int face) const;
  std::vector<int> faces_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  long long cell_key(const Eigen::Vector3i& c) const;

  std::vector<std::shared_ptr<const collision::Collider>> m_obstacles;
  std::vector<collision::Aabb> m_bounds;        // obstacles at the pass's time, grown by the gap
  std::vector<collision::Aabb> m_reach_bounds;  // the same, grown by the barrier's reach
  /// Corners and edges of the polytope obstacles (box, gable) at the pass's time [m].
  std::vector<Eigen::Vector3d> m_corners;
  std::vector<std::array<int, 2>> m_edges;  // indices into m_corners
  /// Centres and radii of the sphere obstacles at the pass's time [m].
  std::vector<std::pair<Eigen::Vector3d, double>> m_spheres;
  RemeshVetoParams m_params;
  Eigen::MatrixX3d m_curvatures;  // per vertex of the starting mesh; empty: chords
  double m_cell = 1.0;            // grid cell size [m]
  std::unordered_map<long long, std::vector<int>> m_grid;  // faces of the starting mesh by cell
};

/// Smallest distance between two triangles (rows = corners) [m]: 0 when they intersect.
double triangle_distance(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

/// What the obstacle-proximity sizing refines by, per vertex (#V) [m]: the smallest signed
/// distance to any obstacle at time t, less the distance the vertex closes towards that obstacle
/// in `lookahead` seconds at its current velocity relative to the obstacle's (0 when it moves
/// away), so a sheet falling onto an obstacle is refined before it arrives.
/// @param positions, velocities #V x 3 [m], [m/s]
Eigen::VectorXd approach_distance(
    const std::vector<std::shared_ptr<const collision::Collider>>& obstacles,
    const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities, double t,
    double lookahead);

}  // namespace papersim::simulation
