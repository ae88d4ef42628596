#include "scenegen/geometry.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace papersim::scenegen {

Eigen::MatrixX3d vertex_normals(const SheetMesh& mesh) {
  Eigen::MatrixX3d n = Eigen::MatrixX3d::Zero(mesh.num_vertices(), 3);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = mesh.positions.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.positions.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.positions.row(mesh.faces(f, 2));
    const Eigen::RowVector3d fn = (b - a).cross(c - a).transpose();  // |fn| = 2 area
    for (int k = 0; k < 3; ++k) n.row(mesh.faces(f, k)) += fn;
  }
  for (int i = 0; i < n.rows(); ++i) {
    const double len = n.row(i).norm();
    n.row(i) = len > 0 ? Eigen::RowVector3d(n.row(i) / len) : Eigen::RowVector3d(0, 0, 1);
  }
  return n;
}

Eigen::Vector3d centre_of_mass(const SheetMesh& mesh) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double area = 0.0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = mesh.positions.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.positions.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.positions.row(mesh.faces(f, 2));
    const double w = 0.5 * (b - a).cross(c - a).norm();
    sum += w * (a + b + c) / 3.0;
    area += w;
  }
  return area > 0 ? Eigen::Vector3d(sum / area) : Eigen::Vector3d(mesh.positions.colwise().mean());
}

MeshBvh::MeshBvh(const SheetMesh& mesh) : m_mesh(mesh) {
  const int nf = mesh.num_faces();
  m_order.resize(nf);
  m_centroids.resize(nf);
  for (int f = 0; f < nf; ++f) {
    m_order[f] = f;
    m_centroids[f] = (mesh.positions.row(mesh.faces(f, 0)) + mesh.positions.row(mesh.faces(f, 1)) +
                      mesh.positions.row(mesh.faces(f, 2)))
                         .transpose() /
                     3.0;
  }
  m_nodes.reserve(2 * nf);
  build(0, nf);
}

int MeshBvh::build(int begin, int end) {
  Node node;
  node.lo.setConstant(std::numeric_limits<double>::infinity());
  node.hi.setConstant(-std::numeric_limits<double>::infinity());
  for (int i = begin; i < end; ++i)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = m_mesh.positions.row(m_mesh.faces(m_order[i], k));
      node.lo = node.lo.cwiseMin(p);
      node.hi = node.hi.cwiseMax(p);
    }
  const int id = static_cast<int>(m_nodes.size());
  m_nodes.push_back(node);
  if (end - begin <= 4) {
    m_nodes[id].begin = begin;
    m_nodes[id].end = end;
    return id;
  }
  int axis = 0;
  (node.hi - node.lo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(m_order.begin() + begin, m_order.begin() + mid, m_order.begin() + end,
                   [&](int a, int b) { return m_centroids[a][axis] < m_centroids[b][axis]; });
  const int left = build(begin, mid);
  const int right = build(mid, end);
  m_nodes[id].left = left;
  m_nodes[id].right = right;
  return id;
}

namespace {

bool box_hit(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& o,
             const Eigen::Vector3d& inv_d, double t0, double t1) {
  for (int k = 0; k < 3; ++k) {
    double ta = (lo[k] - o[k]) * inv_d[k];
    double tb = (hi[k] - o[k]) * inv_d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

std::optional<RayHit> MeshBvh::first_hit(const Eigen::Vector3d& origin,
                                         const Eigen::Vector3d& direction, double t_min,
                                         double t_max, int skip_vertex) const {
  std::optional<RayHit> best;
  if (m_nodes.empty()) return best;
  const Eigen::Vector3d inv_d = direction.cwiseInverse();
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const Node& node = m_nodes[stack.back()];
    stack.pop_back();
    if (!box_hit(node.lo, node.hi, origin, inv_d, t_min, t_max)) continue;
    if (node.left >= 0) {
      stack.push_back(node.left);
      stack.push_back(node.right);
      continue;
    }
    for (int i = node.begin; i < node.end; ++i) {
      const int f = m_order[i];
      if (skip_vertex >= 0 &&
          (m_mesh.faces(f, 0) == skip_vertex || m_mesh.faces(f, 1) == skip_vertex ||
           m_mesh.faces(f, 2) == skip_vertex))
        continue;
      const Eigen::Vector3d a = m_mesh.positions.row(m_mesh.faces(f, 0));
      const Eigen::Vector3d e1 = Eigen::Vector3d(m_mesh.positions.row(m_mesh.faces(f, 1))) - a;
      const Eigen::Vector3d e2 = Eigen::Vector3d(m_mesh.positions.row(m_mesh.faces(f, 2))) - a;
      const Eigen::Vector3d p = direction.cross(e2);
      const double det = e1.dot(p);
      if (std::abs(det) < 1e-300) continue;
      const Eigen::Vector3d s = origin - a;
      const double b1 = s.dot(p) / det;
      if (b1 < 0.0 || b1 > 1.0) continue;
      const Eigen::Vector3d q = s.cross(e1);
      const double b2 = direction.dot(q) / det;
      if (b2 < 0.0 || b1 + b2 > 1.0) continue;
      const double t = e2.dot(q) / det;
      if (t <= t_min || t >= t_max) continue;
      t_max = t;
      best = RayHit{f, t, Eigen::Vector3d(1.0 - b1 - b2, b1, b2)};
    }
  }
  return best;
}

UvLocator::UvLocator(const SheetMesh& mesh) : m_mesh(mesh) {
  m_n = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(mesh.num_faces()) / 2.0)));
  m_cells.assign(static_cast<std::size_t>(m_n) * m_n, {});
  for (int f = 0; f < mesh.num_faces(); ++f) {
    Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
    for (int k = 0; k < 3; ++k) {
      lo = lo.cwiseMin(Eigen::Vector2d(mesh.uv.row(mesh.faces(f, k))));
      hi = hi.cwiseMax(Eigen::Vector2d(mesh.uv.row(mesh.faces(f, k))));
    }
    const auto cell = [&](double t) { return std::clamp(static_cast<int>(t * m_n), 0, m_n - 1); };
    for (int j = cell(lo.y() - 1e-6); j <= cell(hi.y() + 1e-6); ++j)
      for (int i = cell(lo.x() - 1e-6); i <= cell(hi.x() + 1e-6); ++i)
        m_cells[static_cast<std::size_t>(j) * m_n + i].push_back(f);
  }
}

std::optional<RayHit> UvLocator::locate(const Eigen::Vector2d& p, double eps) const {
  if (p.x() < -eps || p.y() < -eps || p.x() > 1 + eps || p.y() > 1 + eps) return std::nullopt;
  const int i = std::clamp(static_cast<int>(p.x() * m_n), 0, m_n - 1);
  const int j = std::clamp(static_cast<int>(p.y() * m_n), 0, m_n - 1);
  std::optional<RayHit> best;
  double best_violation = eps;
  for (int f : m_cells[static_cast<std::size_t>(j) * m_n + i]) {
    const Eigen::Vector2d a = m_mesh.uv.row(m_mesh.faces(f, 0));
    const Eigen::Vector2d b = m_mesh.uv.row(m_mesh.faces(f, 1));
    const Eigen::Vector2d c = m_mesh.uv.row(m_mesh.faces(f, 2));
    const double det = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    const Eigen::Vector2d d = p - a;
    const double l1 = (d.x() * (c - a).y() - d.y() * (c - a).x()) / det;
    const double l2 = ((b - a).x() * d.y() - (b - a).y() * d.x()) / det;
    const Eigen::Vector3d w(1.0 - l1 - l2, l1, l2);
    const double violation = std::max(0.0, -w.minCoeff());
    if (violation <= best_violation) {
      best_violation = violation;
      best = RayHit{f, 0.0, w};
      if (violation == 0.0) break;
    }
  }
  return best;
}

std::optional<Eigen::Vector3d> UvLocator::world_point(const Eigen::Vector2d& uv_point) const {
  const auto hit = locate(uv_point);
  if (!hit) return std::nullopt;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k)
    p += hit->barycentric[k] * Eigen::Vector3d(m_mesh.positions.row(m_mesh.faces(hit->face, k)));
  return p;
}

}  // namespace papersim::scenegen
