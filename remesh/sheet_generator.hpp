#pragma once
/// Rectangular sheets with no preferred grain.
#include <cstdint>

#include "remesh/sheet_mesh.hpp"

namespace papersim::remesh {

enum class Triangulation {
  alternating,  ///< diagonals alternate in a checkerboard ("union jack" per 2x2 block)
  random,       ///< each cell's diagonal drawn from the seed
  regular,      ///< every diagonal the same way (has a grain; for tests only)
};

/// Options of make_rectangle.
struct RectangleOptions {
  double width = 0.210;   ///< [m] along material x
  double height = 0.297;  ///< [m] along material y
  int nx = 21;            ///< vertices along x (>= 2)
  int ny = 30;            ///< vertices along y (>= 2)
  Triangulation triangulation = Triangulation::alternating;
  std::uint64_t seed = 0;  ///< for Triangulation::random
  double jitter = 0.0;     ///< interior vertices moved by up to jitter x spacing [-], in [0, 0.4]
};

/// A rectangle [0, width] x [0, height] in material coordinates.
/// @throw MeshError when an option is out of range.
SheetMesh make_rectangle(const RectangleOptions& options);

/// Options of make_rotated_lattice.
struct LatticeOptions {
  double width = 0.210;               ///< [m] along material x
  double height = 0.297;              ///< [m] along material y
  double edge_length = 5e-3;          ///< lattice spacing [m]
  double angle = 0.5235987755982988;  ///< angle of the lattice (the mesh grain) to material x [rad]
  /// The lattice's spacing across the grain is edge_length / aspect (0 < aspect <= 1): at aspect
  /// < 1 its cells, and the triangles, are 1 / aspect times longer across the grain than along it.
  double aspect = 1.0;
  /// Material x of straight lines of vertices across the sheet (x = const, spaced like the
  /// boundary), for boundary conditions the mesh must represent exactly: a clamp line.
  std::vector<double> lines_x;
};

/// A rectangle [0, width] x [0, height] meshed by the Delaunay triangulation of a square lattice
/// rotated by `angle` plus evenly spaced boundary points: a mesh whose grain is at an angle to
/// the sheet's edges (for orientation tests). Lattice points closer than half a spacing (measured
/// across the side) to the boundary or to one of `lines_x` are left out.
/// @throw MeshError when an option is out of range.
SheetMesh make_rotated_lattice(const LatticeOptions& options);

/// Delaunay triangulation of points in the plane (Bowyer-Watson), #F by 3, counter-clockwise.
/// Meant for the few thousand points of test sheets: O(n^2).
Eigen::MatrixX3i delaunay_triangulation(const Eigen::MatrixX2d& points);

/// Vertex counts (nx, ny) for a target edge length [m] on a width x height sheet.
Eigen::Vector2i grid_for_edge_length(double width, double height, double edge_length);

}  // namespace papersim::remesh
