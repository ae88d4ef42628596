#include "collision/self_contact.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "collision/barrier.hpp"
#include "collision/collider.hpp"

namespace papersim::collision {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

// ----------------------------------------------------------------------------------------------
// Broad phase: a uniform grid of boxes.

/// A uniform grid over the boxes of `inserted`; queries report each overlapping pair once, in
/// the order of the cells they scan (x, then y, then z) and, within a cell, of the boxes' indices.
///
/// The cells' lists are held densely (a start per cell of the grid's extent, filled by counting)
/// when the extent has few cells for the entries, as a sheet's has; otherwise as entries sorted
/// by cell key, found by binary search. Both hold the same lists, so a query reports the same
/// pairs in the same order.
class BoxGrid {
 public:
  explicit BoxGrid(const std::vector<Aabb>& inserted) : m_boxes(inserted) {
    if (inserted.empty()) return;
    Aabb all;
    double mean = 0, largest = 0;
    for (const Aabb& b : inserted) {
      all.extend(b);
      const double e = (b.hi - b.lo).maxCoeff();
      mean += e;
      largest = std::max(largest, e);
    }
    mean /= static_cast<double>(inserted.size());
    // Cells about the size of a box; a few huge boxes (a vertex with a long step) may not
    // blow the grid up: no box spans more than 8 cells per axis, nor the grid 2^20 per axis.
    m_cell = std::max({mean, largest / 8, (all.hi - all.lo).maxCoeff() / (1 << 20), 1e-9});
    m_origin = all.lo;
    m_low.resize(inserted.size());
    std::vector<Eigen::Array3i> high(inserted.size());
    std::size_t entries = 0;
    for (std::size_t i = 0; i < inserted.size(); ++i) {
      m_low[i] = cell(inserted[i].lo);
      high[i] = cell(inserted[i].hi);
      entries += static_cast<std::size_t>((high[i] - m_low[i] + 1).prod());
    }
    // Every box lies in `all`, so its cells lie in [0, cell(all.hi)].
    m_size = cell(all.hi) + 1;
    const double cells = double(m_size.x()) * double(m_size.y()) * double(m_size.z());
    m_dense = cells <= 4.0 * double(entries) + 65536.0;
    if (m_dense) {
      m_start.assign(static_cast<std::size_t>(cells) + 1, 0);
      for (std::size_t i = 0; i < inserted.size(); ++i)
        for_cells(m_low[i], high[i], [&](std::size_t c) { ++m_start[c + 1]; });
      for (std::size_t c = 1; c < m_start.size(); ++c) m_start[c] += m_start[c - 1];
      m_index.resize(entries);
      std::vector<int> next(m_start.begin(), m_start.end() - 1);
      for (std::size_t i = 0; i < inserted.size(); ++i)
        for_cells(m_low[i], high[i],
                  [&](std::size_t c) { m_index[next[c]++] = static_cast<int>(i); });
    } else {
      m_entries.reserve(entries);
      for (std::size_t i = 0; i < inserted.size(); ++i)
        for_cells(m_low[i], high[i], [&](std::size_t c) {
          m_entries.push_back({c, static_cast<int>(i)});
        });
      std::sort(m_entries.begin(), m_entries.end());
    }
  }

  /// Calls report(i) for every inserted box i > after overlapping q (once each). Each cell holds
  /// its boxes in ascending order, so the boxes at or below `after` are skipped untested.
  template <class Report>
  void query(const Aabb& q, Report&& report, int after = -1) const {
    if (m_boxes.empty()) return;
    const Eigen::Array3i lo = cell(q.lo), hi = cell(q.hi).min(m_size - 1);
    if ((lo > hi).any()) return;
    auto visit = [&](int i, const Eigen::Array3i& here) {
      const Aabb& b = m_boxes[i];
      if ((b.lo.array() > q.hi.array()).any() || (q.lo.array() > b.hi.array()).any()) return;
      // Report the pair only from the cell holding the low corner of the boxes' overlap (cell()
      // is monotone in each axis, so that corner's cell is the larger of the two low cells).
      if ((m_low[i].max(lo) == here).all()) report(i);
    };
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z) {
          const Eigen::Array3i here(x, y, z);
          const std::size_t c = index_of(here);
          if (m_dense) {
            const int* first = m_index.data() + m_start[c];
            const int* last = m_index.data() + m_start[c + 1];
            if (after >= 0) first = std::upper_bound(first, last, after);
            for (; first != last; ++first) visit(*first, here);
          } else {
            auto it = std::lower_bound(m_entries.begin(), m_entries.end(), Entry{c, after + 1});
            for (; it != m_entries.end() && it->cell == c; ++it) visit(it->index, here);
          }
        }
  }

 private:
  struct Entry {
    std::size_t cell;
    int index;
    bool operator<(const Entry& o) const {
      return cell < o.cell || (cell == o.cell && index < o.index);
    }
  };
  Eigen::Array3i cell(const Eigen::Vector3d& p) const {
    const Eigen::Array3d c = ((p - m_origin) / m_cell).array().floor();
    return c.max(0.0).min(double((1 << 21) - 1)).cast<int>();
  }
  /// A cell's place in x, y, z order within the grid's extent.
  std::size_t index_of(const Eigen::Array3i& c) const {
    return (std::size_t(c.x()) * std::size_t(m_size.y()) + std::size_t(c.y())) *
               std::size_t(m_size.z()) +
           std::size_t(c.z());
  }
  template <class F>
  void for_cells(const Eigen::Array3i& lo, const Eigen::Array3i& hi, F&& f) const {
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z) f(index_of(Eigen::Array3i(x, y, z)));
  }

  const std::vector<Aabb>& m_boxes;
  std::vector<Eigen::Array3i> m_low;               ///< each inserted box's lowest cell
  Eigen::Array3i m_size = Eigen::Array3i::Zero();  ///< cells per axis
  bool m_dense = false;
  std::vector<int> m_start,
      m_index;  ///< dense: cell c's boxes are m_index[m_start[c] .. m_start[c + 1])
  std::vector<Entry> m_entries;  ///< sparse: (cell, box) sorted
  Eigen::Vector3d m_origin = Eigen::Vector3d::Zero();
  double m_cell = 1.0;
};

template <int N>
Aabb swept_box(const int* v, const Eigen::VectorXd& x0, const Eigen::VectorXd& x1, double grow) {
  Aabb b;
  for (int k = 0; k < N; ++k) {
    b.extend(Eigen::Vector3d(x0.segment<3>(3 * v[k])));
    b.extend(Eigen::Vector3d(x1.segment<3>(3 * v[k])));
  }
  b.inflate(grow);
  return b;
}

// ----------------------------------------------------------------------------------------------
// Distances.

/// Squared distance from p to segment ab and its stencil (point_point or point_edge), with the
/// stencil's point indices taken from (ip, ia, ib).
double point_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                     int ip, int ia, int ib, DistanceStencil& s) {
  const Eigen::Vector3d e = b - a;
  const double l2 = e.squaredNorm();
  const double t = l2 > 0 ? (p - a).dot(e) / l2 : 0.0;
  if (t <= 0) {
    s = {DistanceType::point_point, {{ip, ia, -1, -1}}};
    return (p - a).squaredNorm();
  }
  if (t >= 1) {
    s = {DistanceType::point_point, {{ip, ib, -1, -1}}};
    return (p - b).squaredNorm();
  }
  s = {DistanceType::point_edge, {{ip, ia, ib, -1}}};
  return (p - a - t * e).squaredNorm();
}

/// The smallest of point-segment candidates (point index, segment end indices).
DistanceStencil closest_of(const PairPoints& x, const std::array<std::array<int, 3>, 4>& c, int n,
                           double* distance2 = nullptr) {
  DistanceStencil best;
  double best_d2 = INF;
  for (int k = 0; k < n; ++k) {
    DistanceStencil s;
    const double d2 =
        point_segment(x[c[k][0]], x[c[k][1]], x[c[k][2]], c[k][0], c[k][1], c[k][2], s);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = s;
    }
  }
  if (distance2) *distance2 = best_d2;
  return best;
}

/// Affine closest-point formulas (IPC distance types): r(beta) = sum_i w_i(beta) x_i with
/// w = w0 + dw beta affine, d^2 = min_beta |r|^2. At the minimiser, by the envelope theorem and
/// implicit differentiation (f = |r|^2, E = X dw):
///   grad_i = 2 w_i r,
///   H = 2 (w w^T kron I) - C (2 E^T E)^-1 C^T,  C(3i.., a) = 2 (w_i e_a + dw_ia r),
/// which is the Hessian of the minimum value function f(x, beta*(x)).
template <int N, int K>
double affine_distance(const PairPoints& x, const std::array<int, 4>& idx,
                       const Eigen::Matrix<double, N, 1>& w0, const Eigen::Matrix<double, N, K>& dw,
                       Eigen::Matrix<double, N, 1>& w, Eigen::Matrix<double, 3 * N, 1>* grad,
                       Eigen::Matrix<double, 3 * N, 3 * N>* hess) {
  Eigen::Matrix<double, 3, N> X;
  for (int i = 0; i < N; ++i) X.col(i) = x[idx[i]];
  const Eigen::Matrix<double, 3, K> E = X * dw;
  const Eigen::Matrix<double, K, K> EtE = E.transpose() * E;
  const Eigen::Matrix<double, K, 1> beta = -EtE.ldlt().solve(E.transpose() * (X * w0));
  w = w0 + dw * beta;
  const Eigen::Vector3d r = X * w;
  if (grad)
    for (int i = 0; i < N; ++i) grad->template segment<3>(3 * i) = 2 * w[i] * r;
  if (hess) {
    Eigen::Matrix<double, 3 * N, K> C;
    for (int i = 0; i < N; ++i)
      for (int a = 0; a < K; ++a)
        C.template block<3, 1>(3 * i, a) = 2 * (w[i] * E.col(a) + dw(i, a) * r);
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j)
        hess->template block<3, 3>(3 * i, 3 * j) = 2 * w[i] * w[j] * Eigen::Matrix3d::Identity();
    *hess -= C * (2 * EtE).inverse() * C.transpose();
  }
  return r.squaredNorm();
}

template <int N, int K>
double stencil_derivatives(const DistanceStencil& s, const PairPoints& x,
                           const Eigen::Matrix<double, N, 1>& w0,
                           const Eigen::Matrix<double, N, K>& dw, Vector12d* g, Matrix12d* H,
                           Eigen::Vector4d* weights) {
  Eigen::Matrix<double, N, 1> w;
  Eigen::Matrix<double, 3 * N, 1> gl;
  Eigen::Matrix<double, 3 * N, 3 * N> hl;
  const double d2 =
      affine_distance<N, K>(x, s.points, w0, dw, w, g ? &gl : nullptr, H ? &hl : nullptr);
  if (g) {
    g->setZero();
    for (int i = 0; i < N; ++i) g->segment<3>(3 * s.points[i]) = gl.template segment<3>(3 * i);
  }
  if (H) {
    H->setZero();
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j)
        H->block<3, 3>(3 * s.points[i], 3 * s.points[j]) = hl.template block<3, 3>(3 * i, 3 * j);
  }
  if (weights) {
    weights->setZero();
    for (int i = 0; i < N; ++i) (*weights)[s.points[i]] = w[i];
  }
  return d2;
}

double evaluate(const DistanceStencil& s, const PairPoints& x, Vector12d* g, Matrix12d* H,
                Eigen::Vector4d* weights) {
  switch (s.type) {
    case DistanceType::point_point: {
      const Eigen::Vector3d r = x[s.points[0]] - x[s.points[1]];
      if (g) {
        g->setZero();
        g->segment<3>(3 * s.points[0]) = 2 * r;
        g->segment<3>(3 * s.points[1]) = -2 * r;
      }
      if (H) {
        H->setZero();
        const Eigen::Matrix3d I2 = 2 * Eigen::Matrix3d::Identity();
        H->block<3, 3>(3 * s.points[0], 3 * s.points[0]) = I2;
        H->block<3, 3>(3 * s.points[1], 3 * s.points[1]) = I2;
        H->block<3, 3>(3 * s.points[0], 3 * s.points[1]) = -I2;
        H->block<3, 3>(3 * s.points[1], 3 * s.points[0]) = -I2;
      }
      if (weights) {
        weights->setZero();
        (*weights)[s.points[0]] = 1;
        (*weights)[s.points[1]] = -1;
      }
      return r.squaredNorm();
    }
    case DistanceType::point_edge:
      return stencil_derivatives<3, 1>(s, x, Eigen::Vector3d(1, -1, 0), Eigen::Vector3d(0, 1, -1),
                                       g, H, weights);
    case DistanceType::point_triangle: {
      Eigen::Matrix<double, 4, 2> dw;
      dw << 0, 0, 1, 1, -1, 0, 0, -1;
      return stencil_derivatives<4, 2>(s, x, Eigen::Vector4d(1, -1, 0, 0), dw, g, H, weights);
    }
    case DistanceType::edge_edge: {
      Eigen::Matrix<double, 4, 2> dw;
      dw << -1, 0, 1, 0, 0, 1, 0, -1;
      return stencil_derivatives<4, 2>(s, x, Eigen::Vector4d(1, 0, -1, 0), dw, g, H, weights);
    }
  }
  return INF;
}

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

double pair_distance_lower_bound(const PairPoints& x, bool edge_edge) {
  if (edge_edge)
    return (0.5 * (x[0] + x[1] - x[2] - x[3])).norm() -
           0.5 * ((x[1] - x[0]).norm() + (x[3] - x[2]).norm());
  const Eigen::Vector3d c = (x[1] + x[2] + x[3]) / 3;
  return (x[0] - c).norm() - std::sqrt(std::max({(x[1] - c).squaredNorm(), (x[2] - c).squaredNorm(),
                                                 (x[3] - c).squaredNorm()}));
}

namespace {

/// Additive CCD (Li et al. 2021, Alg. 1) with thickness `offset`: the gap is the distance of the
/// pair less the offset. The distance changes no faster than the bound lp on the relative speed
/// of the pair's points, and so does the gap.
template <class Distance2>
double additive_ccd(PairPoints x, PairPoints dx, bool edge_edge, double t_max, double s,
                    double offset, Distance2&& distance2) {
  // The distance is translation invariant: remove the mean motion to tighten the bound.
  const Eigen::Vector3d mean = 0.25 * (dx[0] + dx[1] + dx[2] + dx[3]);
  for (auto& p : dx) p -= mean;
  const double lp =
      edge_edge ? std::max(dx[0].norm(), dx[1].norm()) + std::max(dx[2].norm(), dx[3].norm())
                : dx[0].norm() + std::max({dx[1].norm(), dx[2].norm(), dx[3].norm()});
  if (lp == 0) return t_max;
  // Most candidates cannot close their gap within t_max: the bounding-sphere bound shows it
  // without the closest-feature search.
  if (0.9 * (pair_distance_lower_bound(x, edge_edge) - offset) >= lp * t_max) return t_max;
  double d = std::sqrt(distance2(x)) - offset;
  if (!(d > 0)) return 0.0;
  const double g = s * d;
  double t = 0, tl = (1 - s) * d / lp;
  // Every step of tl = 0.9 d / lp keeps the gap above 0.1 d > 0; t grows by at least
  // 0.9 g / lp per step. The cap only guards against pathological grazing; t stays safe.
  for (int it = 0; it < 100000; ++it) {
    for (int k = 0; k < 4; ++k) x[k] += tl * dx[k];
    d = std::sqrt(distance2(x)) - offset;
    if (t > 0 && d < g) return t;
    t += tl;
    if (t >= t_max) return t_max;
    tl = 0.9 * d / lp;
  }
  return t;
}

}  // namespace

// ------------------------------------------------------------------------------------------------

SelfContactMesh SelfContactMesh::from_faces(const Eigen::MatrixX3i& faces, int num_vertices) {
  SelfContactMesh m;
  m.faces = faces;
  m.num_vertices = num_vertices;
  std::vector<std::array<int, 2>> e;
  e.reserve(3 * faces.rows());
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = faces(f, k), b = faces(f, (k + 1) % 3);
      if (a < 0 || a >= num_vertices || b < 0 || b >= num_vertices)
        throw std::invalid_argument("self contact: face index out of range");
      e.push_back({{std::min(a, b), std::max(a, b)}});
    }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  m.edges.resize(static_cast<Eigen::Index>(e.size()), 2);
  for (size_t i = 0; i < e.size(); ++i)
    m.edges.row(static_cast<Eigen::Index>(i)) << e[i][0], e[i][1];
  return m;
}

SelfContactCandidates find_self_contact_candidates(const SelfContactMesh& mesh,
                                                   const Eigen::VectorXd& x0,
                                                   const Eigen::VectorXd& x1, double radius) {
  SelfContactCandidates out;
  // Two primitives within `radius` have boxes within `radius` in every axis: growing each box
  // by half of it (and a hair for round-off) makes them overlap.
  const double grow = 0.5 * radius * (1 + 1e-9) + 1e-15;
  const Eigen::Index nf = mesh.faces.rows(), ne = mesh.edges.rows();
  std::vector<Aabb> face_boxes(nf), edge_boxes(ne), vertex_boxes(mesh.num_vertices);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const int v[3] = {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2)};
    face_boxes[f] = swept_box<3>(v, x0, x1, grow);
  }
  for (Eigen::Index e = 0; e < ne; ++e) {
    const int v[2] = {mesh.edges(e, 0), mesh.edges(e, 1)};
    edge_boxes[e] = swept_box<2>(v, x0, x1, grow);
  }
  for (int v = 0; v < mesh.num_vertices; ++v) vertex_boxes[v] = swept_box<1>(&v, x0, x1, grow);

  const BoxGrid faces(face_boxes);
  for (int v = 0; v < mesh.num_vertices; ++v)
    faces.query(vertex_boxes[v], [&](int f) {
      if (mesh.faces(f, 0) != v && mesh.faces(f, 1) != v && mesh.faces(f, 2) != v)
        out.point_triangle.push_back({{v, f}});
    });
  const BoxGrid edges(edge_boxes);
  for (int a = 0; a < static_cast<int>(ne); ++a)
    edges.query(
        edge_boxes[a],
        [&](int b) {
          const int a0 = mesh.edges(a, 0), a1 = mesh.edges(a, 1), b0 = mesh.edges(b, 0),
                    b1 = mesh.edges(b, 1);
          if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) return;
          out.edge_edge.push_back({{a, b}});
        },
        a);
  // The grid reports a vertex's faces in the order of its cells; sorted, the pairs near each
  // other are summed in the same order whatever positions the set was found at (a run continued
  // from a checkpoint finds its set at other positions than the run it continues).
  std::sort(out.point_triangle.begin(), out.point_triangle.end());
  std::sort(out.edge_edge.begin(), out.edge_edge.end());
  return out;
}

int DistanceStencil::count() const {
  switch (type) {
    case DistanceType::point_point:
      return 2;
    case DistanceType::point_edge:
      return 3;
    default:
      return 4;
  }
}

DistanceStencil point_triangle_stencil(const PairPoints& x) {
  const Eigen::Vector3d e1 = x[2] - x[1], e2 = x[3] - x[1], q = x[0] - x[1];
  const Eigen::Vector3d n = e1.cross(e2);
  // Proper triangle: project p onto its plane and test the barycentric coordinates.
  if (n.squaredNorm() > 1e-20 * e1.squaredNorm() * e2.squaredNorm()) {
    Eigen::Matrix2d A;
    A << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    const Eigen::Vector2d b = A.ldlt().solve(Eigen::Vector2d(e1.dot(q), e2.dot(q)));
    if (b[0] >= 0 && b[1] >= 0 && b[0] + b[1] <= 1)
      return {DistanceType::point_triangle, {{0, 1, 2, 3}}};
  }
  // Outside (or degenerate): the closest point lies on the boundary.
  return closest_of(x, {{{{0, 1, 2}}, {{0, 2, 3}}, {{0, 3, 1}}, {{0, 0, 0}}}}, 3);
}

DistanceStencil edge_edge_stencil(const PairPoints& x) {
  const Eigen::Vector3d u = x[1] - x[0], v = x[3] - x[2], w = x[0] - x[2];
  const double a = u.squaredNorm(), b = u.dot(v), c = v.squaredNorm(), d = u.dot(w), e = v.dot(w);
  // Candidates on the boundary of the parameter square: an endpoint against the other segment
  // (this holds the minimum for parallel segments, where the distance is constant along the
  // overlap).
  double boundary_d2 = INF;
  const DistanceStencil boundary =
      closest_of(x, {{{{0, 2, 3}}, {{1, 2, 3}}, {{2, 0, 1}}, {{3, 0, 1}}}}, 4, &boundary_d2);
  const double D = u.cross(v).squaredNorm();  // = a c - b^2, without cancellation
  if (D > 1e-20 * a * c) {
    const double s = (b * e - c * d) / D, t = (a * e - b * d) / D;
    // For nearly parallel (or collinear) segments s and t are ill-conditioned and may land
    // inside the square by round-off while the lines nearly coincide (line distance ~0, segment
    // distance large): the interior type is taken only when the points it names really are
    // closer than every boundary candidate.
    if (s > 0 && s < 1 && t > 0 && t < 1 && (w + s * u - t * v).squaredNorm() < boundary_d2)
      return {DistanceType::edge_edge, {{0, 1, 2, 3}}};
  }
  return boundary;
}

double distance_squared(const DistanceStencil& s, const PairPoints& x) {
  const auto& p = s.points;
  switch (s.type) {
    case DistanceType::point_point:
      return (x[p[0]] - x[p[1]]).squaredNorm();
    case DistanceType::point_edge: {
      const Eigen::Vector3d e = x[p[2]] - x[p[1]];
      return e.cross(x[p[0]] - x[p[1]]).squaredNorm() / e.squaredNorm();
    }
    case DistanceType::point_triangle: {
      const Eigen::Vector3d n = (x[p[2]] - x[p[1]]).cross(x[p[3]] - x[p[1]]);
      const double h = n.dot(x[p[0]] - x[p[1]]);
      return h * h / n.squaredNorm();
    }
    case DistanceType::edge_edge: {
      const Eigen::Vector3d n = (x[p[1]] - x[p[0]]).cross(x[p[3]] - x[p[2]]);
      const double h = n.dot(x[p[2]] - x[p[0]]);
      return h * h / n.squaredNorm();
    }
  }
  return INF;
}

double distance_squared_derivatives(const DistanceStencil& s, const PairPoints& x,
                                    Vector12d& gradient, Matrix12d* hessian) {
  return evaluate(s, x, &gradient, hessian, nullptr);
}

Eigen::Vector4d closest_point_weights(const DistanceStencil& s, const PairPoints& x) {
  Eigen::Vector4d w;
  evaluate(s, x, nullptr, nullptr, &w);
  return w;
}

double point_triangle_distance_squared(const PairPoints& x) {
  return distance_squared(point_triangle_stencil(x), x);
}

double edge_edge_distance_squared(const PairPoints& x) {
  return distance_squared(edge_edge_stencil(x), x);
}

double edge_edge_mollifier_threshold(double rest_length_a, double rest_length_b) {
  return 1e-3 * rest_length_a * rest_length_a * rest_length_b * rest_length_b;
}

double edge_edge_mollifier(const PairPoints& x, double eps, Vector12d* gradient,
                           Matrix12d* hessian) {
  const Eigen::Vector3d u = x[1] - x[0], v = x[3] - x[2], w = u.cross(v);
  const double c = w.squaredNorm();
  if (c >= eps) {
    if (gradient) gradient->setZero();
    if (hessian) hessian->setZero();
    return 1.0;
  }
  const double m = (2 - c / eps) * c / eps, dm = 2 / eps - 2 * c / (eps * eps),
               ddm = -2 / (eps * eps);
  // c = |u x v|^2: dc/du = 2 v x w, dc/dv = 2 w x u; second derivatives (derived from
  // dw = du x v + u x dv): Huu = 2(|v|^2 I - v v^T), Hvv = 2(|u|^2 I - u u^T),
  // Huv = 2(u v^T - (u.v) I - [w]x).
  Eigen::Matrix<double, 6, 1> gc;
  gc << 2 * v.cross(w), 2 * w.cross(u);
  // d(u, v) / d(a0, a1, b0, b1)
  Eigen::Matrix<double, 6, 12> J = Eigen::Matrix<double, 6, 12>::Zero();
  J.block<3, 3>(0, 0) = -Eigen::Matrix3d::Identity();
  J.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity();
  J.block<3, 3>(3, 6) = -Eigen::Matrix3d::Identity();
  J.block<3, 3>(3, 9) = Eigen::Matrix3d::Identity();
  const Vector12d grad_c = J.transpose() * gc;
  if (gradient) *gradient = dm * grad_c;
  if (hessian) {
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    Eigen::Matrix<double, 6, 6> Hc;
    Hc.block<3, 3>(0, 0) = 2 * (v.squaredNorm() * I - v * v.transpose());
    Hc.block<3, 3>(3, 3) = 2 * (u.squaredNorm() * I - u * u.transpose());
    Hc.block<3, 3>(0, 3) = 2 * (u * v.transpose() - u.dot(v) * I - cross_matrix(w));
    Hc.block<3, 3>(3, 0) = Hc.block<3, 3>(0, 3).transpose();
    *hessian = ddm * grad_c * grad_c.transpose() + dm * J.transpose() * Hc * J;
  }
  return m;
}

double pair_barrier_derivatives(const DistanceStencil& s, const PairPoints& pts, double dhat,
                                double mollifier_eps, Vector12d& grad, Matrix12d* hess,
                                double offset) {
  Vector12d g2;
  Matrix12d H2;
  const double d2 = distance_squared_derivatives(s, pts, g2, hess ? &H2 : nullptr);
  // b(d) with d = |r| - offset, |r| = sqrt(d^2): grad d = grad d^2 / (2 |r|),
  // Hess d = (Hess d^2 - 2 grad d grad d^T) / (2 |r|).
  const double r = std::sqrt(d2), d = r - offset;
  const Vector12d gd = g2 / (2 * r);
  const double b = barrier(d, dhat), b1 = barrier_first_derivative(d, dhat);
  grad = b1 * gd;
  if (hess)
    *hess = barrier_second_derivative(d, dhat) * gd * gd.transpose() +
            b1 * (H2 - 2 * gd * gd.transpose()) / (2 * r);
  if (mollifier_eps <= 0) return b;
  // Mollified: E = m b, grad = m grad b + b grad m, Hess = m Hb + grad b grad m^T + grad m grad b^T
  // + b Hm.
  Vector12d gm;
  Matrix12d Hm;
  const double m = edge_edge_mollifier(pts, mollifier_eps, &gm, hess ? &Hm : nullptr);
  if (hess) *hess = m * *hess + grad * gm.transpose() + gm * grad.transpose() + b * Hm;
  grad = m * grad + b * gm;
  return m * b;
}

double point_triangle_ccd(const PairPoints& x, const PairPoints& dx, double t_max,
                          double min_separation, double offset) {
  return additive_ccd(x, dx, false, t_max, min_separation, offset,
                      [](const PairPoints& y) { return point_triangle_distance_squared(y); });
}

double edge_edge_ccd(const PairPoints& x, const PairPoints& dx, double t_max,
                     double min_separation) {
  return additive_ccd(x, dx, true, t_max, min_separation, 0.0,
                      [](const PairPoints& y) { return edge_edge_distance_squared(y); });
}

double min_self_distance(const SelfContactMesh& mesh, const Eigen::VectorXd& x, double radius) {
  const SelfContactCandidates c = find_self_contact_candidates(mesh, x, x, radius);
  double d2 = INF;
  auto p = [&](int v) { return Eigen::Vector3d(x.segment<3>(3 * v)); };
  for (const auto& [v, f] : c.point_triangle)
    d2 = std::min(d2, point_triangle_distance_squared(
                          {p(v), p(mesh.faces(f, 0)), p(mesh.faces(f, 1)), p(mesh.faces(f, 2))}));
  for (const auto& [a, b] : c.edge_edge)
    d2 = std::min(d2, edge_edge_distance_squared({p(mesh.edges(a, 0)), p(mesh.edges(a, 1)),
                                                  p(mesh.edges(b, 0)), p(mesh.edges(b, 1))}));
  const double d = std::sqrt(d2);
  return d < radius ? d : INF;
}

}  // namespace papersim::collision
