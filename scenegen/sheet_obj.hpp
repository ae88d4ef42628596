#pragma once
/// The sheet as scenegen sees it: a triangle mesh with world positions and exact material UV,
/// read from the OBJ files the simulator writes (scenegen does not link the simulator).
#include <Eigen/Core>
#include <iosfwd>
#include <string>

namespace papersim::scenegen {

/// A sheet mesh: one UV per vertex, faces oriented so that their UV area is positive (the side
/// the document is printed on faces along the face normal).
struct SheetMesh {
  Eigen::MatrixX3d positions;     ///< #V by 3 world positions [m]
  Eigen::MatrixX2d uv;            ///< #V by 2 material UV: u = material x / width, v = y / height
  Eigen::MatrixX3i faces;         ///< #F by 3 vertex indices
  double width = 0.0;             ///< sheet size along material x [m]
  double height = 0.0;            ///< sheet size along material y [m]
  bool size_from_header = false;  ///< false: width / height fitted to the world edge lengths

  int num_vertices() const { return static_cast<int>(positions.rows()); }
  int num_faces() const { return static_cast<int>(faces.rows()); }
  /// Material point [m] of UV (u, v).
  Eigen::Vector2d material_point(const Eigen::Vector2d& uv_point) const {
    return {uv_point.x() * width, uv_point.y() * height};
  }
};

/// Parse a sheet OBJ: optional first-line comment `# papersim sheet WIDTH HEIGHT` (metres),
/// `v x y z`, `vt u v`, faces `f a/ta b/tb c/tc` (polygons are fan-triangulated, negative
/// indices allowed, normals ignored). Each vertex must have exactly one UV.
/// Without the header, width and height are fitted by least squares to the world edge lengths.
/// @param source  name used in error messages
/// @throw InputError when the text is malformed, has no `vt`, a vertex with two different UVs,
///        a UV outside [0, 1], a non-finite value, an out-of-range index or a face with zero
///        UV area.
SheetMesh parse_sheet_obj(std::istream& in, const std::string& source);

/// Read a sheet OBJ file. @throw IoError when the file cannot be opened; InputError as above.
SheetMesh read_sheet_obj(const std::string& path);

/// Write a sheet OBJ in the simulator's format (header, v, vt, f a/a b/b c/c).
void write_sheet_obj(std::ostream& out, const SheetMesh& mesh);

}  // namespace papersim::scenegen
