#pragma once
/// The one place where the sheet's topology changes: every edge split, flip and collapse goes
/// through a MeshEditor, which carries every attribute across the edit (as geometry-central's
/// MutationManager does) and asks the caller's veto before applying it.
///
/// While an editor is open the per-vertex state (positions, velocities, obstacle distances and the
/// remeshing metric) lives in OpenMesh vertex properties, so OpenMesh's garbage collection in
/// finish() permutes it together with the connectivity. Vertex and face indices seen during the
/// edits (EditProposal) are those of the working mesh: deleted elements keep their index until
/// finish().
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "remesh/remesh.hpp"
#include "remesh/sheet_mesh.hpp"

namespace papersim::remesh {

class MeshEditor {
 public:
  /// An extra acceptance test (the remesh loop's metric criteria): empty string to accept, or the
  /// reason counted in the refusals. Called after the editor's own checks, before the veto.
  using EditCheck = std::function<std::string(const EditProposal&)>;

  /// Opens `mesh` and `state` for editing. Both must outlive the editor; they are only consistent
  /// again after finish().
  /// @throw MeshError when the state does not have one finite row per vertex.
  MeshEditor(SheetMesh& mesh, RemeshState& state, EditVeto veto = {});
  /// Calls finish() if it was not called.
  ~MeshEditor();
  MeshEditor(const MeshEditor&) = delete;
  MeshEditor& operator=(const MeshEditor&) = delete;

  /// Splits edge e at its material midpoint (a boundary edge's new vertex is on the boundary).
  /// Positions, velocities, obstacle distance and metric of the new vertex are the mean of the
  /// ends'; the children of each face inherit its plastic curvature and damage.
  /// @return the new vertex, or an invalid handle when the split was refused (counted).
  OpenMesh::VertexHandle split(OpenMesh::EdgeHandle e, const EditCheck& check = {});

  /// Flips interior edge e; both new faces get the material-area-weighted mean of the two old
  /// faces' plastic curvature and damage (exact: each new face overlaps each old one in the same
  /// proportion). @return false when refused (counted).
  bool flip(OpenMesh::EdgeHandle e, const EditCheck& check = {});

  /// Collapses halfedge h: its from-vertex is removed, its to-vertex survives with its own
  /// material coordinates, position, velocity and metric. The faces around the removed vertex pass
  /// their plastic curvature and damage to the new faces in proportion to their overlaps in
  /// material space, so the area integrals are conserved. Refused ("boundary") when it would move
  /// a boundary vertex off the boundary or remove a corner of the sheet.
  /// @return false when refused (counted).
  bool collapse(OpenMesh::HalfedgeHandle h, const EditCheck& check = {});

  /// What split / flip / collapse would create, without any check or change.
  EditProposal propose_split(OpenMesh::EdgeHandle e) const;
  EditProposal propose_flip(OpenMesh::EdgeHandle e) const;
  EditProposal propose_collapse(OpenMesh::HalfedgeHandle h) const;

  /// The working mesh (points = material coordinates, z = 0; may hold deleted elements).
  const TriMesh& mesh() const { return m_sheet.mesh(); }
  /// World position [m] of a vertex of the working mesh.
  Eigen::Vector3d position(OpenMesh::VertexHandle v) const;
  /// Material coordinates [m] of a vertex of the working mesh.
  Eigen::Vector2d material(OpenMesh::VertexHandle v) const;
  /// The remeshing metric of a vertex [1/m^2] (zero until set), carried like the positions.
  Eigen::Matrix2d metric(OpenMesh::VertexHandle v) const;
  void set_metric(OpenMesh::VertexHandle v, const Eigen::Matrix2d& m);

  /// Edits applied and refused so far.
  const RemeshStats& stats() const { return m_stats; }

  /// Removes deleted elements (renumbering vertices and faces), writes the per-vertex state back
  /// into the RemeshState and drops the working properties. Further edits are not allowed.
  void finish();

 private:
  /// A face next to an edge being split: its vertex opposite the edge and its plastic state.
  struct ParentFace {
    OpenMesh::VertexHandle opposite;
    OpenMesh::Vec3d plastic;
    double damage, area, children_area = 0.0;
  };
  /// A new vertex at the midpoint of a and b, every vertex attribute the mean of theirs.
  OpenMesh::VertexHandle add_midpoint(OpenMesh::VertexHandle a, OpenMesh::VertexHandle b);
  std::vector<ParentFace> faces_of_edge(OpenMesh::EdgeHandle e) const;
  void pass_to_children(OpenMesh::VertexHandle v, std::vector<ParentFace>& parents);
  bool accept(const EditProposal& proposal, const std::string& own_reason, const EditCheck& check);
  void refuse(const std::string& reason);
  double face_area(OpenMesh::FaceHandle f) const;
  std::string collapse_boundary_reason(OpenMesh::HalfedgeHandle h) const;
  void transfer_collapse(OpenMesh::HalfedgeHandle h);
  /// Fills world and material corners of the proposal's faces (index -1: the inserted vertex).
  void fill_geometry(EditProposal& proposal, const Eigen::Vector3d& inserted_world,
                     const Eigen::Vector2d& inserted_material) const;

  SheetMesh& m_sheet;
  RemeshState& m_state;
  EditVeto m_veto;
  RemeshStats m_stats;
  bool m_finished = false;
  bool m_had_vertex_status = false, m_had_edge_status = false, m_had_face_status = false;
  bool m_has_distance = false;
  OpenMesh::VPropHandleT<OpenMesh::Vec3d> m_position, m_velocity, m_metric;
  OpenMesh::VPropHandleT<double> m_distance;
};

/// [-] Smallest aspect ratio (aspect_ratio in sizing.hpp: 12 sqrt(3) area / perimeter^2) of a face
/// any edit may create; edits below it are refused ("degenerate"). The Morley plate inverts a
/// per-face 3 x 3 geometry matrix whose condition number grows as about 3.6 / aspect^2 (5e3 at
/// aspect 0.026, 5e15 at 2.6e-8, where Eigen's FullPivLU calls it singular): at 1e-2 it is about
/// 4e4, far from singular, while the floor stays well below the aspect_min (0.2) of collapses and
/// of the metric, so ordinary splits of acceptable faces are never refused by it.
constexpr double EDIT_ASPECT_MIN = 1e-2;

/// Twice the signed area of the material triangle (a, b, c) [m^2]: > 0 counter-clockwise.
double signed_area2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

/// True when the triangle is counter-clockwise with an area that is not negligible: twice its
/// area exceeds 1e-10 times its longest edge squared.
bool is_proper_triangle(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                        const Eigen::Vector2d& c);

/// Area [m^2] of the intersection of two counter-clockwise triangles in the plane (rows =
/// corners), by Sutherland-Hodgman clipping.
double triangle_overlap(const Eigen::Matrix<double, 3, 2>& a, const Eigen::Matrix<double, 3, 2>& b);

}  // namespace papersim::remesh
