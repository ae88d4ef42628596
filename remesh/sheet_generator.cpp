#include "remesh/sheet_generator.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "remesh/errors.hpp"

namespace papersim::remesh {

namespace {

void check(const RectangleOptions& o) {
  if (!(o.width > 0) || !(o.height > 0)) throw MeshError("rectangle: width and height must be > 0");
  if (o.nx < 2 || o.ny < 2) throw MeshError("rectangle: nx and ny must be >= 2");
  if (!(o.jitter >= 0.0 && o.jitter <= 0.4)) throw MeshError("rectangle: jitter must be in [0, 0.4]");
}

/// Diagonal of cell (i, j): true = from (i, j) to (i+1, j+1).
bool cell_diagonal(const RectangleOptions& o, int i, int j, std::mt19937_64& rng) {
  switch (o.triangulation) {
    case Triangulation::alternating: return ((i + j) % 2) == 0;
    case Triangulation::random: return (rng() & 1u) != 0;
    case Triangulation::regular: return true;
  }
  return true;
}

}  // namespace

SheetMesh make_rectangle(const RectangleOptions& o) {
  check(o);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> jitter(-o.jitter, o.jitter);
  const double dx = o.width / (o.nx - 1), dy = o.height / (o.ny - 1);
  Eigen::MatrixX2d material(o.nx * o.ny, 2);
  for (int j = 0; j < o.ny; ++j)
    for (int i = 0; i < o.nx; ++i) {
      double x = i * dx, y = j * dy;
      // Jitter interior coordinates only, so the outline stays a rectangle.
      if (i > 0 && i < o.nx - 1) x += jitter(rng) * dx;
      if (j > 0 && j < o.ny - 1) y += jitter(rng) * dy;
      material.row(j * o.nx + i) << x, y;
    }
  Eigen::MatrixX3i faces(2 * (o.nx - 1) * (o.ny - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < o.ny; ++j)
    for (int i = 0; i + 1 < o.nx; ++i) {
      const int a = j * o.nx + i, b = a + 1, c = a + o.nx, d = c + 1;
      if (cell_diagonal(o, i, j, rng)) {
        faces.row(f++) << a, b, d;
        faces.row(f++) << a, d, c;
      } else {
        faces.row(f++) << a, b, c;
        faces.row(f++) << b, d, c;
      }
    }
  return SheetMesh(material, faces);
}

Eigen::Vector2i grid_for_edge_length(double width, double height, double edge_length) {
  if (!(edge_length > 0)) throw MeshError("rectangle: edge length must be > 0");
  const int nx = std::max(2, static_cast<int>(std::lround(width / edge_length)) + 1);
  const int ny = std::max(2, static_cast<int>(std::lround(height / edge_length)) + 1);
  return {nx, ny};
}

}  // namespace papersim::remesh
