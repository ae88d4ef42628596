#include "simulation/energies/contact_energy.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "collision/barrier.hpp"
#include "collision/shapes.hpp"
#include "simulation/energies/psd.hpp"
#include "simulation/energies/scoped_timer.hpp"
#include "simulation/errors.hpp"

namespace papersim::simulation {

using collision::barrier;
using collision::barrier_first_derivative;
using collision::barrier_second_derivative;

ObstacleContactEnergy::ObstacleContactEnergy(
    Eigen::VectorXd vertex_areas, std::vector<std::shared_ptr<const collision::Collider>> obstacles,
    const ContactParams& params)
    : m_area(std::move(vertex_areas)),
      m_obstacles(std::move(obstacles)),
      m_params(params),
      m_stiffness(params.stiffness) {
  m_mode.assign(m_obstacles.size(), Mode::vertices);
  m_rigid.assign(m_obstacles.size(), -1);
  m_sphere_radius.assign(m_obstacles.size(), 0.0);
  // The minimum over a triangle is resolved to a tenth of the contact thickness, and triangles
  // farther than the thickness are not refined (their barrier is zero).
  m_triangle.cutoff = m_params.dhat;
  m_triangle.resolution = 0.1 * m_params.dhat;
}

void ObstacleContactEnergy::set_faces(const Eigen::MatrixX3i& faces, const Eigen::MatrixX2d& X) {
  m_faces = faces;
  const int nf = static_cast<int>(faces.rows());
  m_face_area.resize(nf);
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector2d e1 = X.row(faces(f, 1)) - X.row(faces(f, 0)),
                          e2 = X.row(faces(f, 2)) - X.row(faces(f, 0));
    m_face_area[f] = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
  }
  m_edges = collision::SelfContactMesh::from_faces(faces, static_cast<int>(X.rows())).edges;
  const int ne = static_cast<int>(m_edges.rows());
  m_edge_rest.resize(ne);
  for (int e = 0; e < ne; ++e)
    m_edge_rest[e] = (X.row(m_edges(e, 1)) - X.row(m_edges(e, 0))).norm();
  // Edge weight: a third of the area of the faces at the edge.
  m_edge_area = Eigen::VectorXd::Zero(ne);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = std::min(faces(f, k), faces(f, (k + 1) % 3)),
                b = std::max(faces(f, k), faces(f, (k + 1) % 3));
      int lo = 0, hi = ne;  // edges are sorted by (a, b)
      while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (m_edges(mid, 0) < a || (m_edges(mid, 0) == a && m_edges(mid, 1) < b))
          lo = mid + 1;
        else
          hi = mid;
      }
      m_edge_area[lo] += m_face_area[f] / 3;
    }
  for (size_t o = 0; o < m_obstacles.size(); ++o) {
    const auto* obs = m_obstacles[o].get();
    if (obs->is_plane()) continue;
    const collision::Shape* analytic = obs->analytic_shape();
    // Inverted sphere: r - |p - c| is concave, so its minimum over a triangle is at a vertex
    // (the farthest point from c): the vertex terms are the exact face contact.
    if (analytic && analytic->kind == collision::ShapeKind::inverted_sphere) continue;
    m_mode[o] = Mode::search;
    if (!analytic) continue;
    if (analytic->kind == collision::ShapeKind::sphere) {
      m_mode[o] = Mode::sphere;
      m_sphere_radius[o] = analytic->radius;
    } else if (!collision::polytope_features(*analytic).corners.empty()) {
      m_mode[o] = Mode::polytope;
    }
  }
}

void ObstacleContactEnergy::set_rigid_block(int o, int block) {
  if (m_mode[o] != Mode::vertices)
    throw SceneError(
        "contact: a coupled lifting obstacle needs vertex contact (contact.faces false)");
  m_rigid[o] = block;
}

void ObstacleContactEnergy::add_pattern(SparsityBuilder& pattern) const {
  for (int o = 0; o < num_obstacles(); ++o) {
    if (m_rigid[o] < 0) continue;
    for (int v = 0; v < m_area.size(); ++v) {
      const int c[2] = {v, m_rigid[o]};
      pattern.add_clique(c, 2);
    }
  }
  for (int f = 0; f < m_faces.rows(); ++f) {
    const int v[3] = {m_faces(f, 0), m_faces(f, 1), m_faces(f, 2)};
    pattern.add_clique(v, 3);
  }
}

ObstacleContactEnergy::WorldFeatures ObstacleContactEnergy::world_features(int o, double t) const {
  WorldFeatures w;
  if (m_mode[o] != Mode::polytope) return w;
  const auto& analytic = static_cast<const collision::AnalyticCollider&>(*m_obstacles[o]);
  const collision::PolytopeFeatures local = collision::polytope_features(analytic.shape());
  const Eigen::Affine3d pose = analytic.motion.pose(t);
  for (const auto& c : local.corners) w.corners.push_back(pose * c);
  w.edges = local.edges;
  for (const auto& e : w.edges) w.edge_length.push_back((w.corners[e[1]] - w.corners[e[0]]).norm());
  return w;
}

std::vector<ObstacleContactEnergy::FeaturePair> ObstacleContactEnergy::feature_pairs(
    const Eigen::VectorXd& x, const Eigen::VectorXd* dx, double radius,
    const std::vector<WorldFeatures>& features) const {
  std::vector<FeaturePair> pairs;
  const auto box_of = [&](const int* v, int n) {
    collision::Aabb b;
    for (int k = 0; k < n; ++k) {
      b.extend(Eigen::Vector3d(x.segment<3>(3 * v[k])));
      if (dx) b.extend(Eigen::Vector3d(x.segment<3>(3 * v[k]) + dx->segment<3>(3 * v[k])));
    }
    b.inflate(radius);
    return b;
  };
  const auto overlap = [](const collision::Aabb& a, const collision::Aabb& b) {
    return (a.hi.array() >= b.lo.array()).all() && (a.lo.array() <= b.hi.array()).all();
  };
  for (int o = 0; o < num_obstacles(); ++o) {
    if (m_mode[o] != Mode::polytope) continue;
    const WorldFeatures& w = features[o];
    collision::Aabb whole;
    for (const auto& c : w.corners) whole.extend(c);
    std::vector<collision::Aabb> edge_box(w.edges.size());
    for (size_t e = 0; e < w.edges.size(); ++e) {
      edge_box[e].extend(w.corners[w.edges[e][0]]);
      edge_box[e].extend(w.corners[w.edges[e][1]]);
    }
    for (int f = 0; f < m_faces.rows(); ++f) {
      const int v[3] = {m_faces(f, 0), m_faces(f, 1), m_faces(f, 2)};
      const collision::Aabb b = box_of(v, 3);
      if (!overlap(b, whole)) continue;
      for (size_t c = 0; c < w.corners.size(); ++c)
        if (b.distance_to(w.corners[c]) == 0) pairs.push_back({o, false, static_cast<int>(c), f});
    }
    for (int e = 0; e < m_edges.rows(); ++e) {
      const int v[2] = {m_edges(e, 0), m_edges(e, 1)};
      const collision::Aabb b = box_of(v, 2);
      if (!overlap(b, whole)) continue;
      for (size_t k = 0; k < w.edges.size(); ++k)
        if (overlap(b, edge_box[k])) pairs.push_back({o, true, e, static_cast<int>(k)});
    }
  }
  return pairs;
}

collision::PairPoints ObstacleContactEnergy::pair_points(
    const FeaturePair& p, const Eigen::VectorXd& x,
    const std::vector<WorldFeatures>& features) const {
  const WorldFeatures& w = features[p.obstacle];
  if (p.edge_edge)
    return {x.segment<3>(3 * m_edges(p.a, 0)), x.segment<3>(3 * m_edges(p.a, 1)),
            w.corners[w.edges[p.b][0]], w.corners[w.edges[p.b][1]]};
  return {w.corners[p.a], x.segment<3>(3 * m_faces(p.b, 0)), x.segment<3>(3 * m_faces(p.b, 1)),
          x.segment<3>(3 * m_faces(p.b, 2))};
}

double ObstacleContactEnergy::pair_weight(const FeaturePair& p) const {
  return p.edge_edge ? m_edge_area[p.a] : m_face_area[p.b] / 3;
}

double ObstacleContactEnergy::pair_mollifier_eps(const FeaturePair& p,
                                                 const std::vector<WorldFeatures>& features) const {
  return p.edge_edge ? collision::edge_edge_mollifier_threshold(
                           m_edge_rest[p.a], features[p.obstacle].edge_length[p.b])
                     : 0.0;
}

collision::PairPoints ObstacleContactEnergy::sphere_points(const Eigen::VectorXd& x, int f,
                                                           const Eigen::Affine3d& pose) const {
  return {pose.translation(), x.segment<3>(3 * m_faces(f, 0)), x.segment<3>(3 * m_faces(f, 1)),
          x.segment<3>(3 * m_faces(f, 2))};
}

/// The boxes of the sheet's faces at x. near() is face_near_bounds's test on a stored box (the
/// same arithmetic, so the same answer). With many obstacles (fall-spheres has 121) testing
/// every face against every obstacle dominates a contact evaluation, so there the faces are also
/// sorted by their lowest x and near_faces lists only those whose x range can reach the box, in
/// ascending face order as the plain loop visits them (sums and matrix entries are added in the
/// same order, so results are the same to the bit).
class ObstacleContactEnergy::FaceBoxes {
 public:
  FaceBoxes(const Eigen::MatrixX3i& faces, const Eigen::VectorXd& x, bool sorted) {
    const int nf = static_cast<int>(faces.rows());
    m_lo.resize(nf);
    m_hi.resize(nf);
    bool finite = true;
    for (int f = 0; f < nf; ++f) {
      Eigen::Vector3d lo = x.segment<3>(3 * faces(f, 0)), hi = lo;
      for (int k = 1; k < 3; ++k) {
        lo = lo.cwiseMin(x.segment<3>(3 * faces(f, k)));
        hi = hi.cwiseMax(x.segment<3>(3 * faces(f, k)));
      }
      m_lo[f] = lo;
      m_hi[f] = hi;
      m_width = std::max(m_width, hi.x() - lo.x());
      finite = finite && std::isfinite(lo.x()) && std::isfinite(hi.x());
    }
    // A NaN would break the sort's ordering: the plain loop then tests every face (and
    // near() refuses the NaN boxes, as face_near_bounds does).
    if (!sorted || !finite) return;
    m_order.resize(nf);
    for (int f = 0; f < nf; ++f) m_order[f] = f;
    std::sort(m_order.begin(), m_order.end(),
              [&](int a, int b) { return m_lo[a].x() < m_lo[b].x(); });
    m_sorted_lo.resize(nf);
    for (int i = 0; i < nf; ++i) m_sorted_lo[i] = m_lo[m_order[i]].x();
  }
  /// Whether face f's box, grown by margin, meets box b (face_near_bounds).
  bool near(int f, const collision::Aabb& b, double margin) const {
    return (m_hi[f].array() + margin >= b.lo.array()).all() &&
           (m_lo[f].array() - margin <= b.hi.array()).all();
  }
  /// The faces f, in ascending order, for which near(f, b, m) can hold for some m <= margin
  /// (a superset: the caller applies near() with its own margin). Valid until the next call.
  const std::vector<int>& near_faces(const collision::Aabb& b, double margin) const {
    const int nf = static_cast<int>(m_lo.size());
    if (m_order.empty() || !std::isfinite(margin)) {
      m_found.resize(nf);
      for (int f = 0; f < nf; ++f) m_found[f] = f;
      return m_found;
    }
    // near() needs lo.x - margin <= b.hi.x and hi.x + margin >= b.lo.x, with hi.x <= lo.x +
    // m_width; the range is widened by a micrometre against the rounding of those sums.
    const double slack = 1e-6 + 1e-12 * (std::abs(b.lo.x()) + std::abs(b.hi.x()) + margin);
    const double from = b.lo.x() - margin - m_width - slack, to = b.hi.x() + margin + slack;
    const auto first = std::lower_bound(m_sorted_lo.begin(), m_sorted_lo.end(), from);
    const auto last = std::upper_bound(first, m_sorted_lo.end(), to);
    m_found.clear();
    // near() is monotone in the margin, so the faces it refuses at `margin` it refuses at any
    // smaller one.
    for (auto i = first - m_sorted_lo.begin(); i < last - m_sorted_lo.begin(); ++i)
      if (near(m_order[i], b, margin)) m_found.push_back(m_order[i]);
    std::sort(m_found.begin(), m_found.end());
    return m_found;
  }

 private:
  std::vector<Eigen::Vector3d> m_lo, m_hi;
  double m_width = 0.0;      // the widest face in x [m]
  std::vector<int> m_order;  // faces by their lowest x (empty: not sorted)
  std::vector<double> m_sorted_lo;
  mutable std::vector<int> m_found;
};

ObstacleContactEnergy::FaceBoxes ObstacleContactEnergy::face_boxes(const Eigen::VectorXd& x) const {
  // Sorting costs a sort of the faces per evaluation; it pays only where many obstacles are
  // tested against them (fall-spheres: 121 spheres; the other scenarios have 1-3 such obstacles).
  // No such obstacle (polyhedra or vertex contact only): no boxes to build.
  const int n = face_obstacles();
  return n == 0 ? FaceBoxes(Eigen::MatrixX3i(), x, false) : FaceBoxes(m_faces, x, n >= 8);
}

int ObstacleContactEnergy::face_obstacles() const {
  int n = 0;
  for (int o = 0; o < num_obstacles(); ++o)
    n += m_mode[o] == Mode::sphere || m_mode[o] == Mode::search;
  return n;
}

std::vector<double> ObstacleContactEnergy::face_speeds(const Eigen::VectorXd& dx) const {
  if (face_obstacles() == 0) return {};
  std::vector<double> speed(m_faces.rows(), 0.0);
  for (int f = 0; f < m_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      speed[f] = std::max(speed[f], dx.segment<3>(3 * m_faces(f, k)).norm());
  return speed;
}

bool ObstacleContactEnergy::face_near_bounds(int o, const Eigen::VectorXd& x, int f,
                                             double margin) const {
  const auto& b = m_bounds[o];
  Eigen::Vector3d lo = x.segment<3>(3 * m_faces(f, 0)), hi = lo;
  for (int k = 1; k < 3; ++k) {
    lo = lo.cwiseMin(x.segment<3>(3 * m_faces(f, k)));
    hi = hi.cwiseMax(x.segment<3>(3 * m_faces(f, k)));
  }
  return (hi.array() + margin >= b.lo.array()).all() && (lo.array() - margin <= b.hi.array()).all();
}

Eigen::Vector3d ObstacleContactEnergy::contact_point(const FrictionPoint& fp,
                                                     const Eigen::VectorXd& x) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < fp.count; ++k) p += fp.weights[k] * x.segment<3>(3 * fp.vertices[k]);
  return p;
}

namespace {

/// Polishes the minimum of the field over triangle (a, b, c) found by the subdivision search
/// (accurate to its resolution only, which makes a barrier on it noisy): projected gradient
/// descent in barycentric coordinates with Barzilai-Borwein steps and backtracking, from the
/// minimiser found. The field is smooth on smooth obstacles, so this converges to the exact
/// minimum and the barrier becomes a smooth function of the vertex positions.
collision::TriangleSdfResult polish_minimum(const collision::Collider& obs,
                                            const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                            const Eigen::Vector3d& c, const Eigen::Affine3d& pose,
                                            collision::TriangleSdfResult r) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const auto project = [](Eigen::Vector2d w) {  // onto w1, w2 >= 0, w1 + w2 <= 1
    w = w.cwiseMax(0.0);
    const double s = w.sum();
    if (s > 1) w /= s;
    return w;
  };
  Eigen::Vector2d w(r.barycentric[1], r.barycentric[2]);
  Eigen::Vector3d n;
  double phi = obs.distance_at_pose(a + w[0] * e1 + w[1] * e2, pose, &n);
  Eigen::Vector2d g(n.dot(e1), n.dot(e2));
  double step =
      1.0 / std::max(e1.squaredNorm(), e2.squaredNorm());  // one unit of length per unit slope
  Eigen::Vector2d w_prev = w, g_prev = g;
  for (int it = 0; it < 400; ++it) {
    if (it > 0) {
      const Eigen::Vector2d sw = w - w_prev, sg = g - g_prev;
      const double den = sw.dot(sg);
      if (den > 1e-30) step = sw.squaredNorm() / den;
    }
    bool moved = false;
    for (int k = 0; k < 30; ++k, step *= 0.5) {
      const Eigen::Vector2d w_new = project(w - step * g);
      if ((w_new - w).norm() < 1e-12) break;
      Eigen::Vector3d n_new;
      const double phi_new = obs.distance_at_pose(a + w_new[0] * e1 + w_new[1] * e2, pose, &n_new);
      if (phi_new < phi - 1e-4 * g.dot(w - w_new) * 0 - 1e-15) {
        w_prev = w, g_prev = g;
        w = w_new, phi = phi_new, n = n_new;
        g = Eigen::Vector2d(n.dot(e1), n.dot(e2));
        moved = true;
        break;
      }
    }
    if (!moved) break;
  }
  if (phi < r.distance) {
    r.distance = phi;
    r.barycentric = Eigen::Vector3d(1 - w[0] - w[1], w[0], w[1]);
    r.point = a + w[0] * e1 + w[1] * e2;
    r.gradient = n;
  }
  return r;
}

/// Minimum of the field over a triangle: subdivision search, then polish_minimum near contact.
collision::TriangleSdfResult face_minimum(const collision::Collider& obs, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                          const Eigen::Affine3d& pose,
                                          const collision::TriangleSdfParams& params) {
  collision::TriangleSdfResult r = collision::triangle_min_distance(obs, a, b, c, pose, params);
  if (r.distance < params.cutoff + params.lipschitz * params.resolution)
    r = polish_minimum(obs, a, b, c, pose, r);
  return r;
}

}  // namespace

double ObstacleContactEnergy::sphere_face_distance(int o, const Eigen::VectorXd& x, int f,
                                                   const Eigen::Affine3d& pose,
                                                   collision::PairPoints& pts,
                                                   collision::DistanceStencil& s) const {
  pts = sphere_points(x, f, pose);
  s = collision::point_triangle_stencil(pts);
  return std::sqrt(collision::distance_squared(s, pts)) - sphere_radius(o, pose);
}

collision::TriangleSdfResult ObstacleContactEnergy::face_contact(
    int o, const Eigen::VectorXd& x, int f, const Eigen::Affine3d& pose) const {
  if (!face_near_bounds(o, x, f, 0.0)) return {};  // distance +inf: out of contact
  if (m_mode[o] == Mode::sphere) {
    // Exact: the closest point of the triangle to the centre.
    collision::PairPoints pts;
    collision::DistanceStencil s;
    collision::TriangleSdfResult r;
    r.distance = sphere_face_distance(o, x, f, pose, pts, s);
    const Eigen::Vector4d w = collision::closest_point_weights(s, pts);  // r = centre - point
    r.barycentric = -w.tail<3>();
    r.point = r.barycentric[0] * pts[1] + r.barycentric[1] * pts[2] + r.barycentric[2] * pts[3];
    const Eigen::Vector3d out = r.point - pts[0];
    const double len = out.norm();
    r.lower_bound = r.distance;
    r.gradient = len > 0 ? Eigen::Vector3d(out / len) : Eigen::Vector3d::UnitZ();
    r.evaluations = 1;
    return r;
  }
  return face_minimum(*m_obstacles[o], x.segment<3>(3 * m_faces(f, 0)),
                      x.segment<3>(3 * m_faces(f, 1)), x.segment<3>(3 * m_faces(f, 2)), pose,
                      m_triangle);
}

bool ObstacleContactEnergy::near_bounds(int o, const Eigen::Vector3d& p) const {
  const auto& b = m_bounds[o];
  return (p.array() >= b.lo.array()).all() && (p.array() <= b.hi.array()).all();
}

void ObstacleContactEnergy::update_bounds() {
  m_bounds.clear();
  for (const auto& o : m_obstacles) {
    collision::Aabb b = o->bounds(m_time);
    b.lo.array() -= m_params.dhat;
    b.hi.array() += m_params.dhat;
    m_bounds.push_back(b);
  }
}

// Every barrier contact of the sheet at x against the obstacles at time t (only obstacle `only`
// when >= 0): visit(fp, lambda, p, n, d) with the contact's vertices and weights in fp
// (fp.obstacle set), its normal force lambda [N], the contact point p on the sheet, the unit
// normal n pointing from the obstacle to the sheet and the gap d of the contact's term [m].
template <class F>
void ObstacleContactEnergy::for_each_contact(const Eigen::VectorXd& x, double t, F&& visit,
                                             int only) const {
  const int nv = static_cast<int>(m_area.size());
  const FaceBoxes boxes = face_boxes(x);
  for (int o = 0; o < num_obstacles(); ++o) {
    if (only >= 0 && o != only) continue;
    const auto& obs = *m_obstacles[o];
    if (m_mode[o] == Mode::sphere || m_mode[o] == Mode::search) {
      const Eigen::Affine3d pose = obs.motion.pose(t);
      for (int f : boxes.near_faces(m_bounds[o], 0.0)) {
        if (!boxes.near(f, m_bounds[o], 0.0)) continue;  // face_contact: out of contact
        const auto r = face_contact(o, x, f, pose);
        if (r.distance >= m_params.dhat || r.distance <= 0) continue;
        FrictionPoint fp;
        fp.count = 3;
        fp.vertices = {m_faces(f, 0), m_faces(f, 1), m_faces(f, 2)};
        fp.weights = r.barycentric;
        fp.obstacle = o;
        visit(fp, -face_kappa(f) * barrier_first_derivative(r.distance, m_params.dhat),
              contact_point(fp, x), r.gradient, r.distance);
      }
    }
    if (!uses_vertices(o)) continue;
    const Eigen::Vector3d lift = lift_of(o, x);
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v);
      if (!near_bounds(o, p - lift)) continue;
      Eigen::Vector3d n;
      const double d = obs.distance(p - lift, t, &n);
      if (d >= m_params.dhat || d <= 0) continue;
      FrictionPoint fp;
      fp.vertices[0] = v;
      fp.obstacle = o;
      visit(fp, -kappa(v) * barrier_first_derivative(d, m_params.dhat), p, n, d);
    }
  }
  // Corner-triangle and edge-edge pairs of polyhedral obstacles: normal force of the mollified
  // barrier, acting at the closest point on the sheet.
  std::vector<WorldFeatures> at_t(m_obstacles.size());
  for (int o = 0; o < num_obstacles(); ++o) at_t[o] = world_features(o, t);
  for (const FeaturePair& p : feature_pairs(x, nullptr, m_params.dhat, at_t)) {
    if (only >= 0 && p.obstacle != only) continue;
    const collision::PairPoints pts = pair_points(p, x, at_t);
    const collision::DistanceStencil s =
        p.edge_edge ? collision::edge_edge_stencil(pts) : collision::point_triangle_stencil(pts);
    const double d = std::sqrt(collision::distance_squared(s, pts));
    if (d >= m_params.dhat || d <= 0) continue;
    const double eps = pair_mollifier_eps(p, at_t);
    const double m = p.edge_edge ? collision::edge_edge_mollifier(pts, eps, nullptr, nullptr) : 1.0;
    const Eigen::Vector4d w = collision::closest_point_weights(s, pts);
    FrictionPoint fp;
    fp.obstacle = p.obstacle;
    if (p.edge_edge) {  // r = sheet point - obstacle point
      fp.count = 2;
      fp.vertices = {m_edges(p.a, 0), m_edges(p.a, 1), -1};
      fp.weights = Eigen::Vector3d(w[0], w[1], 0);
    } else {  // r = corner - sheet point
      fp.count = 3;
      fp.vertices = {m_faces(p.b, 0), m_faces(p.b, 1), m_faces(p.b, 2)};
      fp.weights = -w.tail<3>();
    }
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) r += w[k] * pts[k];
    const double kappa_pair = m_stiffness / m_params.dhat * pair_weight(p);
    // n from the obstacle to the sheet in both cases (friction depends only on its plane).
    const Eigen::Vector3d n = p.edge_edge ? r.normalized() : Eigen::Vector3d(-r.normalized());
    visit(fp, -kappa_pair * m * barrier_first_derivative(d, m_params.dhat), contact_point(fp, x), n,
          d);
  }
}

void ObstacleContactEnergy::begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) {
  ScopedTimer timer(m_stats->seconds);
  m_t0 = ctx.time_t0;
  m_t1 = m_time = ctx.time_t1();
  m_eps = m_params.eps_velocity * (m_params.static_whole_step ? ctx.whole_step() : ctx.h);
  update_bounds();
  m_moving.clear();
  for (const auto& o : m_obstacles) m_moving.push_back(o->motion.moves_during(m_t0, m_t1));
  const double carried = std::max(ctx.contact_stiffness, m_params.stiffness);
  double stiffness = m_params.stiffness;
  if (m_impact_density > 0 && ctx.v_t0) {
    // Impact rule (header): the fastest normal approach of a vertex that can reach an obstacle
    // within this step.
    double approach = 0;
    for (size_t o = 0; o < m_obstacles.size(); ++o) {
      const auto& obs = *m_obstacles[o];
      for (int v = 0; v < static_cast<int>(m_area.size()); ++v) {
        const Eigen::Vector3d p = x_t0.segment<3>(3 * v);
        const Eigen::Vector3d vel = ctx.v_t0->segment<3>(3 * v) - obs.velocity(p, ctx.time_t0);
        const double reach = m_params.dhat + 2 * ctx.h * vel.norm();
        if (m_bounds[o].distance_to(p) > reach) continue;
        Eigen::Vector3d n;
        if (obs.distance(p, ctx.time_t0, &n) > reach) continue;
        approach = std::max(approach, -n.dot(vel));
      }
    }
    stiffness = std::max(
        stiffness, m_impact_density * approach * approach / (2 * m_params.dhat * std::log(100.0)));
  }
  // Contacts at the step start, their forces at the stiffness that holds them there.
  struct Contact {
    FrictionPoint fp;
    double lambda;
    Eigen::Vector3d p, n;
  };
  std::vector<Contact> contacts;
  double gap = m_params.dhat;
  m_stiffness = carried;
  m_features.assign(m_obstacles.size(), {});
  for (int o = 0; o < num_obstacles(); ++o) m_features[o] = world_features(o, m_time);
  const auto collect = [&](const FrictionPoint& fp, double lambda, const Eigen::Vector3d& p,
                           const Eigen::Vector3d& n, double d) {
    contacts.push_back({fp, lambda, p, n});
    gap = std::min(gap, d);
  };
  for_each_contact(x_t0, ctx.time_t0, collect);
  if (m_params.hold_load && gap < m_params.dhat) {
    // Load rule (header): the stiffness moves to the one that holds the present contact
    // pressure at dhat / 100; it falls that far at once and rises by at most load_raise.
    const double ratio = barrier_first_derivative(gap, m_params.dhat) /
                         barrier_first_derivative(m_params.dhat / 100, m_params.dhat);
    double target = carried * std::min(m_params.load_raise, ratio);
    if (target > carried)  // a raise stops at raise_limit times the scene's stiffness
      target = std::max(carried, std::min(target, m_params.raise_limit * m_params.stiffness));
    stiffness = std::max(stiffness, target);
  }
  m_stiffness = stiffness;
  m_params.trace(Trace::contact,
                 "contact t %.6f h %.3e: %zu contacts, gap %.3e, stiffness %.4g -> %.4g Pa",
                 ctx.time_t0, ctx.h, contacts.size(), gap, carried, stiffness);
  // Lagged friction: normal force and tangent plane at the step start (IPC Sec. 5).
  m_friction.clear();
  m_normal_force = 0.0;
  for (Contact& c : contacts) {
    const double lambda = c.lambda * stiffness / carried;
    m_normal_force += lambda;
    const collision::Collider& obs = *m_obstacles[c.fp.obstacle];
    if (obs.friction <= 0) continue;
    c.fp.mu_lambda = obs.friction * lambda;
    const Eigen::Vector3d a =
        std::abs(c.n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    c.fp.T.col(0) = c.n.cross(a).normalized();
    c.fp.T.col(1) = c.n.cross(c.fp.T.col(0));
    c.fp.origin = c.p + ctx.h * obs.velocity(c.p, ctx.time_t0);
    m_friction.push_back(c.fp);
  }
  m_stats->max_friction_points = std::max(m_stats->max_friction_points, active_friction());
  m_stats->max_normal_force = std::max(m_stats->max_normal_force, m_normal_force);
}

void ObstacleContactEnergy::end_step(SheetState& state) const {
  state.contact_stiffness = m_stiffness;
}

Eigen::Vector3d ObstacleContactEnergy::obstacle_load(int o, const Eigen::VectorXd& x) const {
  Eigen::Vector3d load = Eigen::Vector3d::Zero();
  for_each_contact(
      x, m_time,
      [&](const FrictionPoint&, double lambda, const Eigen::Vector3d&, const Eigen::Vector3d& n,
          double) { load -= lambda * n; },
      o);
  return load;
}

namespace {

/// IPC friction smoothing: f0(y) = -y^3/(3 eps^2) + y^2/eps + eps/3 below eps, y above.
double f0(double y, double eps) {
  return y >= eps ? y : -y * y * y / (3 * eps * eps) + y * y / eps + eps / 3;
}

/// The stencil of a pair of a polyhedral obstacle (corner-triangle or edge-edge).
collision::DistanceStencil pair_stencil(bool edge_edge, const collision::PairPoints& pts) {
  return edge_edge ? collision::edge_edge_stencil(pts) : collision::point_triangle_stencil(pts);
}

}  // namespace

double ObstacleContactEnergy::value(const Eigen::VectorXd& x) const {
  ScopedTimer timer(m_stats->seconds);
  double e = 0;
  const int nv = static_cast<int>(m_area.size());
  const double dhat = m_params.dhat;
  const FaceBoxes boxes = face_boxes(x);
  for (int o = 0; o < num_obstacles(); ++o) {
    if (m_mode[o] == Mode::sphere || m_mode[o] == Mode::search) {
      const Eigen::Affine3d pose = m_obstacles[o]->motion.pose(m_time);
      collision::PairPoints pts;
      collision::DistanceStencil s;
      for (int f : boxes.near_faces(m_bounds[o], 0.0)) {
        if (!boxes.near(f, m_bounds[o], 0.0)) continue;
        const double d = m_mode[o] == Mode::sphere ? sphere_face_distance(o, x, f, pose, pts, s)
                                                   : face_contact(o, x, f, pose).distance;
        if (d <= 0) return INF;
        if (d < dhat) e += face_kappa(f) * barrier(d, dhat);
      }
    }
    if (!uses_vertices(o)) continue;
    const Eigen::Vector3d lift = lift_of(o, x);
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v) - lift;
      if (!near_bounds(o, p)) continue;
      const double d = m_obstacles[o]->distance(p, m_time);
      if (d <= 0) return INF;
      if (d < dhat) e += kappa(v) * barrier(d, dhat);
    }
  }
  for (const FeaturePair& p : feature_pairs(x, nullptr, dhat, m_features)) {
    const collision::PairPoints pts = pair_points(p, x, m_features);
    const double d2 = collision::distance_squared(pair_stencil(p.edge_edge, pts), pts);
    if (d2 >= dhat * dhat) continue;
    if (!(d2 > 0)) return INF;
    const double m = p.edge_edge ? collision::edge_edge_mollifier(
                                       pts, pair_mollifier_eps(p, m_features), nullptr, nullptr)
                                 : 1.0;
    e += m_stiffness / dhat * pair_weight(p) * m * barrier(std::sqrt(d2), dhat);
  }
  for (const auto& fp : m_friction) {
    const Eigen::Vector2d u = fp.T.transpose() * (contact_point(fp, x) - fp.origin);
    e += fp.mu_lambda * f0(u.norm(), m_eps);
  }
  return e;
}

void ObstacleContactEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& g,
                                            BlockSymmetricMatrix* H,
                                            HessianProjection projection) const {
  ScopedTimer timer(m_stats->seconds);
  const bool project = projection == HessianProjection::psd;
  const int nv = static_cast<int>(m_area.size());
  const double dhat = m_params.dhat;
  const auto add_weighted = [&](const std::array<int, 3>& vs, const Eigen::Vector3d& w, int count,
                                const Eigen::Vector3d& force, const Eigen::Matrix3d& local) {
    for (int k = 0; k < count; ++k) g.segment<3>(3 * vs[k]) += w[k] * force;
    if (!H) return;
    if (count == 1) {
      H->add_element<1>({vs[0]}, local);
      return;
    }
    Eigen::Matrix<double, 9, 9> block = Eigen::Matrix<double, 9, 9>::Zero();
    for (int a = 0; a < count; ++a)
      for (int b = 0; b < count; ++b) block.block<3, 3>(3 * a, 3 * b) = w[a] * w[b] * local;
    if (count == 2)
      H->add_element<2>({vs[0], vs[1]}, block.topLeftCorner<6, 6>());
    else
      H->add_element<3>(vs, block);
  };
  // A term with exact 12-coordinate derivatives of which `first` .. `first + count - 1` are
  // sheet vertices `vs` (the other points belong to the obstacle and do not move).
  const auto add_exact = [&](const std::array<int, 3>& vs, int first, int count, double scale,
                             const collision::Vector12d& grad, collision::Matrix12d* hess) {
    for (int k = 0; k < count; ++k)
      g.segment<3>(3 * vs[k]) += scale * grad.segment<3>(3 * (first + k));
    if (!H) return;
    const collision::Matrix12d h =
        project ? project_psd(scale * *hess) : collision::Matrix12d(scale * *hess);
    if (count == 2)
      H->add_element<2>({vs[0], vs[1]}, h.block<6, 6>(3 * first, 3 * first));
    else
      H->add_element<3>(vs, h.block<9, 9>(3 * first, 3 * first));
  };
  collision::Vector12d grad;
  collision::Matrix12d hess;
  const FaceBoxes boxes = face_boxes(x);
  for (int o = 0; o < num_obstacles(); ++o) {
    if (m_mode[o] == Mode::sphere || m_mode[o] == Mode::search) {
      const Eigen::Affine3d pose = m_obstacles[o]->motion.pose(m_time);
      collision::PairPoints pts;
      collision::DistanceStencil s;
      for (int f : boxes.near_faces(m_bounds[o], 0.0)) {
        if (!boxes.near(f, m_bounds[o], 0.0)) continue;
        const double k = face_kappa(f);
        const std::array<int, 3> vs{{m_faces(f, 0), m_faces(f, 1), m_faces(f, 2)}};
        if (m_mode[o] == Mode::sphere) {
          const double d = sphere_face_distance(o, x, f, pose, pts, s);
          if (d >= dhat || d <= 0) continue;
          collision::pair_barrier_derivatives(s, pts, dhat, 0.0, grad, H ? &hess : nullptr,
                                              sphere_radius(o, pose));
          add_exact(vs, 1, 3, k, grad, &hess);
          continue;
        }
        const auto r = face_contact(o, x, f, pose);
        if (r.distance >= dhat || r.distance <= 0) continue;
        add_weighted(
            vs, r.barycentric, 3, k * barrier_first_derivative(r.distance, dhat) * r.gradient,
            k * barrier_second_derivative(r.distance, dhat) * r.gradient * r.gradient.transpose());
      }
    }
    if (!uses_vertices(o)) continue;
    const int rigid = m_rigid[o];
    const Eigen::Vector3d lift = lift_of(o, x);
    const bool coupled = rigid >= 0 && g.size() >= 3 * rigid + 3;  // g has the body's entries
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v) - lift;
      if (!near_bounds(o, p)) continue;
      Eigen::Vector3d n;
      const double d = m_obstacles[o]->distance(p, m_time, &n);
      if (d >= dhat || d <= 0) continue;
      const double b1 = barrier_first_derivative(d, dhat);
      g.segment<3>(3 * v) += kappa(v) * b1 * n;
      if (coupled) g[3 * rigid + 2] -= kappa(v) * b1 * n.z();
      if (H) {
        Eigen::Matrix3d local = kappa(v) * barrier_second_derivative(d, dhat) * n * n.transpose();
        // The curvature term b' Hess phi where the collider provides Hess phi (see the header).
        Eigen::Matrix3d curvature;
        if (m_obstacles[o]->distance_hessian(p, m_time, curvature)) {
          local += kappa(v) * b1 * curvature;
          if (project) local = project_psd(local);
        }
        if (!coupled) {
          H->add_element<1>({v}, local);
          continue;
        }
        // (p, q) -> r = p - E q, E = e_z e_z^T: the Hessian in (p, q) is P^T local P with
        // P = [I, -E] (PSD when local is).
        Eigen::Matrix<double, 3, 6> P = Eigen::Matrix<double, 3, 6>::Zero();
        P.leftCols<3>().setIdentity();
        P(2, 5) = -1;
        H->add_element<2>({v, rigid}, P.transpose() * local * P);
      }
    }
  }
  for (const FeaturePair& p : feature_pairs(x, nullptr, dhat, m_features)) {
    const collision::PairPoints pts = pair_points(p, x, m_features);
    const collision::DistanceStencil s = pair_stencil(p.edge_edge, pts);
    const double d2 = collision::distance_squared(s, pts);
    if (d2 >= dhat * dhat || !(d2 > 0)) continue;
    collision::pair_barrier_derivatives(s, pts, dhat, pair_mollifier_eps(p, m_features), grad,
                                        H ? &hess : nullptr);
    const double scale = m_stiffness / dhat * pair_weight(p);
    if (p.edge_edge)
      add_exact({m_edges(p.a, 0), m_edges(p.a, 1), -1}, 0, 2, scale, grad, &hess);
    else
      add_exact({m_faces(p.b, 0), m_faces(p.b, 1), m_faces(p.b, 2)}, 1, 3, scale, grad, &hess);
  }
  for (const auto& fp : m_friction) {
    const Eigen::Vector2d u = fp.T.transpose() * (contact_point(fp, x) - fp.origin);
    const double y = u.norm();
    // f1(y)/y with f1 = f0': 1/y above eps, -y/eps^2 + 2/eps below (finite at y = 0).
    const double f1_over_y = y >= m_eps ? 1 / y : -y / (m_eps * m_eps) + 2 / m_eps;
    // d/du (f1/y u) = f1/y I + (d(f1/y)/dy / y) u u^T; PSD in both regimes (see header).
    Eigen::Matrix2d M = f1_over_y * Eigen::Matrix2d::Identity();
    if (y > 0) {
      const double slope = y >= m_eps ? -1 / (y * y * y) : -1 / (m_eps * m_eps * y);
      M += slope * u * u.transpose();
    }
    add_weighted(fp.vertices, fp.weights, fp.count, fp.mu_lambda * f1_over_y * (fp.T * u),
                 fp.mu_lambda * fp.T * M * fp.T.transpose());
  }
}

double ObstacleContactEnergy::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  ScopedTimer timer(m_stats->seconds);
  double alpha = 1.0;
  const FaceBoxes boxes = face_boxes(x);
  const std::vector<double> speeds = face_speeds(dx);
  for (int o = 0; o < num_obstacles(); ++o)
    alpha = obstacle_max_step(o, x, dx, alpha, boxes, speeds);
  return pairs_max_step(x, dx, alpha);
}

double ObstacleContactEnergy::obstacle_max_step(int o, const Eigen::VectorXd& x,
                                                const Eigen::VectorXd& dx, double alpha,
                                                const FaceBoxes& boxes,
                                                const std::vector<double>& speeds) const {
  const int nv = static_cast<int>(m_area.size());
  const auto& obs = *m_obstacles[o];
  // Faces against a convex obstacle cover their vertices (below); otherwise the vertices of
  // the terms are traced.
  const bool trace_vertices = uses_vertices(o) || (m_mode[o] == Mode::search && !obs.is_convex());
  const Eigen::Vector3d lift = lift_of(o, x), dlift = lift_of(o, dx);  // relative to a coupled body
  for (int v = 0; v < nv && trace_vertices; ++v) {
    const Eigen::Vector3d p = x.segment<3>(3 * v) - lift, d = dx.segment<3>(3 * v) - dlift;
    const double len = d.norm();
    if (len == 0) continue;
    Eigen::Vector3d n;
    double dist = obs.distance(p, m_time, &n);
    if (dist >= alpha * len) continue;  // cannot reach the surface within this step
    if (obs.is_convex() && dist > 0) {
      // The solid lies behind the tangent plane at the closest surface point: the vertex may
      // close 90% of its gap to that plane (exact for the ground; sliding along a curved
      // surface is not held back as sphere tracing would hold it).
      const double rate = -n.dot(d);
      if (rate > 0) alpha = std::min(alpha, 0.9 * dist / rate);
      continue;
    }
    // Sphere tracing (exact for an inverted sphere): the vertex may close at most 90% of
    // its gap.
    alpha = std::min(alpha, obs.segment_step(p, d, m_time, alpha, 0.1));
  }
  if (m_mode[o] != Mode::sphere && m_mode[o] != Mode::search) return alpha;
  // Faces: conservative advancement on a lower bound of the field over the moving triangle.
  const Eigen::Affine3d pose = obs.motion.pose(m_time);
  const double fastest = speeds.empty() ? 0.0 : *std::max_element(speeds.begin(), speeds.end());
  for (int f : boxes.near_faces(m_bounds[o], alpha * fastest)) {
    const double speed = speeds[f];
    if (speed == 0 || !boxes.near(f, m_bounds[o], alpha * speed)) continue;
    if (obs.is_convex()) {
      // The minimiser m of the field over the triangle, with normal n, gives a plane that
      // separates the triangle from the convex solid: the solid lies behind the tangent plane
      // at its closest point m - phi(m) n, and the triangle (the hull of its vertices) in
      // front of it. Each vertex may close 90% of the smallest vertex gap to that plane.
      collision::TriangleSdfResult r;
      if (m_mode[o] == Mode::sphere) {
        r = face_contact(o, x, f, pose);
      } else {
        collision::TriangleSdfParams p = m_triangle;
        p.cutoff = std::max(m_params.dhat, alpha * speed);
        r = face_minimum(obs, x.segment<3>(3 * m_faces(f, 0)), x.segment<3>(3 * m_faces(f, 1)),
                         x.segment<3>(3 * m_faces(f, 2)), pose, p);
      }
      if (r.lower_bound >= alpha * speed) continue;  // out of reach this step
      if (r.distance > 0) {
        const Eigen::Vector3d q = r.point - r.distance * r.gradient;
        double gap[3], smallest = INF;
        for (int k = 0; k < 3; ++k) {
          gap[k] = r.gradient.dot(x.segment<3>(3 * m_faces(f, k)) - q);
          smallest = std::min(smallest, gap[k]);
        }
        if (smallest > 0) {
          double plane = alpha;
          for (int k = 0; k < 3; ++k) {
            const double rate = -r.gradient.dot(dx.segment<3>(3 * m_faces(f, k)));
            if (rate > 0) plane = std::min(plane, (gap[k] - 0.1 * smallest) / rate);
          }
          if (plane < alpha && m_mode[o] == Mode::sphere) {
            // The plane bound is one step: a face turning on a sphere smaller than itself
            // closes its tangent plane at once while keeping its distance. Additive CCD on
            // the exact centre-triangle distance follows the turn; both bounds are safe.
            collision::PairPoints d;
            d[0].setZero();
            for (int k = 0; k < 3; ++k) d[k + 1] = dx.segment<3>(3 * m_faces(f, k));
            plane =
                std::max(plane, collision::point_triangle_ccd(sphere_points(x, f, pose), d, alpha,
                                                              0.1, sphere_radius(o, pose)));
          }
          alpha = std::min(alpha, plane);
          continue;
        }
      }
      // No separating plane found (the minimum is not resolved): trace as below.
    }
    // A lower bound of the field over the triangle at parameter t: the larger of the
    // certified bound of the branch and bound (triangle_min_distance) and the minimum found
    // less the search resolution. The resolution is refined to a fifth of the distance when
    // the face is close, so that the advancement below can close in on the obstacle as far
    // as the barrier lets it (a fixed resolution would stall every face at that distance).
    // The certified bound alone is weak for a face nearly tangent to a large smooth surface
    // (the query budget runs out), hence the maximum.
    collision::TriangleSdfParams p = m_triangle;
    p.cutoff = std::max(m_params.dhat, alpha * speed);
    const auto lower_bound = [&](double t) {
      const Eigen::Vector3d a =
          x.segment<3>(3 * m_faces(f, 0)) + t * dx.segment<3>(3 * m_faces(f, 0));
      const Eigen::Vector3d b =
          x.segment<3>(3 * m_faces(f, 1)) + t * dx.segment<3>(3 * m_faces(f, 1));
      const Eigen::Vector3d c =
          x.segment<3>(3 * m_faces(f, 2)) + t * dx.segment<3>(3 * m_faces(f, 2));
      p.resolution = m_triangle.resolution;
      auto r = face_minimum(obs, a, b, c, pose, p);
      if (r.distance > 0 && r.distance < 5 * p.resolution) {
        p.resolution = 0.2 * r.distance;
        r = face_minimum(obs, a, b, c, pose, p);
      }
      return std::max(r.lower_bound, r.distance - p.resolution);
    };
    double bound = lower_bound(0.0);
    if (bound <= 0 || bound >= alpha * speed) continue;  // in contact, or out of reach this step
    const double stop = 0.1 * bound;
    double t = 0;
    for (int it = 0; it < 64; ++it) {
      const double advance = (bound - stop) / speed;
      if (advance <= 1e-12) break;
      t += advance;
      if (t >= alpha) break;
      bound = lower_bound(t);
    }
    alpha = std::min(alpha, t);
  }
  return alpha;
}

double ObstacleContactEnergy::pairs_max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                             double alpha) const {
  // Corner-triangle and edge-edge pairs of polyhedral obstacles: additive CCD, the obstacle held
  // at its pose at m_time (the step's end).
  const Eigen::VectorXd reach = alpha * dx;
  for (const FeaturePair& p : feature_pairs(x, &reach, 0.0, m_features)) {
    const collision::PairPoints pts = pair_points(p, x, m_features);
    collision::PairPoints d;
    for (auto& v : d) v.setZero();
    if (p.edge_edge) {
      d[0] = dx.segment<3>(3 * m_edges(p.a, 0));
      d[1] = dx.segment<3>(3 * m_edges(p.a, 1));
      alpha = collision::edge_edge_ccd(pts, d, alpha);
    } else {
      for (int k = 0; k < 3; ++k) d[k + 1] = dx.segment<3>(3 * m_faces(p.b, k));
      alpha = collision::point_triangle_ccd(pts, d, alpha);
    }
  }
  return alpha;
}

EnergyTerm::ObstacleMotion ObstacleContactEnergy::obstacle_motion() const {
  ObstacleMotion motion = ObstacleMotion::none;
  for (int o = 0; o < num_obstacles(); ++o) {
    if (!m_moving[o]) continue;
    if (m_mode[o] != Mode::vertices || !m_obstacles[o]->moves_affinely(m_t0, m_t1))
      return ObstacleMotion::unsupported;
    motion = ObstacleMotion::follow;
  }
  return motion;
}

bool ObstacleContactEnergy::obstacles_close_in(const Eigen::VectorXd& x) const {
  ScopedTimer timer(m_stats->seconds);
  const double dhat = m_params.dhat;
  for (int o = 0; o < num_obstacles(); ++o) {
    if (!m_moving[o]) continue;
    const auto& obs = *m_obstacles[o];
    collision::Aabb swept = obs.swept_bounds(m_t0, m_t1);
    swept.inflate(dhat);
    const Eigen::Vector3d lift = lift_of(o, x);
    for (int v = 0; v < m_area.size(); ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v) - lift;
      if (swept.distance_to(p) > 0) continue;
      const double before = obs.distance(p, m_t0), after = obs.distance(p, m_t1);
      if (after < 0.5 * std::min(before, dhat)) return true;
    }
  }
  return false;
}

void ObstacleContactEnergy::set_obstacle_time(double t) {
  m_time = t;
  update_bounds();
}

void ObstacleContactEnergy::add_obstacle_motion_gradient(const Eigen::VectorXd& x, double dt,
                                                         Eigen::VectorXd& g) const {
  ScopedTimer timer(m_stats->seconds);
  const double dhat = m_params.dhat;
  for (int o = 0; o < num_obstacles(); ++o) {
    if (!m_moving[o]) continue;
    const auto& obs = *m_obstacles[o];
    const Eigen::Vector3d lift = lift_of(o, x);
    for (int v = 0; v < m_area.size(); ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v) - lift;
      if (!near_bounds(o, p)) continue;
      Eigen::Vector3d n;
      const double d = obs.distance(p, m_time, &n);
      if (d >= dhat || d <= 0) continue;
      const double phi_t = -n.dot(obs.velocity(p, m_time));
      const double change = kappa(v) * barrier_second_derivative(d, dhat) * phi_t * dt;
      g.segment<3>(3 * v) += change * n;
      // A coupled body takes the reaction (dr/dq = -e_z e_z^T, set_rigid_block).
      if (m_rigid[o] >= 0 && g.size() >= 3 * m_rigid[o] + 3)
        g[3 * m_rigid[o] + 2] -= change * n.z();
    }
  }
}

double ObstacleContactEnergy::max_step_with_obstacles(const Eigen::VectorXd& x,
                                                      const Eigen::VectorXd& dx, double dt) const {
  ScopedTimer timer(m_stats->seconds);
  double alpha = 1.0;
  const FaceBoxes boxes = face_boxes(x);
  const std::vector<double> speeds = face_speeds(dx);
  for (int o = 0; o < num_obstacles(); ++o) {
    if (!m_moving[o] || dt == 0) {
      alpha = obstacle_max_step(o, x, dx, alpha, boxes, speeds);
      continue;
    }
    const auto& obs = *m_obstacles[o];
    collision::Aabb swept = obs.swept_bounds(m_time, m_time + dt);
    swept.inflate(m_params.dhat);
    const Eigen::Vector3d lift = lift_of(o, x), dlift = lift_of(o, dx);
    for (int v = 0; v < m_area.size(); ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v) - lift, d = dx.segment<3>(3 * v) - dlift;
      collision::Aabb path;
      path.extend(p);
      path.extend(Eigen::Vector3d(p + alpha * d));
      if (path.distance_to(swept) > 0) continue;  // cannot reach the obstacle within this step
      const double a = obs.moving_segment_step(p, d, m_time, dt, alpha, 0.1);
      if (a < 0) throw NumericError("contact: an obstacle's motion cannot be followed");
      alpha = std::min(alpha, a);
    }
  }
  return pairs_max_step(x, dx, alpha);
}

double ObstacleContactEnergy::surface_distance(int o, const Eigen::VectorXd& x, double t) const {
  ScopedTimer timer(m_stats->seconds);
  const collision::Collider& obs = *m_obstacles[o];
  double m = INF;
  const Eigen::Vector3d lift = lift_of(o, x);
  const Eigen::Affine3d pose = obs.motion.pose(t);
  for (int v = 0; v < m_area.size(); ++v)
    m = std::min(m, obs.distance_at_pose(x.segment<3>(3 * v) - lift, pose));
  if (m_mode[o] == Mode::vertices || !(m > 0)) return m;
  const auto face_box = [&](int f) {
    collision::Aabb b;
    for (int k = 0; k < 3; ++k) b.extend(Eigen::Vector3d(x.segment<3>(3 * m_faces(f, k))));
    return b;
  };
  collision::Aabb bounds = obs.bounds(t);
  if (m_mode[o] == Mode::sphere || m_mode[o] == Mode::search) {
    for (int f = 0; f < m_faces.rows(); ++f) {
      if (face_box(f).distance_to(bounds) >= m) continue;  // the face min is at least that
      if (m_mode[o] == Mode::sphere) {
        collision::PairPoints pts;
        collision::DistanceStencil s;
        m = std::min(m, sphere_face_distance(o, x, f, pose, pts, s));
        continue;
      }
      collision::TriangleSdfParams p = m_triangle;
      p.cutoff = m;
      m = std::min(
          m, face_minimum(obs, x.segment<3>(3 * m_faces(f, 0)), x.segment<3>(3 * m_faces(f, 1)),
                          x.segment<3>(3 * m_faces(f, 2)), pose, p)
                 .distance);
    }
    return m;
  }
  // Polyhedron: corners against faces and edges against edges, within the vertex minimum; an
  // obstacle edge through a face (every vertex outside) counts as distance 0.
  std::vector<WorldFeatures> features(m_obstacles.size());
  features[o] = world_features(o, t);
  const WorldFeatures& w = features[o];
  for (int f = 0; f < m_faces.rows(); ++f) {
    if (face_box(f).distance_to(bounds) > 0) continue;
    const Eigen::Vector3d a = x.segment<3>(3 * m_faces(f, 0)), b = x.segment<3>(3 * m_faces(f, 1)),
                          c = x.segment<3>(3 * m_faces(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    for (const auto& [i, j] : w.edges) {
      const Eigen::Vector3d &p = w.corners[i], &q = w.corners[j];
      const double sp = n.dot(p - a), sq = n.dot(q - a);
      if (sp * sq > 0 || sp == sq) continue;                   // both ends on one side of the plane
      const Eigen::Vector3d y = p + sp / (sp - sq) * (q - p);  // where the edge meets the plane
      const bool inside = n.dot((b - a).cross(y - a)) >= 0 && n.dot((c - b).cross(y - b)) >= 0 &&
                          n.dot((a - c).cross(y - c)) >= 0;
      if (inside) return 0.0;
    }
  }
  for (const FeaturePair& p : feature_pairs(x, nullptr, m, features)) {
    if (p.obstacle != o) continue;
    const collision::PairPoints pts = pair_points(p, x, features);
    m = std::min(m, std::sqrt(p.edge_edge ? collision::edge_edge_distance_squared(pts)
                                          : collision::point_triangle_distance_squared(pts)));
  }
  return m;
}

}  // namespace papersim::simulation
