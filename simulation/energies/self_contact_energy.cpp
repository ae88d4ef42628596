#include "simulation/energies/self_contact_energy.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>

#include "collision/barrier.hpp"
#include "collision/self_intersection.hpp"
#include "simulation/energies/psd.hpp"
#include "simulation/energies/scoped_timer.hpp"

namespace papersim::simulation {

using collision::DistanceStencil;
using collision::Matrix12d;
using collision::PairPoints;
using collision::Vector12d;

namespace {

/// The first nv vertices of flat positions x as rows.
Eigen::MatrixX3d sheet_positions(const Eigen::VectorXd& x, int nv) {
  Eigen::MatrixX3d p(nv, 3);
  for (int v = 0; v < nv; ++v) p.row(v) = x.segment<3>(3 * v).transpose();
  return p;
}

}  // namespace

SelfContactEnergy::SelfContactEnergy(const Eigen::MatrixX2d& X, const Eigen::MatrixX3i& F,
                                     const SelfContactParams& params)
    : m_mesh(collision::SelfContactMesh::from_faces(F, static_cast<int>(X.rows()))),
      m_params(params) {
  if (!(params.dhat > 0)) throw std::invalid_argument("self contact: thickness must be positive");
  if (!(params.stiffness > 0))
    throw std::invalid_argument("self contact: stiffness must be positive");
  m_stiffness = params.stiffness;
  const Eigen::Index nv = X.rows(), ne = m_mesh.edges.rows();
  m_vertex_area = Eigen::VectorXd::Zero(nv);
  m_edge_area = Eigen::VectorXd::Zero(ne);
  m_edge_rest.resize(ne);
  for (Eigen::Index e = 0; e < ne; ++e)
    m_edge_rest[e] = (X.row(m_mesh.edges(e, 1)) - X.row(m_mesh.edges(e, 0))).norm();
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector2d e1 = X.row(F(f, 1)) - X.row(F(f, 0)),
                          e2 = X.row(F(f, 2)) - X.row(F(f, 0));
    const double a = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    for (int k = 0; k < 3; ++k) {
      m_vertex_area[F(f, k)] += a / 3;
      const int i = std::min(F(f, k), F(f, (k + 1) % 3)), j = std::max(F(f, k), F(f, (k + 1) % 3));
      // Edges are sorted (i, j): find this one.
      Eigen::Index lo = 0, hi = ne;
      while (lo < hi) {
        const Eigen::Index mid = (lo + hi) / 2;
        if (m_mesh.edges(mid, 0) < i || (m_mesh.edges(mid, 0) == i && m_mesh.edges(mid, 1) < j))
          lo = mid + 1;
        else
          hi = mid;
      }
      m_edge_area[lo] += a / 3;
    }
  }
}

std::array<int, 4> SelfContactEnergy::vertices(const Pair& p) const {
  if (p.edge_edge)
    return {
        {m_mesh.edges(p.a, 0), m_mesh.edges(p.a, 1), m_mesh.edges(p.b, 0), m_mesh.edges(p.b, 1)}};
  return {{p.a, m_mesh.faces(p.b, 0), m_mesh.faces(p.b, 1), m_mesh.faces(p.b, 2)}};
}

PairPoints SelfContactEnergy::points(const Pair& p, const Eigen::VectorXd& x) const {
  const std::array<int, 4> v = vertices(p);
  PairPoints pts;
  for (int k = 0; k < 4; ++k) pts[k] = x.segment<3>(3 * v[k]);
  return pts;
}

double SelfContactEnergy::weight(const Pair& p) const {
  return p.edge_edge ? 0.25 * (m_edge_area[p.a] + m_edge_area[p.b]) : 0.5 * m_vertex_area[p.a];
}

double SelfContactEnergy::mollifier_eps(const Pair& p) const {
  return collision::edge_edge_mollifier_threshold(m_edge_rest[p.a], m_edge_rest[p.b]);
}

std::uint64_t SelfContactEnergy::key(const Pair& p) {
  return (std::uint64_t(p.edge_edge) << 62) | (std::uint64_t(p.a) << 31) | std::uint64_t(p.b);
}

SelfContactEnergy::Pair SelfContactEnergy::pair_of(std::uint64_t key) {
  return {(key >> 62) != 0, static_cast<int>((key >> 31) & 0x7fffffff),
          static_cast<int>(key & 0x7fffffff)};
}

namespace {

/// Mean of the vertex vectors of a flat 3N vector.
Eigen::Vector3d vertex_mean(const Eigen::VectorXd& d) {
  const Eigen::Index nv = d.size() / 3;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (Eigen::Index v = 0; v < nv; ++v) mean += d.segment<3>(3 * v);
  return nv > 0 ? Eigen::Vector3d(mean / static_cast<double>(nv)) : mean;
}

/// Largest |d_v - mean(d)| over the vertices of a flat 3N vector [m].
double relative_motion(const Eigen::VectorXd& d) {
  const Eigen::Index nv = d.size() / 3;
  const Eigen::Vector3d mean = vertex_mean(d);
  double m = 0;
  for (Eigen::Index v = 0; v < nv; ++v) m = std::max(m, (d.segment<3>(3 * v) - mean).squaredNorm());
  return std::sqrt(m);
}

}  // namespace

bool SelfContactEnergy::covered(const Eigen::VectorXd& x) const {
  if (m_base.size() != x.size()) return false;
  if (m_segment_dx.size() == 0) return relative_motion(x - m_base) <= 0.5 * m_margin;
  // Segment set: x within dhat / 4 of the segment point base + a dx (a the least-squares
  // fraction, clamped to [0, 1]), after removing the common translation.
  const double dd = m_segment_dx.squaredNorm();
  const double a = dd > 0 ? std::clamp((x - m_base).dot(m_segment_dx) / dd, 0.0, 1.0) : 0.0;
  return relative_motion(x - m_base - a * m_segment_dx) <= 0.25 * m_params.dhat;
}

void SelfContactEnergy::find_candidates(const Eigen::VectorXd& x, const Eigen::VectorXd* dx) const {
  m_base = x;
  Eigen::VectorXd x1 = x;
  if (dx) {
    // Swept boxes along dx less its mean: pair distances are translation invariant.
    m_segment_dx = *dx;
    const Eigen::Vector3d mean = vertex_mean(*dx);
    for (Eigen::Index v = 0; v < x.size() / 3; ++v)
      x1.segment<3>(3 * v) += dx->segment<3>(3 * v) - mean;
    m_margin = 0;
  } else {
    m_segment_dx.resize(0);
    m_margin = 2 * m_params.dhat;
  }
  const collision::SelfContactCandidates c =
      collision::find_self_contact_candidates(m_mesh, x, x1, 1.5 * m_params.dhat + m_margin);
  m_candidates.clear();
  m_candidates.reserve(c.size());
  for (const auto& [v, f] : c.point_triangle) m_candidates.push_back({false, v, f});
  for (const auto& [a, b] : c.edge_edge) m_candidates.push_back({true, a, b});
  m_base_distance.assign(m_candidates.size(), 0.0);
}

Eigen::VectorXd SelfContactEnergy::motions(const Eigen::VectorXd& x) const {
  const Eigen::Index nv = x.size() / 3;
  const Eigen::VectorXd d = x - m_base;
  const Eigen::Vector3d mean = vertex_mean(d);
  Eigen::VectorXd m(nv);
  for (Eigen::Index v = 0; v < nv; ++v) m[v] = (d.segment<3>(3 * v) - mean).norm();
  return m;
}

double SelfContactEnergy::pair_motion(const Pair& p, const Eigen::VectorXd& moved) const {
  const std::array<int, 4> v = vertices(p);
  if (p.edge_edge) return std::max(moved[v[0]], moved[v[1]]) + std::max(moved[v[2]], moved[v[3]]);
  return moved[v[0]] + std::max({moved[v[1]], moved[v[2]], moved[v[3]]});
}

void SelfContactEnergy::build_candidates(const Eigen::VectorXd& x,
                                         const Eigen::VectorXd& dx) const {
  // A set at a base with a margin covers the segment when it covers both ends (the relative
  // motion is convex along the segment: a maximum of norms of affine functions).
  if (m_segment_dx.size() == 0 && covered(x) && covered(x + dx)) return;
  // the margin (2 dhat) covers the whole step
  if (relative_motion(dx) <= m_params.dhat)
    find_candidates(x, nullptr);
  else
    find_candidates(x, &dx);
}

void SelfContactEnergy::ensure_candidates(const Eigen::VectorXd& x) const {
  if (!covered(x)) find_candidates(x, nullptr);
}

double SelfContactEnergy::stencil_distance2(std::size_t k, const PairPoints& pts,
                                            DistanceStencil& s, double reject2,
                                            const Eigen::VectorXd& moved) const {
  const Pair& p = m_candidates[k];
  // A bound kept from an earlier x first, then one from bounding spheres: most candidates are
  // neighbours in the mesh a whole edge apart, and the closest-feature search costs several
  // times more (measured: the stencils were 6% of a fall-sphere run with no pair ever within
  // the thickness). Each bound is a distance at x no larger than the pair's, so a pair is
  // rejected only where its distance would be.
  const double motion = pair_motion(p, moved);
  const double kept = m_base_distance[k] - motion;
  if (kept > 0 && kept * kept >= reject2) return kept * kept;
  const double gap = collision::pair_distance_lower_bound(pts, p.edge_edge);
  if (gap > 0 && gap * gap >= reject2) {
    m_base_distance[k] = std::max(m_base_distance[k], gap - motion);
    return gap * gap;
  }
  s = p.edge_edge ? collision::edge_edge_stencil(pts) : collision::point_triangle_stencil(pts);
  const double d2 = collision::distance_squared(s, pts);
  m_base_distance[k] = std::max(m_base_distance[k], std::sqrt(d2) - motion);
  return d2;
}

void SelfContactEnergy::begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) {
  ScopedTimer timer(m_stats->seconds);
  m_eps = m_params.eps_velocity * (m_params.static_whole_step ? ctx.whole_step() : ctx.h);
  m_t0 = ctx.time_t0;
  m_stiffness = std::max(m_params.stiffness, ctx.self_contact_stiffness);
  m_stats->max_stiffness = std::max(m_stats->max_stiffness, m_stiffness);
  const int nv = m_mesh.num_vertices;
  const Eigen::MatrixX3d p = sheet_positions(x_t0, nv);
  m_floor =
      nv > 0 ? floor_fraction * (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm() : 0.0;
  if (m_params.trace.on(Trace::intersect))
    m_params.trace(Trace::intersect, "self t %.6f h %.3e: %d intersecting pairs", ctx.time_t0,
                   ctx.h,
                   collision::count_self_intersections(sheet_positions(x_t0, m_mesh.num_vertices),
                                                       m_mesh.faces));
  ensure_candidates(x_t0);
  m_last_below = distance_below(x_t0, m_floor);
  m_friction.clear();
  m_friction_keys.clear();
  if (m_params.friction <= 0) return;
  const double dhat = m_params.dhat, kappa = m_stiffness / dhat;
  const Eigen::VectorXd moved = motions(x_t0);
  for (std::size_t k = 0; k < m_candidates.size(); ++k) {
    const Pair& p = m_candidates[k];
    const PairPoints pts = points(p, x_t0);
    DistanceStencil s;
    const double d2 = stencil_distance2(k, pts, s, dhat * dhat, moved);
    if (d2 >= dhat * dhat || d2 <= 0) continue;
    const double d = std::sqrt(d2);
    const double m =
        p.edge_edge ? collision::edge_edge_mollifier(pts, mollifier_eps(p), nullptr, nullptr) : 1.0;
    const double lambda = -kappa * weight(p) * m * collision::barrier_first_derivative(d, dhat);
    if (!(lambda > 0)) continue;
    FrictionPair fp;
    fp.vertices = vertices(p);
    fp.weights = collision::closest_point_weights(s, pts);
    fp.r_t0 = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) fp.r_t0 += fp.weights[k] * pts[k];
    const Eigen::Vector3d n = fp.r_t0.normalized();
    const Eigen::Vector3d a =
        std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    fp.T.col(0) = n.cross(a).normalized();
    fp.T.col(1) = n.cross(fp.T.col(0));
    fp.mu_lambda = m_params.friction * lambda;
    m_friction.push_back(fp);
    m_friction_keys.push_back(key(p));
  }
  std::sort(m_friction_keys.begin(), m_friction_keys.end());
  if (m_params.trace.on(Trace::contact)) {
    double largest = 0, total = 0;
    for (const FrictionPair& fp : m_friction)
      largest = std::max(largest, fp.mu_lambda), total += fp.mu_lambda;
    m_params.trace(Trace::contact,
                   "self t %.6f h %.3e: %zu friction pairs, mu lambda largest %.3e N, sum %.3e N, "
                   "static zone %.3e m",
                   ctx.time_t0, ctx.h, m_friction.size(), largest, total, m_eps);
  }
}

bool SelfContactEnergy::update_pattern(const Eigen::VectorXd& x) {
  ScopedTimer timer(m_stats->seconds);
  ensure_candidates(x);
  const double dhat2 = m_params.dhat * m_params.dhat, near2 = 4 * dhat2;
  bool missing = !std::includes(m_pattern.begin(), m_pattern.end(), m_friction_keys.begin(),
                                m_friction_keys.end());
  std::vector<Pair> near;
  const Eigen::VectorXd moved = motions(x);
  for (std::size_t k = 0; k < m_candidates.size(); ++k) {
    const Pair& p = m_candidates[k];
    DistanceStencil s;
    const double d2 = stencil_distance2(k, points(p, x), s, near2, moved);
    if (d2 >= near2) continue;
    near.push_back(p);
    if (!missing && d2 < dhat2)
      missing = !std::binary_search(m_pattern.begin(), m_pattern.end(), key(p));
  }
  // Pairs far apart in the mesh add fill to the factorisation (measured on the strip scene:
  // 1.7x the factor's nonzeros), so a pattern holding far more pairs than are near (a contact
  // ended) is rebuilt too.
  const size_t needed = near.size() + m_friction_keys.size();
  // Even a few long-range pairs close a long strip into a loop and double the fill: once no
  // pair is near, the dynamic pattern is emptied.
  const bool excess = needed == 0 ? !m_pattern.empty() : m_pattern.size() > 4 * needed + 64;
  if (!missing && !excess) return false;
  // Rebuild with the pairs within 2 dhat and the friction pairs: the pattern then holds until
  // a pair closes from 2 dhat to dhat.
  set_pattern(std::move(near), m_friction_keys);
  ++m_stats->pattern_changes;
  return true;
}

void SelfContactEnergy::set_pattern(std::vector<Pair> pairs,
                                    const std::vector<std::uint64_t>& extra_keys) {
  m_pattern.clear();
  for (const Pair& p : pairs) m_pattern.push_back(key(p));
  m_pattern.insert(m_pattern.end(), extra_keys.begin(), extra_keys.end());
  std::sort(m_pattern.begin(), m_pattern.end());
  m_pattern.erase(std::unique(m_pattern.begin(), m_pattern.end()), m_pattern.end());
  m_pattern_pairs = std::move(pairs);
}

std::vector<std::array<int, 3>> SelfContactEnergy::pattern_pairs() const {
  std::vector<std::array<int, 3>> out;
  out.reserve(m_pattern.size());
  for (const std::uint64_t k : m_pattern) {
    const Pair p = pair_of(k);
    out.push_back({{p.edge_edge ? 1 : 0, p.a, p.b}});
  }
  return out;
}

void SelfContactEnergy::restore_pattern(const std::vector<std::array<int, 3>>& pairs) {
  std::vector<Pair> restored;
  restored.reserve(pairs.size());
  for (const auto& [kind, a, b] : pairs) {
    const int na = kind == 1 ? static_cast<int>(m_mesh.edges.rows()) : m_mesh.num_vertices;
    const int nb = static_cast<int>(kind == 1 ? m_mesh.edges.rows() : m_mesh.faces.rows());
    if ((kind != 0 && kind != 1) || a < 0 || a >= na || b < 0 || b >= nb)
      throw std::invalid_argument("self-contact pattern pair (" + std::to_string(kind) + ", " +
                                  std::to_string(a) + ", " + std::to_string(b) +
                                  ") is not a pair of this mesh");
    restored.push_back({kind == 1, a, b});
  }
  set_pattern(std::move(restored), {});
}

void SelfContactEnergy::add_dynamic_pattern(SparsityBuilder& pattern) const {
  for (const Pair& p : m_pattern_pairs) {
    const std::array<int, 4> v = vertices(p);
    pattern.add_clique(v.data(), 4);
  }
  for (const FrictionPair& fp : m_friction) pattern.add_clique(fp.vertices.data(), 4);
}

double SelfContactEnergy::value(const Eigen::VectorXd& x) const {
  ScopedTimer timer(m_stats->seconds);
  ensure_candidates(x);
  const double dhat = m_params.dhat, kappa = m_stiffness / dhat;
  double e = 0;
  const Eigen::VectorXd moved = motions(x);
  for (std::size_t k = 0; k < m_candidates.size(); ++k) {
    const Pair& p = m_candidates[k];
    const PairPoints pts = points(p, x);
    DistanceStencil s;
    const double d2 = stencil_distance2(k, pts, s, dhat * dhat, moved);
    if (d2 >= dhat * dhat) continue;
    if (!(d2 > 0)) return INF;
    const double m =
        p.edge_edge ? collision::edge_edge_mollifier(pts, mollifier_eps(p), nullptr, nullptr) : 1.0;
    e += kappa * weight(p) * m * collision::barrier(std::sqrt(d2), dhat);
  }
  for (const FrictionPair& fp : m_friction) {
    Eigen::Vector3d r = -fp.r_t0;
    for (int k = 0; k < 4; ++k) r += fp.weights[k] * x.segment<3>(3 * fp.vertices[k]);
    e += fp.mu_lambda * collision::friction_f0((fp.T.transpose() * r).norm(), m_eps);
  }
  return e;
}

void SelfContactEnergy::add_pair(const Pair& p, const PairPoints& pts, const DistanceStencil& s,
                                 Eigen::VectorXd& g, BlockSymmetricMatrix* H, bool project) const {
  const double scale = m_stiffness / m_params.dhat * weight(p);
  Vector12d grad;
  Matrix12d hess;
  collision::pair_barrier_derivatives(s, pts, m_params.dhat, p.edge_edge ? mollifier_eps(p) : 0.0,
                                      grad, H ? &hess : nullptr);
  const std::array<int, 4> v = vertices(p);
  for (int k = 0; k < 4; ++k) g.segment<3>(3 * v[k]) += scale * grad.segment<3>(3 * k);
  if (H) {
    hess *= scale;
    H->add_element<4>(v, project ? project_psd(hess) : hess);
  }
}

void SelfContactEnergy::add_friction(const Eigen::VectorXd& x, Eigen::VectorXd& g,
                                     BlockSymmetricMatrix* H) const {
  for (const FrictionPair& fp : m_friction) {
    Eigen::Vector3d r = -fp.r_t0;
    for (int k = 0; k < 4; ++k) r += fp.weights[k] * x.segment<3>(3 * fp.vertices[k]);
    const Eigen::Vector2d u = fp.T.transpose() * r;
    const Eigen::Vector3d f = fp.mu_lambda * (fp.T * collision::friction_gradient(u, m_eps));
    for (int k = 0; k < 4; ++k) g.segment<3>(3 * fp.vertices[k]) += fp.weights[k] * f;
    if (!H) continue;
    // d r / d x_k = w_k I: Hess = (w w^T) kron (T Hf T^T), PSD as Hf is (barrier.hpp).
    const Eigen::Matrix3d M =
        fp.mu_lambda * fp.T * collision::friction_hessian(u, m_eps) * fp.T.transpose();
    Matrix12d local;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        local.block<3, 3>(3 * a, 3 * b) = fp.weights[a] * fp.weights[b] * M;
    H->add_element<4>(fp.vertices, local);
  }
}

void SelfContactEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& g,
                                        BlockSymmetricMatrix* H,
                                        HessianProjection projection) const {
  ScopedTimer timer(m_stats->seconds);
  ensure_candidates(x);
  const double dhat2 = m_params.dhat * m_params.dhat;
  int active = 0;
  const Eigen::VectorXd moved = motions(x);
  for (std::size_t k = 0; k < m_candidates.size(); ++k) {
    const Pair& p = m_candidates[k];
    const PairPoints pts = points(p, x);
    DistanceStencil s;
    const double d2 = stencil_distance2(k, pts, s, dhat2, moved);
    if (d2 >= dhat2 || !(d2 > 0)) continue;
    ++active;
    add_pair(p, pts, s, g, H, projection == HessianProjection::psd);
  }
  add_friction(x, g, H);
  m_active = active;
  m_stats->max_active_pairs = std::max(m_stats->max_active_pairs, active);
}

void SelfContactEnergy::report_crossings(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                         double alpha) const {
  const int nv = m_mesh.num_vertices;
  const Eigen::VectorXd x1 = x + alpha * dx;
  const int before = collision::count_self_intersections(sheet_positions(x, nv), m_mesh.faces);
  const collision::SelfIntersections after =
      collision::find_self_intersections(sheet_positions(x1, nv), m_mesh.faces);
  if (after.count() <= before) return;
  const Trace& trace = m_params.trace;
  trace(Trace::intersect,
        "self-contact CCD: %d -> %d intersecting pairs at step %.3e (%zu candidates)", before,
        after.count(), alpha, m_candidates.size());
  for (int k = 0; k < after.count(); ++k) {
    const int fa = after.pairs(k, 0), fb = after.pairs(k, 1);
    trace(Trace::intersect, "  faces %d and %d", fa, fb);
    // The IPC pairs of the two faces: vertex-triangle both ways, and edge-edge.
    std::vector<Pair> pairs;
    std::vector<int> edges_a, edges_b;
    for (int e = 0; e < m_mesh.edges.rows(); ++e) {
      const auto holds = [&](int f) {
        int n = 0;
        for (int i = 0; i < 3; ++i)
          n += m_mesh.faces(f, i) == m_mesh.edges(e, 0) || m_mesh.faces(f, i) == m_mesh.edges(e, 1);
        return n == 2;
      };
      if (holds(fa)) edges_a.push_back(e);
      if (holds(fb)) edges_b.push_back(e);
    }
    for (int i = 0; i < 3; ++i) {
      pairs.push_back({false, m_mesh.faces(fa, i), fb});
      pairs.push_back({false, m_mesh.faces(fb, i), fa});
    }
    for (int ea : edges_a)
      for (int eb : edges_b) pairs.push_back({true, std::min(ea, eb), std::max(ea, eb)});
    for (const Pair& p : pairs) {
      const std::array<int, 4> v = vertices(p);
      const bool adjacent = p.edge_edge
                                ? (v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3])
                                : (v[0] == v[1] || v[0] == v[2] || v[0] == v[3]);
      if (adjacent) continue;  // not an IPC pair
      const bool candidate = std::any_of(
          m_candidates.begin(), m_candidates.end(),
          [&](const Pair& c) { return c.edge_edge == p.edge_edge && c.a == p.a && c.b == p.b; });
      const PairPoints p0 = points(p, x), p1 = points(p, x1);
      PairPoints d;
      for (int k2 = 0; k2 < 4; ++k2) d[k2] = dx.segment<3>(3 * v[k2]);
      const auto distance = [&](const PairPoints& pts) {
        return std::sqrt(collision::distance_squared(p.edge_edge
                                                         ? collision::edge_edge_stencil(pts)
                                                         : collision::point_triangle_stencil(pts),
                                                     pts));
      };
      const double t = p.edge_edge
                           ? collision::edge_edge_ccd(p0, d, 1.0, m_params.ccd_min_separation)
                           : collision::point_triangle_ccd(p0, d, 1.0, m_params.ccd_min_separation);
      trace(Trace::intersect,
            "    %s (vertices %d %d %d %d): candidate %d, distance %.3e -> %.3e, CCD %.3e",
            p.edge_edge ? "edge-edge" : "vertex-triangle", v[0], v[1], v[2], v[3],
            candidate ? 1 : 0, distance(p0), distance(p1), t);
    }
  }
}

double SelfContactEnergy::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  ScopedTimer timer(m_stats->seconds);
  // One broad phase over the swept boxes serves the CCD here (a superset of the pairs whose
  // swept boxes meet) and every energy evaluation of the line search after it.
  build_candidates(x, dx);
  double alpha = 1.0;
  for (const Pair& p : m_candidates) {
    const std::array<int, 4> v = vertices(p);
    PairPoints d;
    for (int k = 0; k < 4; ++k) d[k] = dx.segment<3>(3 * v[k]);
    alpha =
        p.edge_edge
            ? collision::edge_edge_ccd(points(p, x), d, alpha, m_params.ccd_min_separation)
            : collision::point_triangle_ccd(points(p, x), d, alpha, m_params.ccd_min_separation);
  }
  if (m_params.trace.on(Trace::intersect)) report_crossings(x, dx, alpha);
  return alpha;
}

double SelfContactEnergy::distance_below(const Eigen::VectorXd& x, double floor) const {
  ensure_candidates(x);
  const double floor2 = floor * floor;
  double best2 = floor2;
  const Eigen::VectorXd moved = motions(x);
  for (std::size_t k = 0; k < m_candidates.size(); ++k) {
    DistanceStencil s;
    best2 = std::min(best2, stencil_distance2(k, points(m_candidates[k], x), s, floor2, moved));
  }
  return best2 < floor2 ? std::sqrt(best2) : INF;
}

bool SelfContactEnergy::adapt(const Eigen::VectorXd& x) {
  ScopedTimer timer(m_stats->seconds);
  const double d = distance_below(x, m_floor), before = m_last_below;
  m_last_below = d;
  const double most = max_stiffness_factor * m_params.stiffness;
  if (!(d < before) || before == INF || m_stiffness >= most) return false;  // INF: not below
  m_stiffness = std::min(2 * m_stiffness, most);
  m_stats->max_stiffness = std::max(m_stats->max_stiffness, m_stiffness);
  ++m_stats->stiffness_doublings;
  m_params.trace(Trace::contact,
                 "self t %.6f: closest pair %.3e -> %.3e m (floor %.3e): stiffness %.4g Pa", m_t0,
                 before, d, m_floor, m_stiffness);
  return true;
}

double SelfContactEnergy::min_distance(const Eigen::VectorXd& x, double radius) const {
  return collision::min_self_distance(m_mesh, x, radius);
}

}  // namespace papersim::simulation
