#pragma once
/// Reading and writing sheets: OBJ (world positions + exact material UV) and PLY (with the
/// extra per-vertex and per-face fields). Writers take std::ostream& so output can be compared.
#include <iosfwd>
#include <string>

#include "remesh/sheet_mesh.hpp"

namespace papersim::remesh {

/// Limits of the sheet readers, checked while reading (before memory is committed).
constexpr long MAX_SHEET_VERTICES = 500'000;  ///< vertices of a sheet file
constexpr long MAX_SHEET_FACES = 1'000'000;   ///< faces of a sheet file
constexpr double MAX_SHEET_COORDINATE = 1e6;  ///< |x|, |y|, |z|, width and height [m]

/// A sheet as stored in a file: connectivity, material coordinates and world state.
struct SheetData {
  SheetMesh mesh;
  Eigen::MatrixX3d positions;   ///< #V by 3 world positions [m]
  Eigen::MatrixX3d velocities;  ///< #V by 3 [m/s]; zero when the file has none
  double width = 0.0;           ///< sheet size along material x [m] (u = x / width)
  double height = 0.0;          ///< sheet size along material y [m] (v = y / height)
};

/// OBJ: a header comment `# papersim sheet WIDTH HEIGHT`, `v` world positions [m],
/// `vt` u = material x / width, v = material y / height, faces `f v/vt v/vt v/vt`.
void write_obj(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& positions,
               double width, double height);

/// Binary little-endian PLY with vertex x y z (world), mx my (material), vx vy vz and face
/// vertex_indices, kxx kyy kxy (plastic curvature [1/m]), damage.
void write_ply(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& positions,
               const Eigen::MatrixX3d& velocities, double width, double height);

/// Read an OBJ (v, vt, f with v/vt; one vt per v) or a PLY written by write_ply (binary or
/// ASCII, with mx my). Without the `# papersim sheet` header the OBJ's material scale is fitted
/// to the world edge lengths (the sheet is assumed nearly isometric).
/// @throw IoError when the file cannot be read or parsed (the message names the file and, for
///        an OBJ, the line), MeshError when the mesh is invalid (NaN, a coordinate beyond
///        MAX_SHEET_COORDINATE, more than MAX_SHEET_VERTICES / MAX_SHEET_FACES, a vertex used by
///        no face, non-manifold edge, face degenerate in material space, missing vt).
SheetData read_sheet(const std::string& path);

enum class SheetFormat { obj, ply };

/// read_sheet from a stream (opened in binary mode for a PLY); `source` names it in messages.
/// @throw IoError, MeshError as read_sheet
SheetData parse_sheet(std::istream& in, const std::string& source, SheetFormat format);

/// Write to `path` atomically: the content goes to a temporary file that is renamed into place.
/// @throw IoError for an unknown extension, common::OutputError when the file cannot be written
///        (nothing is then left at `path` or beside it).
void write_sheet_file(const std::string& path, const SheetMesh& mesh,
                      const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities,
                      double width, double height);

}  // namespace papersim::remesh
