#include "collision/triangle_sdf.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <queue>

namespace papersim::collision {

namespace {

/// A sub-triangle: barycentric corners, its centroid value and lower bound.
struct Node {
  Eigen::Matrix3d corners;  ///< columns: barycentric coordinates of the 3 corners
  double lower = 0.0;       ///< phi >= lower on the sub-triangle [m]
  bool operator<(const Node& o) const { return lower > o.lower; }  // min-heap on lower
};

/// Evaluates the field at barycentric w and keeps the best value in `best`.
class Search {
 public:
  Search(const Collider& collider, const Eigen::Matrix3d& vertices, const Eigen::Affine3d& pose,
         const TriangleSdfParams& params)
      : m_collider(collider), m_vertices(vertices), m_pose(pose), m_params(params) {}

  double evaluate(const Eigen::Vector3d& w) {
    Eigen::Vector3d g;
    const Eigen::Vector3d x = m_vertices * w;
    const double d = m_collider.distance_at_pose(x, m_pose, &g);
    ++best.evaluations;
    if (d < best.distance) {
      best.distance = d;
      best.barycentric = w;
      best.point = x;
      best.gradient = g;
    }
    return d;
  }

  /// Evaluates the centroid and returns the node with its Lipschitz lower bound.
  Node make_node(const Eigen::Matrix3d& corners) {
    const Eigen::Vector3d w = corners.rowwise().mean();
    const Eigen::Vector3d centre = m_vertices * w;
    double radius = 0.0;
    for (int k = 0; k < 3; ++k)
      radius = std::max(radius, (m_vertices * corners.col(k) - centre).norm());
    Node n;
    n.corners = corners;
    n.lower = evaluate(w) - m_params.lipschitz * radius;
    m_radius = radius;
    return n;
  }
  double last_radius() const { return m_radius; }

  TriangleSdfResult best;

 private:
  const Collider& m_collider;
  const Eigen::Matrix3d& m_vertices;
  const Eigen::Affine3d& m_pose;
  const TriangleSdfParams& m_params;
  double m_radius = 0.0;
};

/// The four midpoint children of a sub-triangle.
std::array<Eigen::Matrix3d, 4> split(const Eigen::Matrix3d& c) {
  const Eigen::Vector3d m01 = 0.5 * (c.col(0) + c.col(1)), m12 = 0.5 * (c.col(1) + c.col(2)),
                        m20 = 0.5 * (c.col(2) + c.col(0));
  std::array<Eigen::Matrix3d, 4> out;
  out[0] << c.col(0), m01, m20;
  out[1] << m01, c.col(1), m12;
  out[2] << m20, m12, c.col(2);
  out[3] << m01, m12, m20;
  return out;
}

/// Barycentric coordinates of the point of triangle (columns of v) closest to x: the minimum
/// of |V w - x|^2 over the simplex, by projecting onto the plane then clamping to an edge.
Eigen::Vector3d closest_barycentric(const Eigen::Matrix3d& v, const Eigen::Vector3d& x) {
  const Eigen::Vector3d e0 = v.col(1) - v.col(0), e1 = v.col(2) - v.col(0), r = x - v.col(0);
  Eigen::Matrix2d gram;
  gram << e0.dot(e0), e0.dot(e1), e0.dot(e1), e1.dot(e1);
  const Eigen::Vector2d st = gram.ldlt().solve(Eigen::Vector2d(e0.dot(r), e1.dot(r)));
  Eigen::Vector3d w(1.0 - st.sum(), st.x(), st.y());
  if ((w.array() >= 0.0).all()) return w;
  Eigen::Vector3d best = w;
  double best_d = 1e300;
  for (int k = 0; k < 3; ++k) {  // clamp onto each edge, keep the closest
    const Eigen::Vector3d a = v.col(k), b = v.col((k + 1) % 3);
    const double t =
        std::clamp((x - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-300), 0.0, 1.0);
    const double d = (a + t * (b - a) - x).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best.setZero();
      best[k] = 1.0 - t;
      best[(k + 1) % 3] = t;
    }
  }
  return best;
}

/// Projected gradient descent from the best sample, step halved on failure.
void polish(Search& s, const Eigen::Matrix3d& v, double step, int iterations) {
  for (int it = 0; it < iterations && step > 1e-12; ++it) {
    const Eigen::Vector3d x = s.best.point - step * s.best.gradient;
    const Eigen::Vector3d w = closest_barycentric(v, x);
    const double before = s.best.distance;
    if ((w - s.best.barycentric).norm() < 1e-12) break;  // stuck on the boundary
    if (!(s.evaluate(w) < before)) step *= 0.5;
  }
}

}  // namespace

TriangleSdfResult triangle_min_distance(const Collider& collider, const Eigen::Vector3d& a,
                                        const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                        const Eigen::Affine3d& pose,
                                        const TriangleSdfParams& params) {
  Eigen::Matrix3d vertices;
  vertices << a, b, c;
  Search search(collider, vertices, pose, params);
  std::priority_queue<Node> open;
  open.push(search.make_node(Eigen::Matrix3d::Identity()));
  double lower = std::numeric_limits<double>::infinity();  // min bound of finished nodes
  double leaf_radius = search.last_radius();
  while (!open.empty()) {
    const Node n = open.top();
    open.pop();
    const bool out_of_range = n.lower > params.cutoff || n.lower >= search.best.distance;
    const bool no_budget = search.best.evaluations + 4 > params.max_evaluations;
    if (out_of_range || no_budget) {
      lower = std::min(lower, n.lower);
      continue;
    }
    for (const Eigen::Matrix3d& child : split(n.corners)) {
      const Node m = search.make_node(child);
      leaf_radius = std::min(leaf_radius, search.last_radius());
      if (search.last_radius() <= params.resolution)
        lower = std::min(lower, m.lower);
      else
        open.push(m);
    }
  }
  if (search.best.distance <= params.cutoff)
    polish(search, vertices, leaf_radius, params.polish_iterations);
  search.best.lower_bound = std::min(lower, search.best.distance);
  return search.best;
}

std::vector<FaceSdfContact> mesh_edges_faces_vs_sdf(const Collider& collider,
                                                    const std::vector<Eigen::Vector3d>& positions,
                                                    const std::vector<Eigen::Vector3i>& faces,
                                                    const Eigen::Affine3d& pose,
                                                    const TriangleSdfParams& params) {
  std::vector<TriangleSdfResult> results(faces.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces.size(), 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t f = r.begin(); f != r.end(); ++f) {
                        const Eigen::Vector3i& t = faces[f];
                        results[f] =
                            triangle_min_distance(collider, positions[t[0]], positions[t[1]],
                                                  positions[t[2]], pose, params);
                      }
                    });
  std::vector<FaceSdfContact> contacts;
  for (std::size_t f = 0; f < faces.size(); ++f)
    if (results[f].distance < params.cutoff) contacts.push_back({static_cast<int>(f), results[f]});
  return contacts;
}

}  // namespace papersim::collision
