#pragma once
/// Geometry on a sheet mesh: normals, centre of mass, ray casting and point location in UV.
#include <Eigen/Core>
#include <cmath>
#include <optional>
#include <vector>

#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// Degrees to radians.
constexpr double DEG = M_PI / 180.0;

/// #V by 3 unit vertex normals (area-weighted face normals; faces oriented by positive UV area,
/// so normals point to the printed side).
Eigen::MatrixX3d vertex_normals(const SheetMesh& mesh);

/// Centre of mass of the sheet as a uniform-density surface [m].
Eigen::Vector3d centre_of_mass(const SheetMesh& mesh);

/// A hit of a ray with the mesh.
struct RayHit {
  int face = -1;   ///< face index
  double t = 0.0;  ///< ray parameter (distance in units of |direction|)
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();  ///< weights of the face's corners
};

/// Bounding volume hierarchy over the faces of a mesh, for exact ray casting (Moller-Trumbore).
class MeshBvh {
 public:
  explicit MeshBvh(const SheetMesh& mesh);
  /// First hit with t in (t_min, t_max), skipping faces for which `skip(face)` is true.
  /// @param skip_vertex faces using this vertex are skipped (-1: none)
  std::optional<RayHit> first_hit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double t_min, double t_max, int skip_vertex = -1) const;

 private:
  struct Node {
    Eigen::Vector3d lo, hi;
    int left = -1, right = -1;  // children; -1 for a leaf
    int begin = 0, end = 0;     // range in m_order for a leaf
  };
  int build(int begin, int end);
  const SheetMesh& m_mesh;
  std::vector<int> m_order;
  std::vector<Node> m_nodes;
  std::vector<Eigen::Vector3d> m_centroids;
};

/// Point location in UV space: which face contains a UV point and with which barycentric
/// weights. A uniform grid over the UV square.
class UvLocator {
 public:
  explicit UvLocator(const SheetMesh& mesh);
  /// Face containing `uv_point` (tolerance `eps` in UV), or nothing when it is outside the sheet.
  std::optional<RayHit> locate(const Eigen::Vector2d& uv_point, double eps = 1e-9) const;
  /// World position of a UV point, or nothing when it is outside the sheet.
  std::optional<Eigen::Vector3d> world_point(const Eigen::Vector2d& uv_point) const;

 private:
  const SheetMesh& m_mesh;
  int m_n = 1;
  std::vector<std::vector<int>> m_cells;
};

}  // namespace papersim::scenegen
