#pragma once
#include <vector>
/// The sheet's connectivity and material coordinates.
///
/// A SheetMesh is an OpenMesh triangle mesh whose points are the *material coordinates* of the
/// vertices (the place of the vertex on the flat sheet, in metres, z = 0). World positions and
/// velocities are state, not connectivity: they live in Eigen arrays indexed by vertex index
/// (see simulation::SheetState). Faces carry the plastic state of Narain et al. 2013: a 2x2
/// symmetric plastic curvature tensor in material coordinates stored as (k_xx, k_yy, k_xy)
/// [1/m], and a scalar damage [-].
#include <Eigen/Core>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

namespace papersim::remesh {

struct MeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<MeshTraits>;

/// Connectivity + material coordinates + per-face plastic state of a sheet.
class SheetMesh {
 public:
  SheetMesh();
  SheetMesh(const SheetMesh& other);
  SheetMesh& operator=(const SheetMesh& other);

  /// Build from material coordinates (#V by 2, metres) and faces (#F by 3, counter-clockwise
  /// seen from +z in material space). Plastic state starts at zero.
  /// @throw MeshError on NaN, a face degenerate in material space, or a non-manifold edge.
  SheetMesh(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces);

  int num_vertices() const { return static_cast<int>(m_mesh.n_vertices()); }
  int num_faces() const { return static_cast<int>(m_mesh.n_faces()); }
  int num_edges() const { return static_cast<int>(m_mesh.n_edges()); }

  /// #V by 2 material coordinates [m].
  Eigen::MatrixX2d material_coords() const;
  /// #F by 3 vertex indices, counter-clockwise in material space.
  Eigen::MatrixX3i faces() const;
  /// Material coordinate of vertex v [m].
  Eigen::Vector2d material_coord(int v) const;

  /// #F by 3 plastic curvature (k_xx, k_yy, k_xy) [1/m] in material coordinates.
  Eigen::MatrixX3d plastic_curvature() const;
  void set_plastic_curvature(const Eigen::MatrixX3d& k);
  /// #F damage [-].
  Eigen::VectorXd damage() const;
  void set_damage(const Eigen::VectorXd& d);

  /// The same sheet built afresh from its arrays (material coordinates, faces, plastic state),
  /// as reading it back from a file builds it: vertices and faces keep their indices, edges are
  /// numbered in the order the faces first meet them. Sums over edges then run in the same
  /// order in a mesh that was remeshed and in its copy read from a checkpoint.
  /// @throw MeshError as the constructor does
  SheetMesh rebuilt() const;

  /// Axis-aligned extent of the material coordinates: (min x, min y, max x, max y) [m].
  Eigen::Vector4d material_bounds() const;

  /// The OpenMesh connectivity (points = material coordinates, z = 0).
  TriMesh& mesh() { return m_mesh; }
  const TriMesh& mesh() const { return m_mesh; }

  OpenMesh::FPropHandleT<OpenMesh::Vec3d> plastic_curvature_handle() const { return m_plastic; }
  OpenMesh::FPropHandleT<double> damage_handle() const { return m_damage; }

 private:
  void add_properties();
  TriMesh m_mesh;
  OpenMesh::FPropHandleT<OpenMesh::Vec3d> m_plastic;
  OpenMesh::FPropHandleT<double> m_damage;
};

/// The hinges of a mesh: for every interior edge, its two end vertices and the two opposite
/// vertices. Row e = (v0, v1, a, b): edge v0->v1 is counter-clockwise in the face (v0, v1, a),
/// so b is the opposite vertex of the face (v1, v0, b).
struct Hinges {
  Eigen::MatrixX4i vertices;  ///< #H by 4 (v0, v1, a, b)
  Eigen::MatrixX2i faces;     ///< #H by 2 (face of a, face of b)
};
Hinges interior_hinges(const SheetMesh& mesh);

/// For every face, the index into Hinges of its three edges (edge i opposite corner i), or -1
/// for a boundary edge. #F by 3.
Eigen::MatrixX3i face_hinges(const SheetMesh& mesh, const Hinges& hinges);

/// Faces whose three corners lie in the material-space box (x_min, y_min, x_max, y_max) [m]
/// (bounds included, 1e-12 m of slack): the faces a clamp over that box holds.
std::vector<int> faces_inside(const SheetMesh& mesh, const Eigen::Vector4d& box);

}  // namespace papersim::remesh
