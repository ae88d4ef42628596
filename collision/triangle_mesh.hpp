#pragma once
/// A plain indexed triangle mesh for mesh obstacles, and its OBJ reader.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "collision/collider.hpp"

namespace papersim::collision {

/// Indexed triangles; vertices in the obstacle's local frame [m], triangles counter-clockwise
/// seen from outside (the level set does not rely on the orientation).
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;   ///< [m]
  std::vector<Eigen::Vector3i> triangles;  ///< 0-based vertex indices
};

/// Reads the `v` and `f` records of an OBJ file (other records are ignored); polygons are
/// split into fans, `f a/b/c` and negative (relative) indices are accepted.
/// @throw ColliderIoError naming the file (and line) when it cannot be opened, a record is
///        malformed, an index is out of range or the file holds no triangle.
TriangleMesh read_obj(const std::string& path);

/// Checks the mesh is a closed 2-manifold surface (every edge shared by exactly two triangles),
/// has finite vertices and no repeated vertex in a triangle.
/// @throw ColliderError naming `name` and the first offending edge or triangle.
void check_closed(const TriangleMesh& mesh, const std::string& name);

/// Bounding box of the vertices [m].
Aabb mesh_bounds(const TriangleMesh& mesh);

/// Total triangle area [m^2].
double mesh_area(const TriangleMesh& mesh);

}  // namespace papersim::collision
