#include "remesh/sheet_generator.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "remesh/errors.hpp"

namespace papersim::remesh {

namespace {

void check(const RectangleOptions& o) {
  if (!(o.width > 0) || !(o.height > 0)) throw MeshError("rectangle: width and height must be > 0");
  if (o.nx < 2 || o.ny < 2) throw MeshError("rectangle: nx and ny must be >= 2");
  if (!(o.jitter >= 0.0 && o.jitter <= 0.4))
    throw MeshError("rectangle: jitter must be in [0, 0.4]");
}

/// Diagonal of cell (i, j): true = from (i, j) to (i+1, j+1).
bool cell_diagonal(const RectangleOptions& o, int i, int j, std::mt19937_64& rng) {
  switch (o.triangulation) {
    case Triangulation::alternating:
      return ((i + j) % 2) == 0;
    case Triangulation::random:
      return (rng() & 1u) != 0;
    case Triangulation::regular:
      return true;
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

namespace {

struct Circle {
  Eigen::Vector2d centre;
  double radius2;
};

Circle circumcircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Eigen::Vector2d ab = b - a, ac = c - a;
  const double d = 2 * (ab.x() * ac.y() - ab.y() * ac.x());
  const Eigen::Vector2d o((ac.y() * ab.squaredNorm() - ab.y() * ac.squaredNorm()) / d,
                          (ab.x() * ac.squaredNorm() - ac.x() * ab.squaredNorm()) / d);
  return {a + o, o.squaredNorm()};
}

}  // namespace

Eigen::MatrixX3i delaunay_triangulation(const Eigen::MatrixX2d& P) {
  const int n = static_cast<int>(P.rows());
  const Eigen::Vector2d lo = P.colwise().minCoeff(), hi = P.colwise().maxCoeff();
  const double span = (hi - lo).maxCoeff() * 10;
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  std::vector<Eigen::Vector2d> pts(n);
  for (int i = 0; i < n; ++i) pts[i] = P.row(i);
  pts.push_back(mid + Eigen::Vector2d(-span, -span));  // super triangle
  pts.push_back(mid + Eigen::Vector2d(span, -span));
  pts.push_back(mid + Eigen::Vector2d(0, span));
  struct Tri {
    std::array<int, 3> v;
    Circle c;
  };
  std::vector<Tri> tris{{{n, n + 1, n + 2}, circumcircle(pts[n], pts[n + 1], pts[n + 2])}};
  for (int p = 0; p < n; ++p) {
    std::vector<std::array<int, 2>> edges;
    std::vector<Tri> keep;
    keep.reserve(tris.size() + 2);
    for (const Tri& t : tris) {
      if ((pts[p] - t.c.centre).squaredNorm() < t.c.radius2 * (1 - 1e-12)) {
        for (int k = 0; k < 3; ++k) edges.push_back({t.v[k], t.v[(k + 1) % 3]});
      } else {
        keep.push_back(t);
      }
    }
    // Boundary of the cavity: edges that appear once.
    for (size_t i = 0; i < edges.size(); ++i) {
      bool shared = false;
      for (size_t j = 0; j < edges.size(); ++j)
        if (i != j && edges[i][0] == edges[j][1] && edges[i][1] == edges[j][0]) shared = true;
      if (!shared)
        keep.push_back({{edges[i][0], edges[i][1], p},
                        circumcircle(pts[edges[i][0]], pts[edges[i][1]], pts[p])});
    }
    tris.swap(keep);
  }
  std::vector<Eigen::Vector3i> out;
  for (const Tri& t : tris) {
    if (t.v[0] >= n || t.v[1] >= n || t.v[2] >= n) continue;
    const Eigen::Vector2d e1 = pts[t.v[1]] - pts[t.v[0]], e2 = pts[t.v[2]] - pts[t.v[0]];
    const double area2 = e1.x() * e2.y() - e1.y() * e2.x();
    if (std::abs(area2) < 1e-10 * std::max(e1.squaredNorm(), e2.squaredNorm())) continue;
    out.emplace_back(t.v[0], t.v[1], t.v[2]);
  }
  Eigen::MatrixX3i F(out.size(), 3);
  for (size_t f = 0; f < out.size(); ++f) F.row(f) = out[f].transpose();
  return F;
}

SheetMesh make_rotated_lattice(const LatticeOptions& o) {
  if (!(o.width > 0 && o.height > 0 && o.edge_length > 0))
    throw MeshError("lattice: width, height and edge_length must be > 0");
  if (!(o.aspect > 0 && o.aspect <= 1)) throw MeshError("lattice: aspect must be in (0, 1]");
  const double h = o.edge_length;
  // Lattice vectors: h along the grain, h / aspect across it.
  const Eigen::Vector2d a1(h * std::cos(o.angle), h * std::sin(o.angle));
  const Eigen::Vector2d a2 = Eigen::Vector2d(-a1.y(), a1.x()) / o.aspect;
  // Half the lattice's spacing across a side of constant x / y (at aspect 1: half an edge).
  const double margin_x = 0.5 * std::max(h, std::abs(a2.x())),
               margin_y = 0.5 * std::max(h, std::abs(a2.y()));
  std::vector<Eigen::Vector2d> pts;
  // Boundary: evenly spaced points on the four sides.
  const int nx = std::max(1, static_cast<int>(std::lround(o.width / h)));
  const int ny = std::max(1, static_cast<int>(std::lround(o.height / h)));
  for (int i = 0; i < nx; ++i) {
    pts.emplace_back(o.width * i / nx, 0.0);
    pts.emplace_back(o.width * (nx - i) / nx, o.height);
  }
  for (int j = 0; j < ny; ++j) {
    pts.emplace_back(o.width, o.height * j / ny);
    pts.emplace_back(0.0, o.height * (ny - j) / ny);
  }
  for (double lx : o.lines_x) {
    if (!(lx > 0.5 * h && lx < o.width - 0.5 * h))
      throw MeshError("lattice: lines_x must lie inside the sheet, half an edge from its sides");
    // The line's ends replace the boundary points within half a spacing of them.
    pts.erase(std::remove_if(pts.begin(), pts.end(),
                             [&](const Eigen::Vector2d& p) {
                               return (p.y() == 0.0 || p.y() == o.height) &&
                                      std::abs(p.x() - lx) < 0.5 * h;
                             }),
              pts.end());
    for (int j = 0; j <= ny; ++j) pts.emplace_back(lx, o.height * j / ny);
  }
  const auto near_line = [&](const Eigen::Vector2d& p) {
    for (double lx : o.lines_x)
      if (std::abs(p.x() - lx) < margin_x) return true;
    return false;
  };
  // Interior: the rotated lattice, kept half a spacing away from the boundary and the lines.
  const int range = static_cast<int>(std::ceil((o.width + o.height) / h)) + 2;
  const Eigen::Vector2d centre(0.5 * o.width, 0.5 * o.height);
  for (int i = -range; i <= range; ++i)
    for (int j = -range; j <= range; ++j) {
      const Eigen::Vector2d p = centre + i * a1 + j * a2 + 0.25 * (a1 + a2);
      if (p.x() > margin_x && p.x() < o.width - margin_x && p.y() > margin_y &&
          p.y() < o.height - margin_y && !near_line(p))
        pts.push_back(p);
    }
  Eigen::MatrixX2d P(pts.size(), 2);
  for (size_t i = 0; i < pts.size(); ++i) P.row(i) = pts[i].transpose();
  return SheetMesh(P, delaunay_triangulation(P));
}

Eigen::Vector2i grid_for_edge_length(double width, double height, double edge_length) {
  if (!(edge_length > 0)) throw MeshError("rectangle: edge length must be > 0");
  const int nx = std::max(2, static_cast<int>(std::lround(width / edge_length)) + 1);
  const int ny = std::max(2, static_cast<int>(std::lround(height / edge_length)) + 1);
  return {nx, ny};
}

}  // namespace papersim::remesh
