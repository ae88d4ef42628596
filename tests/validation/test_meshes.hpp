#pragma once
// Meshes with known answers for the metrics tests, built from plain arrays so that every
// expected value is computed here, independently of the remesh module.
#include <Eigen/Core>
#include <cmath>
#include <functional>

namespace papersim::validation::test {

constexpr double PI = 3.14159265358979323846;

/// Rounding of a few double operations on O(1) numbers; sums over a few hundred vertices.
constexpr double ROUNDING = 1e-12;

/// A nx by ny grid of width x height [m]; vertex (i, j) has index j * nx + i. Every cell is
/// split along the diagonal (i, j)-(i+1, j+1), counter-clockwise from +z.
struct Grid {
  int nx = 0, ny = 0;
  double dx = 0.0, dy = 0.0;
  Eigen::MatrixX2d material;  // #V by 2 [m]
  Eigen::MatrixX3i faces;     // #F by 3
  int index(int i, int j) const { return j * nx + i; }
};

inline Grid make_grid(int nx, int ny, double width, double height) {
  Grid g;
  g.nx = nx;
  g.ny = ny;
  g.dx = width / (nx - 1);
  g.dy = height / (ny - 1);
  g.material.resize(nx * ny, 2);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) g.material.row(g.index(i, j)) << i * g.dx, j * g.dy;
  g.faces.resize(2 * (nx - 1) * (ny - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = g.index(i, j), b = a + 1, c = a + nx, d = c + 1;
      g.faces.row(f++) << a, b, d;
      g.faces.row(f++) << a, d, c;
    }
  return g;
}

/// World positions p = map(X, Y) for every vertex.
inline Eigen::MatrixX3d map_positions(const Eigen::MatrixX2d& material,
                                      const std::function<Eigen::Vector3d(double, double)>& map) {
  Eigen::MatrixX3d p(material.rows(), 3);
  for (Eigen::Index v = 0; v < material.rows(); ++v)
    p.row(v) = map(material(v, 0), material(v, 1)).transpose();
  return p;
}

inline Eigen::MatrixX3d flat_positions(const Eigen::MatrixX2d& material) {
  return map_positions(material, [](double x, double y) { return Eigen::Vector3d(x, y, 0.0); });
}

/// Wrap onto the cylinder of radius r whose axis is the line z = r, x = 0 along y: material x
/// becomes the arc length.
inline Eigen::MatrixX3d cylinder_positions(const Eigen::MatrixX2d& material, double r) {
  return map_positions(material, [r](double x, double y) {
    return Eigen::Vector3d(r * std::sin(x / r), y, r * (1.0 - std::cos(x / r)));
  });
}

/// Fold the part x > a up about the line x = a by `angle` [rad].
inline Eigen::MatrixX3d folded_positions(const Eigen::MatrixX2d& material, double a, double angle) {
  return map_positions(material, [a, angle](double x, double y) {
    if (x <= a) return Eigen::Vector3d(x, y, 0.0);
    const double s = x - a;
    return Eigen::Vector3d(a + s * std::cos(angle), y, s * std::sin(angle));
  });
}

/// A triangulated cone: apex (index 0), then rings of n vertices at slant distances rho[j]
/// from the apex. Material: the flat disc (apex at the origin, ring j at radius rho[j]);
/// world: the cone of half-angle beta about -z with the same slant distances.
struct Cone {
  int n = 0;
  Eigen::MatrixX2d material;
  Eigen::MatrixX3d positions;
  Eigen::MatrixX3i faces;
};

inline Cone make_cone(int n, const Eigen::Vector2d& rho, double beta) {
  Cone c;
  c.n = n;
  c.material.resize(1 + 2 * n, 2);
  c.positions.resize(1 + 2 * n, 3);
  c.material.row(0) << 0.0, 0.0;
  c.positions.row(0) << 0.0, 0.0, 0.0;
  for (int j = 0; j < 2; ++j)
    for (int k = 0; k < n; ++k) {
      const double phi = 2.0 * PI * k / n;
      c.material.row(1 + j * n + k) << rho(j) * std::cos(phi), rho(j) * std::sin(phi);
      c.positions.row(1 + j * n + k) << rho(j) * std::sin(beta) * std::cos(phi),
          rho(j) * std::sin(beta) * std::sin(phi), -rho(j) * std::cos(beta);
    }
  c.faces.resize(3 * n, 3);
  for (int k = 0; k < n; ++k) {
    const int a1 = 1 + k, b1 = 1 + (k + 1) % n, a2 = a1 + n, b2 = b1 + n;
    c.faces.row(k) << 0, a1, b1;
    c.faces.row(n + 2 * k) << a1, a2, b2;
    c.faces.row(n + 2 * k + 1) << a1, b2, b1;
  }
  return c;
}

}  // namespace papersim::validation::test
