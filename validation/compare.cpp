#include "validation/compare.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace papersim::validation {

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

namespace {

/// Uniform grid over the material bounding box holding the faces whose box overlaps a cell.
class MaterialLocator {
 public:
  explicit MaterialLocator(const SheetGeometry& s) : m_s(s) {
    m_lo = s.material.colwise().minCoeff().transpose();
    const Eigen::Vector2d hi = s.material.colwise().maxCoeff().transpose();
    const int n = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(s.faces.rows()))));
    m_cell = std::max((hi - m_lo).maxCoeff() / n, 1e-12);
    m_nx = static_cast<int>((hi.x() - m_lo.x()) / m_cell) + 1;
    m_ny = static_cast<int>((hi.y() - m_lo.y()) / m_cell) + 1;
    m_cells.resize(static_cast<size_t>(m_nx) * m_ny);
    for (int f = 0; f < s.faces.rows(); ++f) {
      Eigen::Vector2d flo = s.material.row(s.faces(f, 0)).transpose(), fhi = flo;
      for (int k = 1; k < 3; ++k) {
        flo = flo.cwiseMin(s.material.row(s.faces(f, k)).transpose());
        fhi = fhi.cwiseMax(s.material.row(s.faces(f, k)).transpose());
      }
      const Eigen::Vector2i c0 = cell(flo), c1 = cell(fhi);
      for (int i = c0.x(); i <= c1.x(); ++i)
        for (int j = c0.y(); j <= c1.y(); ++j)
          m_cells[static_cast<size_t>(j) * m_nx + i].push_back(f);
    }
  }

  /// World position of the reference at material point X, or false outside its domain.
  bool interpolate(const Eigen::Vector2d& X, Eigen::Vector3d& out) const {
    const Eigen::Vector2i c = cell(X);
    double best = -std::numeric_limits<double>::infinity();
    for (int f : m_cells[static_cast<size_t>(c.y()) * m_nx + c.x()]) {
      const Eigen::Vector2d a = m_s.material.row(m_s.faces(f, 0)),
                            b = m_s.material.row(m_s.faces(f, 1)),
                            d = m_s.material.row(m_s.faces(f, 2));
      Eigen::Matrix2d T;
      T << b - a, d - a;
      const Eigen::Vector2d l = T.inverse() * (X - a);
      const Eigen::Vector3d w(1 - l.x() - l.y(), l.x(), l.y());
      // Scale the smallest barycentric coordinate to a distance (edge lengths ~ sqrt(area)).
      const double margin = w.minCoeff() * std::sqrt(std::abs(T.determinant()));
      if (margin > best) {
        best = margin;
        out = w[0] * m_s.positions.row(m_s.faces(f, 0)).transpose() +
              w[1] * m_s.positions.row(m_s.faces(f, 1)).transpose() +
              w[2] * m_s.positions.row(m_s.faces(f, 2)).transpose();
      }
    }
    return best >= -1e-9;
  }

 private:
  Eigen::Vector2i cell(const Eigen::Vector2d& X) const {
    const Eigen::Vector2d r = (X - m_lo) / m_cell;
    return {std::clamp(static_cast<int>(r.x()), 0, m_nx - 1),
            std::clamp(static_cast<int>(r.y()), 0, m_ny - 1)};
  }
  const SheetGeometry& m_s;
  Eigen::Vector2d m_lo;
  double m_cell = 1;
  int m_nx = 1, m_ny = 1;
  std::vector<std::vector<int>> m_cells;
};

/// max over the vertices of `from` of the distance to the surface `to` (brute force over the
/// triangles, in parallel over the vertices).
double one_sided_hausdorff(const SheetGeometry& from, const SheetGeometry& to) {
  std::vector<double> d(static_cast<size_t>(from.positions.rows()));
  tbb::parallel_for(Eigen::Index(0), from.positions.rows(), [&](Eigen::Index v) {
    const Eigen::Vector3d p = from.positions.row(v).transpose();
    double best = std::numeric_limits<double>::infinity();
    for (int f = 0; f < to.faces.rows(); ++f) {
      const Eigen::Vector3d q =
          closest_point_on_triangle(p, to.positions.row(to.faces(f, 0)).transpose(),
                                    to.positions.row(to.faces(f, 1)).transpose(),
                                    to.positions.row(to.faces(f, 2)).transpose());
      best = std::min(best, (p - q).squaredNorm());
    }
    d[static_cast<size_t>(v)] = std::sqrt(best);
  });
  return d.empty() ? 0.0 : *std::max_element(d.begin(), d.end());
}

}  // namespace

void best_rigid_motion(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& q, Eigen::Matrix3d& R,
                       Eigen::Vector3d& t) {
  const Eigen::RowVector3d cp = p.colwise().mean(), cq = q.colwise().mean();
  const Eigen::Matrix3d C =
      (p.rowwise() - cp).transpose() * (q.rowwise() - cq);  // sum p_i q_i^T, centred
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  R = svd.matrixV() * D * svd.matrixU().transpose();
  t = cq.transpose() - R * cp.transpose();
}

SheetDifference compare_sheets(const SheetGeometry& reference, const SheetGeometry& test) {
  const MaterialLocator locator(reference);
  SheetDifference r;
  // p: the test's vertices inside the reference's domain; q: the reference at the same points.
  Eigen::MatrixX3d p(test.material.rows(), 3), q(test.material.rows(), 3);
  int n = 0;
  for (Eigen::Index v = 0; v < test.material.rows(); ++v) {
    Eigen::Vector3d x;
    if (!locator.interpolate(test.material.row(v).transpose(), x)) {
      ++r.outside;
      continue;
    }
    q.row(n) = x.transpose();
    p.row(n++) = test.positions.row(v);
  }
  if (n == 0)
    throw CompareError(
        "compare_sheets: no vertex of the test sheet lies in the reference's material domain");
  p.conservativeResize(n, 3);
  q.conservativeResize(n, 3);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  best_rigid_motion(p, q, R, t);
  double sum = 0, sum_aligned = 0;
  for (int i = 0; i < n; ++i) {
    const double e = (q.row(i) - p.row(i)).norm();
    const double a = (q.row(i).transpose() - (R * p.row(i).transpose() + t)).norm();
    sum += e * e, sum_aligned += a * a;
    r.max = std::max(r.max, e);
    r.max_aligned = std::max(r.max_aligned, a);
  }
  r.rms = std::sqrt(sum / n);
  r.rms_aligned = std::sqrt(sum_aligned / n);
  r.hausdorff =
      std::max(one_sided_hausdorff(reference, test), one_sided_hausdorff(test, reference));
  return r;
}

}  // namespace papersim::validation
