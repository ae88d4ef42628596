#pragma once
/// Sheets, world shapes and mesh checks shared by the remeshing tests.
#include <Eigen/Core>
#include <cmath>
#include <random>

#include "remesh/errors.hpp"
#include "remesh/mesh_editor.hpp"
#include "remesh/remesh.hpp"
#include "remesh/sheet_generator.hpp"
#include "remesh/sheet_mesh.hpp"
#include "remesh/sizing.hpp"

namespace papersim::remesh::testing {

/// A width x height rectangle with nx x ny vertices (alternating diagonals).
inline SheetMesh grid(double width, double height, int nx, int ny, double jitter = 0.0,
                      std::uint64_t seed = 0) {
  RectangleOptions o;
  o.width = width;
  o.height = height;
  o.nx = nx;
  o.ny = ny;
  o.jitter = jitter;
  o.seed = seed;
  return make_rectangle(o);
}

/// The flat sheet at rest: world = (X, Y, 0), zero velocity.
inline RemeshState flat_state(const SheetMesh& mesh) {
  const Eigen::MatrixX2d x = mesh.material_coords();
  RemeshState s;
  s.positions = Eigen::MatrixX3d::Zero(x.rows(), 3);
  s.positions.leftCols(2) = x;
  s.velocities = Eigen::MatrixX3d::Zero(x.rows(), 3);
  return s;
}

/// The isometric wrap of the sheet on a cylinder of radius r whose axis is parallel to material x
/// (material y becomes arc length).
inline RemeshState cylinder_state(const SheetMesh& mesh, double r) {
  const Eigen::MatrixX2d x = mesh.material_coords();
  RemeshState s = flat_state(mesh);
  for (int v = 0; v < x.rows(); ++v)
    s.positions.row(v) << x(v, 0), r * std::sin(x(v, 1) / r), r * (1 - std::cos(x(v, 1) / r));
  return s;
}

/// The sheet folded sharply along the line y = y0 by `angle` (pi/2: the part y > y0 stands up;
/// pi: it lies back over the rest).
inline RemeshState folded_state(const SheetMesh& mesh, double y0, double angle) {
  const Eigen::MatrixX2d x = mesh.material_coords();
  RemeshState s = flat_state(mesh);
  for (int v = 0; v < x.rows(); ++v) {
    const double t = x(v, 1) - y0;
    if (t > 0) s.positions.row(v) << x(v, 0), y0 + t * std::cos(angle), t * std::sin(angle);
  }
  return s;
}

/// Random plastic curvature and damage on every face, random velocities.
inline void randomize_attributes(SheetMesh& mesh, RemeshState& state, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixX3d k(mesh.num_faces(), 3);
  Eigen::VectorXd d(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    k.row(f) << 100 * u(rng), 100 * u(rng), 50 * u(rng);
    d(f) = 0.5 * (1 + u(rng));
  }
  mesh.set_plastic_curvature(k);
  mesh.set_damage(d);
  for (int v = 0; v < state.velocities.rows(); ++v)
    state.velocities.row(v) << u(rng), u(rng), u(rng);
}

/// Material area of every face [m^2].
inline Eigen::VectorXd face_areas(const SheetMesh& mesh) {
  const Eigen::MatrixX2d x = mesh.material_coords();
  const Eigen::MatrixX3i f = mesh.faces();
  Eigen::VectorXd a(f.rows());
  for (int i = 0; i < f.rows(); ++i)
    a(i) = 0.5 * signed_area2(x.row(f(i, 0)).transpose(), x.row(f(i, 1)).transpose(),
                              x.row(f(i, 2)).transpose());
  return a;
}

/// Area integrals: (k_xx, k_yy, k_xy, damage) integrated over the sheet.
inline Eigen::Vector4d integrals(const SheetMesh& mesh) {
  const Eigen::VectorXd a = face_areas(mesh);
  Eigen::Vector4d out;
  out.head<3>() = mesh.plastic_curvature().transpose() * a;
  out(3) = mesh.damage().dot(a);
  return out;
}

/// The same integrals of the absolute values: the scale rounding errors are relative to.
inline Eigen::Vector4d abs_integrals(const SheetMesh& mesh) {
  const Eigen::VectorXd a = face_areas(mesh);
  Eigen::Vector4d out;
  out.head<3>() = mesh.plastic_curvature().cwiseAbs().transpose() * a;
  out(3) = mesh.damage().cwiseAbs().dot(a);
  return out;
}

/// Smallest aspect ratio (12 sqrt(3) area / perimeter^2) over the faces; <= 0 if one is inverted.
inline double min_aspect(const SheetMesh& mesh) {
  const Eigen::MatrixX2d x = mesh.material_coords();
  const Eigen::MatrixX3i f = mesh.faces();
  double lo = 1.0;
  for (int i = 0; i < f.rows(); ++i)
    lo = std::min(lo, aspect_ratio(x.row(f(i, 0)).transpose(), x.row(f(i, 1)).transpose(),
                                   x.row(f(i, 2)).transpose()));
  return lo;
}

/// V - E + F (1 for a disk).
inline int euler_characteristic(const SheetMesh& mesh) {
  return mesh.num_vertices() - mesh.num_edges() + mesh.num_faces();
}

/// True when every vertex on the mesh boundary lies exactly on a side of the rectangle `bounds`
/// (x_min, y_min, x_max, y_max) and every vertex lies inside it.
inline bool boundary_on_rectangle(const SheetMesh& mesh, const Eigen::Vector4d& b) {
  const TriMesh& m = mesh.mesh();
  for (auto v : m.vertices()) {
    const auto& p = m.point(v);
    if (p[0] < b[0] || p[1] < b[1] || p[0] > b[2] || p[1] > b[3]) return false;
    const bool on_side = p[0] == b[0] || p[1] == b[1] || p[0] == b[2] || p[1] == b[3];
    if (m.is_boundary(v) && !on_side) return false;
  }
  return true;
}

/// True when the four corners of the rectangle are vertices of the mesh.
inline bool has_corners(const SheetMesh& mesh, const Eigen::Vector4d& b) {
  int found = 0;
  for (auto v : mesh.mesh().vertices()) {
    const auto& p = mesh.mesh().point(v);
    found += (p[0] == b[0] || p[0] == b[2]) && (p[1] == b[1] || p[1] == b[3]);
  }
  return found == 4;
}

}  // namespace papersim::remesh::testing
