// The only translation unit that includes CGAL (header-only, slow to compile).
#include "scenegen/resting_pose.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "scenegen/geometry.hpp"

namespace papersim::scenegen {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Hull = CGAL::Surface_mesh<Point>;

double cross2(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

/// Is q inside the convex hull of pts (Andrew's monotone chain), with margin tol?
bool inside_convex_hull_2d(std::vector<Eigen::Vector2d> pts, const Eigen::Vector2d& q, double tol) {
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Eigen::Vector2d> h(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross2(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  h.resize(k > 0 ? k - 1 : 0);
  if (h.size() < 3) return false;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const Eigen::Vector2d e = h[(i + 1) % h.size()] - h[i];
    if (cross2(h[i], h[(i + 1) % h.size()], q) < -tol * e.norm()) return false;
  }
  return true;
}

void set_in_plane_axes(Stage& s) {
  Eigen::Vector3d ey = Eigen::Vector3d::UnitY() - s.up.dot(Eigen::Vector3d::UnitY()) * s.up;
  if (ey.norm() < 1e-6) ey = Eigen::Vector3d::UnitX() - s.up.dot(Eigen::Vector3d::UnitX()) * s.up;
  s.ey = ey.normalized();
  s.ex = s.ey.cross(s.up).normalized();
}

/// Place the origin: centre of mass projected on the plane {p : up . p = level}.
void place(Stage& s, double level) {
  s.origin = s.centre_of_mass - (s.up.dot(s.centre_of_mass) - level) * s.up;
  set_in_plane_axes(s);
}

}  // namespace

Stage find_resting_pose(const SheetMesh& mesh) {
  Stage stage;
  stage.centre_of_mass = centre_of_mass(mesh);
  const Eigen::MatrixX3d& P = mesh.positions;
  const Eigen::RowVector3d mean = P.colwise().mean();
  const Eigen::MatrixX3d centred = P.rowwise() - mean;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(centred.transpose() * centred / P.rows());
  const double extent = std::sqrt(std::max(pca.eigenvalues()(2), 1e-30));
  if (std::sqrt(std::max(pca.eigenvalues()(0), 0.0)) < 1e-7 * extent + 1e-9) {
    stage.flat_sheet = true;
    stage.up = pca.eigenvectors().col(0);
    if (stage.up.z() < 0) stage.up = -stage.up;
    place(stage, (P * stage.up).minCoeff());
    stage.stable_faces = 1;
    return stage;
  }
  std::vector<Point> pts;
  pts.reserve(P.rows());
  for (long i = 0; i < P.rows(); ++i) pts.emplace_back(P(i, 0), P(i, 1), P(i, 2));
  Hull hull;
  CGAL::convex_hull_3(pts.begin(), pts.end(), hull);
  std::vector<Eigen::Vector3d> hv;
  for (auto v : hull.vertices()) {
    const Point& p = hull.point(v);
    hv.emplace_back(p.x(), p.y(), p.z());
  }
  const double tol = 1e-9 * extent * 1e3;  // coplanarity tolerance [m]
  double best_score = -2.0, fallback_score = -2.0;
  Eigen::Vector3d best_up = Eigen::Vector3d::UnitZ(), fallback_up = best_up;
  for (auto f : hull.faces()) {
    std::vector<Eigen::Vector3d> c;
    for (auto v : vertices_around_face(hull.halfedge(f), hull)) {
      const Point& p = hull.point(v);
      c.emplace_back(p.x(), p.y(), p.z());
    }
    const Eigen::Vector3d n_out = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
    const double level = n_out.dot(c[0]);
    const double score = -n_out.z();  // alignment of the resting direction with world -z
    if (score > fallback_score) {
      fallback_score = score;
      fallback_up = -n_out;
    }
    const Eigen::Vector3d a = (c[1] - c[0]).normalized(), b = n_out.cross(a);
    std::vector<Eigen::Vector2d> contact;
    for (const auto& p : hv)
      if (std::abs(n_out.dot(p) - level) <= tol) contact.emplace_back(a.dot(p), b.dot(p));
    const Eigen::Vector2d com2(a.dot(stage.centre_of_mass), b.dot(stage.centre_of_mass));
    if (inside_convex_hull_2d(contact, com2, 0.0)) {
      ++stage.stable_faces;
      if (score > best_score) {
        best_score = score;
        best_up = -n_out;
      }
    }
  }
  stage.stable = best_score > -2.0;
  stage.up = stage.stable ? best_up : fallback_up;
  place(stage, (P * stage.up).minCoeff());
  return stage;
}

}  // namespace papersim::scenegen
