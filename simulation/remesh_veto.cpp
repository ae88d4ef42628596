#include "simulation/remesh_veto.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "collision/self_contact.hpp"
#include "collision/shapes.hpp"
#include "remesh/mesh_editor.hpp"
#include "simulation/energies/membrane_energy.hpp"

namespace papersim::simulation {

namespace {

/// True when segment p q crosses triangle t (rows = corners), interior or boundary
/// (Moller-Trumbore on the segment's parameter range).
bool segment_crosses_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                              const Eigen::Matrix3d& t) {
  const Eigen::Vector3d e1 = t.row(1) - t.row(0), e2 = t.row(2) - t.row(0), d = q - p;
  const Eigen::Vector3d h = d.cross(e2);
  const double a = e1.dot(h);
  const double scale = e1.norm() * e2.norm() * d.norm();
  if (std::abs(a) <= 1e-14 * scale) return false;  // parallel: the edge distances decide
  const Eigen::Vector3d s = p - t.row(0).transpose();
  const double u = s.dot(h) / a;
  if (u < 0 || u > 1) return false;
  const Eigen::Vector3d r = s.cross(e1);
  const double v = d.dot(r) / a;
  if (v < 0 || u + v > 1) return false;
  const double w = e2.dot(r) / a;
  return w >= 0 && w <= 1;
}

/// Right Cauchy-Green tensor of the triangle with world corners x and material corners X (rows).
Eigen::Matrix2d cauchy_green(const Eigen::Matrix3d& x, const Eigen::Matrix<double, 3, 2>& X) {
  Eigen::Matrix2d Dm;
  Dm.col(0) = (X.row(1) - X.row(0)).transpose();
  Dm.col(1) = (X.row(2) - X.row(0)).transpose();
  Eigen::Matrix<double, 3, 2> Ds;
  Ds.col(0) = (x.row(1) - x.row(0)).transpose();
  Ds.col(1) = (x.row(2) - x.row(0)).transpose();
  const Eigen::Matrix<double, 3, 2> F = Ds * Dm.inverse();
  return F.transpose() * F;
}

/// Principal stretches (smallest, largest) of a right Cauchy-Green tensor [-].
Eigen::Vector2d principal_stretches(const Eigen::Matrix2d& C) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C).eigenvalues().cwiseMax(0.0).cwiseSqrt();
}

}  // namespace

double triangle_distance(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  for (int i = 0; i < 3; ++i) {
    if (segment_crosses_triangle(a.row(i), a.row((i + 1) % 3), b)) return 0.0;
    if (segment_crosses_triangle(b.row(i), b.row((i + 1) % 3), a)) return 0.0;
  }
  double d2 = INFINITY;
  for (int i = 0; i < 3; ++i) {
    d2 = std::min(
        d2, collision::point_triangle_distance_squared({a.row(i), b.row(0), b.row(1), b.row(2)}));
    d2 = std::min(
        d2, collision::point_triangle_distance_squared({b.row(i), a.row(0), a.row(1), a.row(2)}));
    for (int j = 0; j < 3; ++j)
      d2 = std::min(d2, collision::edge_edge_distance_squared(
                            {a.row(i), a.row((i + 1) % 3), b.row(j), b.row((j + 1) % 3)}));
  }
  return std::sqrt(d2);
}

RemeshVeto::RemeshVeto(std::vector<std::shared_ptr<const collision::Collider>> obstacles,
                       const remesh::SheetMesh& mesh, const Eigen::MatrixX3d& positions,
                       const RemeshVetoParams& params)
    : m_obstacles(std::move(obstacles)), m_params(params) {
  for (const auto& o : m_obstacles) {
    collision::Aabb b = o->bounds(params.time);
    collision::Aabb r = b;
    b.inflate(params.obstacle_gap);
    m_bounds.push_back(b);
    r.inflate(std::max(params.obstacle_reach, params.obstacle_gap));
    m_reach_bounds.push_back(r);
    const collision::Shape* analytic = o->analytic_shape();
    if (!analytic) continue;
    const Eigen::Affine3d pose = o->motion.pose(params.time);
    if (analytic->kind == collision::ShapeKind::sphere) {
      m_spheres.emplace_back(pose.translation(), analytic->radius * pose.linear().col(0).norm());
      continue;
    }
    const collision::PolytopeFeatures local = collision::polytope_features(*analytic);
    const int first = static_cast<int>(m_corners.size());
    for (const auto& c : local.corners) m_corners.push_back(pose * c);
    for (const auto& e : local.edges) m_edges.push_back({first + e[0], first + e[1]});
  }
  if (params.self_gap <= 0) return;
  const Eigen::MatrixX3i F = mesh.faces();
  double mean_edge = 0;
  for (int f = 0; f < F.rows(); ++f)
    mean_edge += (positions.row(F(f, 1)) - positions.row(F(f, 0))).norm();
  m_cell = std::max(2 * params.self_gap, 2 * mean_edge / std::max<Eigen::Index>(1, F.rows()));
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Vector3d lo = positions.row(F(f, 0)).transpose(), hi = lo;
    for (int k = 1; k < 3; ++k) {
      lo = lo.cwiseMin(positions.row(F(f, k)).transpose());
      hi = hi.cwiseMax(positions.row(F(f, k)).transpose());
    }
    const Eigen::Vector3i c0 = (lo / m_cell).array().floor().cast<int>(),
                          c1 = (hi / m_cell).array().floor().cast<int>();
    for (int i = c0.x(); i <= c1.x(); ++i)
      for (int j = c0.y(); j <= c1.y(); ++j)
        for (int k = c0.z(); k <= c1.z(); ++k) m_grid[cell_key({i, j, k})].push_back(f);
  }
}

long long RemeshVeto::cell_key(const Eigen::Vector3i& c) const {
  return (static_cast<long long>(c.x() & 0x1FFFFF) << 42) |
         (static_cast<long long>(c.y() & 0x1FFFFF) << 21) |
         static_cast<long long>(c.z() & 0x1FFFFF);
}

std::vector<int> RemeshVeto::faces_near(const Eigen::Vector3d& lo,
                                        const Eigen::Vector3d& hi) const {
  std::vector<int> faces;
  const Eigen::Vector3i c0 = (lo / m_cell).array().floor().cast<int>(),
                        c1 = (hi / m_cell).array().floor().cast<int>();
  for (int i = c0.x(); i <= c1.x(); ++i)
    for (int j = c0.y(); j <= c1.y(); ++j)
      for (int k = c0.z(); k <= c1.z(); ++k) {
        const auto it = m_grid.find(cell_key({i, j, k}));
        if (it != m_grid.end()) faces.insert(faces.end(), it->second.begin(), it->second.end());
      }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

std::string RemeshVeto::stretch_reason(const remesh::EditProposal& edit) const {
  // A split's triangles keep the deformation gradient of their parents, below the limit as in
  // every accepted state (checked to round-off); flips and collapses keep within the tolerance.
  const bool split = edit.kind == remesh::EditKind::split;
  const double hi = 1 + (split ? m_params.strain_limit : m_params.strain_tolerance);
  const double lo = split ? 0.0 : 1 - m_params.strain_tolerance;
  for (size_t f = 0; f < edit.world.size(); ++f) {
    const Eigen::Vector2d s =
        split || m_curvatures.rows() == 0
            ? principal_stretches(cauchy_green(edit.world[f], edit.material[f]))
            : arc_stretches(edit, f);
    if (!(s[1] < hi)) return "stretch";
    if (!(s[0] > lo)) return "compression";
  }
  return {};
}

Eigen::Vector2d RemeshVeto::arc_stretches(const remesh::EditProposal& edit, size_t f) const {
  // The face's curvature: the mean of its corners' that the starting mesh had (a vertex a split
  // of this pass inserted has none).
  Eigen::Vector3d K = Eigen::Vector3d::Zero();
  int known = 0;
  for (int v : edit.vertices[f])
    if (v >= 0 && v < m_curvatures.rows()) K += m_curvatures.row(v).transpose(), ++known;
  const Eigen::Matrix<double, 3, 2>& X = edit.material[f];
  Eigen::Matrix2d C = cauchy_green(edit.world[f], X);
  if (known == 0) return principal_stretches(C);
  K /= known;
  // C' = C + G delta as the arc membrane has it: row j of A maps C to the squared length of the
  // edge opposite corner j, so G = A^-1.
  const double area = 0.5 * std::abs((X(1, 0) - X(0, 0)) * (X(2, 1) - X(0, 1)) -
                                     (X(1, 1) - X(0, 1)) * (X(2, 0) - X(0, 0)));
  Eigen::Matrix3d A;
  Eigen::Vector3d delta;
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector2d e = (X.row((j + 2) % 3) - X.row((j + 1) % 3)).transpose();
    const double L = e.norm();
    A.row(j) << e.x() * e.x(), e.y() * e.y(), 2 * e.x() * e.y();
    const Eigen::RowVector3d q(e.x() * e.x() / (L * L), e.y() * e.y() / (L * L),
                               2 * e.x() * e.y() / (L * L));
    delta[j] = MembraneEnergy::arc_correction(L, std::sqrt(2 * area), q, K);
  }
  const Eigen::Vector3d c = Eigen::Vector3d(C(0, 0), C(1, 1), C(0, 1)) + A.inverse() * delta;
  C << c[0], c[2], c[2], c[1];
  return principal_stretches(C);
}

bool RemeshVeto::near_obstacle(const Eigen::Vector3d& p) const {
  for (size_t o = 0; o < m_obstacles.size(); ++o) {
    if (m_bounds[o].distance_to(p) > 0) continue;
    if (!(m_obstacles[o]->distance(p, m_params.time) >= m_params.obstacle_gap)) return true;
  }
  return false;
}

bool RemeshVeto::deeper_in_barrier(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b) const {
  if (!(m_params.obstacle_reach > 0)) return false;
  for (size_t o = 0; o < m_obstacles.size(); ++o) {
    if (m_reach_bounds[o].distance_to(p) > 0) continue;
    const double d = m_obstacles[o]->distance(p, m_params.time);
    if (!(d < m_params.obstacle_reach)) continue;
    const double linear = 0.5 * (m_obstacles[o]->distance(a, m_params.time) +
                                 m_obstacles[o]->distance(b, m_params.time));
    if (d < std::min(linear, m_params.obstacle_reach) - 1e-3 * m_params.obstacle_reach) return true;
  }
  return false;
}

bool RemeshVeto::deeper_in_barrier(const Eigen::Matrix3d& t) const {
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d a = t.row(k), b = t.row((k + 1) % 3);
    if (deeper_in_barrier(0.5 * (a + b), a, b)) return true;
  }
  return false;
}

bool RemeshVeto::near_polytope_features(const Eigen::Matrix3d& t) const {
  const double gap2 = m_params.obstacle_gap * m_params.obstacle_gap;
  for (const auto& c : m_corners)
    if (collision::point_triangle_distance_squared({c, t.row(0), t.row(1), t.row(2)}) < gap2)
      return true;
  for (const auto& [i, j] : m_edges) {
    const Eigen::Vector3d &p = m_corners[i], &q = m_corners[j];
    if (segment_crosses_triangle(p, q, t)) return true;
    for (int k = 0; k < 3; ++k)
      if (collision::edge_edge_distance_squared({p, q, t.row(k), t.row((k + 1) % 3)}) < gap2)
        return true;
  }
  return false;
}

bool RemeshVeto::near_sphere(const Eigen::Matrix3d& t) const {
  for (const auto& [centre, radius] : m_spheres) {
    const double d2 =
        collision::point_triangle_distance_squared({centre, t.row(0), t.row(1), t.row(2)});
    if (!(d2 >= (radius + m_params.obstacle_gap) * (radius + m_params.obstacle_gap))) return true;
  }
  return false;
}

bool RemeshVeto::near_sheet(const remesh::EditProposal& edit, int f) const {
  const remesh::TriMesh& mesh = edit.editor->mesh();
  const Eigen::Matrix3d& tri = edit.world[f];
  const Eigen::Vector3d lo = tri.colwise().minCoeff().transpose().array() - m_params.self_gap;
  const Eigen::Vector3d hi = tri.colwise().maxCoeff().transpose().array() + m_params.self_gap;
  for (int g : faces_near(lo, hi)) {
    if (std::find(edit.removed_faces.begin(), edit.removed_faces.end(), g) !=
        edit.removed_faces.end())
      continue;
    const OpenMesh::FaceHandle fh(g);
    if (mesh.status(fh).deleted()) continue;
    Eigen::Matrix3d other;
    bool shares = false;
    int k = 0;
    for (auto v : mesh.fv_range(fh)) {
      shares = shares || std::find(edit.vertices[f].begin(), edit.vertices[f].end(), v.idx()) !=
                             edit.vertices[f].end();
      other.row(k++) = edit.editor->position(v).transpose();
    }
    if (!shares && triangle_distance(tri, other) < m_params.self_gap) return true;
  }
  return false;
}

std::string RemeshVeto::operator()(const remesh::EditProposal& edit) const {
  if (std::string r = stretch_reason(edit); !r.empty()) return r;
  if (edit.kind == remesh::EditKind::split) {
    // The inserted vertex (index -1) is the only new point; its triangles lie in the old planes.
    for (size_t f = 0; f < edit.vertices.size(); ++f)
      for (int k = 0; k < 3; ++k)
        if (edit.vertices[f][k] < 0 && near_obstacle(edit.world[f].row(k).transpose()))
          return "obstacle";
    // Faces (a, new, c) and (new, b, c): the new vertex lies between a and b.
    if (edit.world.size() >= 2 &&
        deeper_in_barrier(edit.world[0].row(1).transpose(), edit.world[0].row(0).transpose(),
                          edit.world[1].row(1).transpose()))
      return "barrier";
    return {};
  }
  for (size_t f = 0; f < edit.world.size(); ++f) {
    const Eigen::Matrix3d& t = edit.world[f];
    const Eigen::Vector3d centroid = t.colwise().mean().transpose();
    if (near_obstacle(centroid)) return "obstacle";
    for (int k = 0; k < 3; ++k)
      if (near_obstacle(0.5 * (t.row(k) + t.row((k + 1) % 3)).transpose())) return "obstacle";
    if (near_polytope_features(t) || near_sphere(t)) return "obstacle";
  }
  for (const Eigen::Matrix3d& t : edit.world)
    if (deeper_in_barrier(t)) return "barrier";
  if (m_params.self_gap > 0)
    for (size_t f = 0; f < edit.world.size(); ++f)
      if (near_sheet(edit, static_cast<int>(f))) return "self";
  return {};
}

Eigen::VectorXd approach_distance(
    const std::vector<std::shared_ptr<const collision::Collider>>& obstacles,
    const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities, double t,
    double lookahead) {
  Eigen::VectorXd d =
      Eigen::VectorXd::Constant(positions.rows(), std::numeric_limits<double>::infinity());
  for (const auto& o : obstacles) {
    const Eigen::Affine3d pose = o->motion.pose(t);
    const Eigen::Vector3d obstacle_velocity = o->motion.linear_velocity(t);
    for (Eigen::Index v = 0; v < positions.rows(); ++v) {
      Eigen::Vector3d gradient;
      const double distance = o->distance_at_pose(positions.row(v).transpose(), pose, &gradient);
      const double closing = -(velocities.row(v).transpose() - obstacle_velocity).dot(gradient);
      d(v) = std::min(d(v), distance - std::max(closing, 0.0) * lookahead);
    }
  }
  return d;
}

}  // namespace papersim::simulation
