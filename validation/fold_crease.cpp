#include "validation/fold_crease.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

namespace papersim::validation {

FoldLine fold_line_in_rectangle(const Eigen::Vector2d& centre, const Eigen::Vector2d& d,
                                double width, double height) {
  if (!(d.norm() > 0)) throw std::invalid_argument("fold_line_in_rectangle: zero direction");
  FoldLine f;
  f.centre = centre;
  f.d = d.normalized();
  const Eigen::Vector2d t(-f.d.y(), f.d.x());
  // Both ends: the largest s with centre +- s t inside the rectangle.
  double ends[2] = {std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
  const double lo[2] = {0.0, 0.0}, hi[2] = {width, height};
  for (int side = 0; side < 2; ++side) {
    const Eigen::Vector2d dir = side == 0 ? t : Eigen::Vector2d(-t);
    for (int a = 0; a < 2; ++a) {
      if (dir[a] > 1e-12) ends[side] = std::min(ends[side], (hi[a] - centre[a]) / dir[a]);
      if (dir[a] < -1e-12) ends[side] = std::min(ends[side], (lo[a] - centre[a]) / dir[a]);
    }
  }
  f.chord = ends[0] + ends[1];
  // Keep the centre at the chord's midpoint, so pieces are measured from one end.
  f.centre += 0.5 * (ends[0] - ends[1]) * t;
  return f;
}

FoldLine fit_crease_line(const Eigen::MatrixX2d& X, const Eigen::MatrixX3i& F,
                         const Eigen::MatrixX3d& K, const FoldLine& nominal, double width,
                         double height, double search) {
  if (K.rows() != F.rows())
    throw std::invalid_argument("fit_crease_line: one plastic curvature per face");
  double total = 0.0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  std::vector<std::pair<Eigen::Vector2d, double>> points;
  for (Eigen::Index i = 0; i < F.rows(); ++i) {
    const Eigen::Vector2d a = X.row(F(i, 0)), b = X.row(F(i, 1)), c = X.row(F(i, 2));
    const Eigen::Vector2d g = (a + b + c) / 3;
    if (std::abs((g - nominal.centre).dot(nominal.d)) > search) continue;
    // Largest |eigenvalue| of [[kxx, kxy], [kxy, kyy]].
    const double mid = 0.5 * (K(i, 0) + K(i, 1)), half = 0.5 * (K(i, 0) - K(i, 1));
    const double k = std::abs(mid) + std::hypot(half, K(i, 2));
    const double w = 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x()) * k * k;
    if (!(w > 0)) continue;
    points.emplace_back(g, w);
    total += w;
    mean += w * g;
  }
  if (!(total > 0)) return nominal;
  mean /= total;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& [g, w] : points) cov += w * (g - mean) * (g - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const Eigen::Vector2d along = eig.eigenvectors().col(1);  // largest eigenvalue
  Eigen::Vector2d d(-along.y(), along.x());
  if (d.dot(nominal.d) < 0) d = -d;
  return fold_line_in_rectangle(mean, d, width, height);
}

FoldCrease measure_fold_crease(const Eigen::MatrixX2d& X, const Eigen::MatrixX3i& F,
                               const Eigen::MatrixX3d& K, const FoldLine& f,
                               const FoldCreaseOptions& o) {
  if (K.rows() != F.rows())
    throw std::invalid_argument("measure_fold_crease: one plastic curvature per face");
  const Eigen::Vector2d t(-f.d.y(), f.d.x());
  const int n = std::max(1, static_cast<int>(std::ceil(f.chord / o.piece - 1e-9)));
  const double piece = f.chord / n;
  std::vector<double> integral(static_cast<std::size_t>(n), 0.0);
  for (Eigen::Index i = 0; i < F.rows(); ++i) {
    const Eigen::Vector2d a = X.row(F(i, 0)), b = X.row(F(i, 1)), c = X.row(F(i, 2));
    const Eigen::Vector2d g = (a + b + c) / 3 - f.centre;
    if (std::abs(g.dot(f.d)) > o.band) continue;
    const double s = g.dot(t) + 0.5 * f.chord;
    const int k = std::clamp(static_cast<int>(std::floor(s / piece)), 0, n - 1);
    const double area = 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    const double kn =
        K(i, 0) * f.d.x() * f.d.x() + K(i, 1) * f.d.y() * f.d.y() + 2 * K(i, 2) * f.d.x() * f.d.y();
    integral[static_cast<std::size_t>(k)] += kn * area;
  }
  FoldCrease r;
  double run = 0.0, sum = 0.0;
  int creased = 0;
  for (int k = 0; k <= n; ++k) {
    const double angle = k < n ? std::abs(integral[static_cast<std::size_t>(k)]) / piece : 0.0;
    if (k < n) r.mean_all += angle / n;
    if (k < n && angle > o.threshold) {
      if (run == 0.0) ++r.lines;
      run += piece;
      sum += angle;
      ++creased;
    } else {
      r.longest = std::max(r.longest, run);
      run = 0.0;
    }
  }
  r.creased = creased * piece;
  r.angle = creased > 0 ? sum / creased : 0.0;
  return r;
}

}  // namespace papersim::validation
