#include "remesh/sizing.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "remesh/errors.hpp"

namespace papersim::remesh {

namespace {

std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

void require(bool ok, const std::string& name, const std::string& rule, double value) {
  if (!ok)
    throw ParameterError("remesh: " + name + " must be " + rule + " (got " + number(value) + ")");
}

/// `element` names what a row is for: "vertex" or "face".
void check_rows(const std::string& name, Eigen::Index rows, int n,
                const std::string& element = "vertex") {
  if (rows != n)
    throw MeshError("remesh: state." + name + " has " + std::to_string(rows) +
                    " rows, the mesh has " + std::to_string(n) + " " +
                    (element == "vertex" ? "vertices" : element + "s"));
}

template <typename Derived>
void check_finite(const std::string& name, const Eigen::MatrixBase<Derived>& m,
                  const std::string& element = "vertex") {
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    if (!m.row(r).allFinite())
      throw MeshError("remesh: state." + name + " of " + element + " " + std::to_string(r) +
                      " is NaN or infinite");
}

/// Symmetric 2 x 2 matrix function applied to the eigenvalues.
template <typename Fn>
Eigen::Matrix2d map_eigenvalues(const Eigen::Matrix2d& a, Fn fn) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (a + a.transpose()));
  Eigen::Vector2d l = es.eigenvalues();
  for (int i = 0; i < 2; ++i) l(i) = fn(l(i));
  return es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
}

/// The adjugate of a 2 x 2 matrix (ArcSim's perp).
Eigen::Matrix2d adjugate(const Eigen::Matrix2d& a) {
  Eigen::Matrix2d p;
  p << a(1, 1), -a(1, 0), -a(0, 1), a(0, 0);
  return p;
}

/// A symmetric tensor as a disk in (a, b; r): M = r I + a diag(1, -1) + b [[0, 1], [1, 0]].
struct Disk {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  double r = 0.0;
};

bool encloses(const Disk& outer, const Disk& inner) {
  const double slack = 1e-9 * std::max(outer.r, inner.r);
  return (outer.c - inner.c).norm() + inner.r <= outer.r + slack;
}

bool encloses_all(const Disk& d, const std::vector<Disk>& disks) {
  return std::all_of(disks.begin(), disks.end(), [&](const Disk& e) { return encloses(d, e); });
}

/// The smallest disk containing two disks.
Disk enclose_pair(const Disk& a, const Disk& b) {
  const double d = (b.c - a.c).norm();
  if (d + b.r <= a.r) return a;
  if (d + a.r <= b.r) return b;
  Disk out;
  out.r = 0.5 * (a.r + d + b.r);
  out.c = a.c + ((out.r - a.r) / d) * (b.c - a.c);
  return out;
}

/// The disks containing and touching three disks (Apollonius' problem, internal tangency):
/// |c - c_i| = R - r_i. Differences of the squared equations are linear in (c, R).
std::vector<Disk> enclose_triple(const Disk& d1, const Disk& d2, const Disk& d3) {
  Eigen::Matrix2d a;
  Eigen::Vector2d b0, b1;
  const Disk* others[2] = {&d2, &d3};
  for (int j = 0; j < 2; ++j) {
    const Disk& dj = *others[j];
    a.row(j) = 2.0 * (dj.c - d1.c).transpose();
    b0(j) = dj.c.squaredNorm() - d1.c.squaredNorm() - dj.r * dj.r + d1.r * d1.r;
    b1(j) = 2.0 * (dj.r - d1.r);
  }
  std::vector<Disk> out;
  const double scale = a.cwiseAbs().maxCoeff();
  if (!(std::abs(a.determinant()) > 1e-12 * scale * scale)) return out;
  const Eigen::Vector2d p = a.partialPivLu().solve(b0), q = a.partialPivLu().solve(b1);
  const Eigen::Vector2d w = p - d1.c;
  const double qa = q.squaredNorm() - 1.0, qb = 2.0 * (w.dot(q) + d1.r),
               qc = w.squaredNorm() - d1.r * d1.r;
  std::vector<double> roots;
  if (std::abs(qa) < 1e-14) {
    if (qb != 0.0) roots.push_back(-qc / qb);
  } else {
    const double disc = qb * qb - 4 * qa * qc;
    if (disc >= 0) {
      roots.push_back((-qb + std::sqrt(disc)) / (2 * qa));
      roots.push_back((-qb - std::sqrt(disc)) / (2 * qa));
    }
  }
  for (double r : roots)
    if (r >= std::max({d1.r, d2.r, d3.r})) out.push_back({p + q * r, r});
  return out;
}

}  // namespace

void check_params(const RemeshParams& p) {
  require(std::isfinite(p.refine_angle) && p.refine_angle > 0, "refine_angle", "> 0",
          p.refine_angle);
  require(std::isfinite(p.refine_compression), "refine_compression", "finite",
          p.refine_compression);
  require(std::isfinite(p.refine_velocity), "refine_velocity", "finite", p.refine_velocity);
  require(std::isfinite(p.obstacle_distance), "obstacle_distance", "finite", p.obstacle_distance);
  require(std::isfinite(p.size_min) && p.size_min > 0, "size_min", "> 0", p.size_min);
  require(std::isfinite(p.size_max) && p.size_max >= p.size_min, "size_max", ">= size_min",
          p.size_max);
  require(p.aspect_min > 0 && p.aspect_min <= 1, "aspect_min", "in (0, 1]", p.aspect_min);
  require(p.flip_angle_max > 0 && p.flip_angle_max <= M_PI, "flip_angle_max", "in (0, pi]",
          p.flip_angle_max);
}

void check_state(const SheetMesh& mesh, const RemeshState& state) {
  const int nv = mesh.num_vertices();
  check_rows("positions", state.positions.rows(), nv);
  check_rows("velocities", state.velocities.rows(), nv);
  if (state.obstacle_distance.size() > 0)
    check_rows("obstacle_distance", state.obstacle_distance.size(), nv);
  check_finite("positions", state.positions);
  check_finite("velocities", state.velocities);
  check_finite("obstacle_distance", state.obstacle_distance);
  if (state.membrane_strain.rows() > 0)
    check_rows("membrane_strain", state.membrane_strain.rows(), mesh.num_faces(), "face");
  check_finite("membrane_strain", state.membrane_strain, "face");
}

std::vector<double> edge_dihedral_angles(const SheetMesh& sheet, const Eigen::MatrixX3d& x) {
  const TriMesh& m = sheet.mesh();
  std::vector<double> angles(m.n_edges(), 0.0);
  for (auto e : m.edges()) {
    if (m.is_boundary(e)) continue;
    const auto h0 = m.halfedge_handle(e, 0), h1 = m.halfedge_handle(e, 1);
    const Eigen::Vector3d a = x.row(m.from_vertex_handle(h0).idx());
    const Eigen::Vector3d b = x.row(m.to_vertex_handle(h0).idx());
    const Eigen::Vector3d c = x.row(m.to_vertex_handle(m.next_halfedge_handle(h0)).idx());
    const Eigen::Vector3d d = x.row(m.to_vertex_handle(m.next_halfedge_handle(h1)).idx());
    const Eigen::Vector3d edge = b - a;
    const Eigen::Vector3d n0 = edge.cross(c - a), n1 = (d - a).cross(edge);
    // Degenerate world faces (zero-length or collinear edges) have no normal: no angle.
    const bool degenerate = !(n0.norm() > 1e-12 * edge.norm() * (c - a).norm()) ||
                            !(n1.norm() > 1e-12 * edge.norm() * (d - a).norm());
    if (!(edge.norm() > 0) || degenerate) continue;
    angles[e.idx()] = std::atan2(n0.cross(n1).dot(edge.normalized()), n0.dot(n1));
  }
  return angles;
}

Eigen::Matrix2d face_curvature(const SheetMesh& sheet, int f, const std::vector<double>& angles) {
  const TriMesh& m = sheet.mesh();
  const TriMesh::FaceHandle fh(f);
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  double area2 = 0.0;
  for (auto h : m.fh_range(fh)) {
    const auto& p = m.point(m.from_vertex_handle(h));
    const auto& q = m.point(m.to_vertex_handle(h));
    const Eigen::Vector2d e(q[0] - p[0], q[1] - p[1]);
    area2 += p[0] * q[1] - p[1] * q[0];
    const double len = e.norm();
    if (!(len > 0)) continue;
    const Eigen::Vector2d t(e.y() / len, -e.x() / len);
    s += 0.5 * angles[m.edge_handle(h).idx()] * len * t * t.transpose();
  }
  return area2 > 0 ? Eigen::Matrix2d(s / (0.5 * area2)) : Eigen::Matrix2d::Zero();
}

Eigen::Matrix2d compression_metric(const Eigen::Matrix2d& e, const Eigen::Matrix2d& curvature2,
                                   double c) {
  const Eigen::Matrix2d d = e.transpose() * e - 4.0 * c * c * adjugate(curvature2);
  const Eigen::Matrix2d root =
      map_eigenvalues(d, [](double l) { return l >= 0 ? std::sqrt(l) : -std::sqrt(-l); });
  return map_eigenvalues(-e + root, [](double l) { return std::max(l, 0.0); }) / (2.0 * c * c);
}

Eigen::Matrix2d compression_metric_at_resolution(const Eigen::Matrix2d& arcsim,
                                                 const Eigen::Matrix<double, 2, 3>& edges, double c,
                                                 double angle) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (arcsim + arcsim.transpose()));
  Eigen::Vector2d mu = es.eigenvalues();
  for (int j = 0; j < 2; ++j) {
    if (!(mu(j) > 0)) {
      mu(j) = 0;
      continue;
    }
    const double h = (es.eigenvectors().col(j).transpose() * edges).cwiseAbs().maxCoeff();
    const double factor = std::max(1.0, angle * h / (2 * M_PI * c));
    mu(j) /= factor * factor;
  }
  return es.eigenvectors() * mu.asDiagonal() * es.eigenvectors().transpose();
}

Eigen::Matrix2d tensor_max(const std::vector<Eigen::Matrix2d>& tensors) {
  std::vector<Disk> disks;
  for (const Eigen::Matrix2d& t : tensors) {
    if (!(t.trace() > 0)) continue;
    disks.push_back(
        {Eigen::Vector2d(0.5 * (t(0, 0) - t(1, 1)), 0.5 * (t(0, 1) + t(1, 0))), 0.5 * t.trace()});
  }
  if (disks.empty()) return Eigen::Matrix2d::Zero();
  // The smallest enclosing disk touches one, two or three of the disks: try them all (a handful
  // of tensors, so no need for Welzl's algorithm).
  Disk best;
  best.r = std::numeric_limits<double>::infinity();
  auto consider = [&](const Disk& d) {
    if (d.r < best.r && encloses_all(d, disks)) best = d;
  };
  const size_t n = disks.size();
  for (size_t i = 0; i < n; ++i) {
    consider(disks[i]);
    for (size_t j = i + 1; j < n; ++j) {
      consider(enclose_pair(disks[i], disks[j]));
      for (size_t k = j + 1; k < n; ++k)
        for (const Disk& d : enclose_triple(disks[i], disks[j], disks[k])) consider(d);
    }
  }
  if (!std::isfinite(best.r)) {
    // Rounding left every candidate a hair short: the sum dominates every tensor.
    Eigen::Matrix2d sum = Eigen::Matrix2d::Zero();
    for (const Eigen::Matrix2d& t : tensors) sum += t;
    return sum;
  }
  Eigen::Matrix2d out;
  out << best.r + best.c.x(), best.c.y(), best.c.y(), best.r - best.c.x();
  return out;
}

Eigen::Matrix2d clamp_metric(const Eigen::Matrix2d& metric, const RemeshParams& p) {
  const double lo = 1.0 / (p.size_max * p.size_max), hi = 1.0 / (p.size_min * p.size_min);
  if (!metric.allFinite()) return Eigen::Matrix2d::Identity() * hi;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (metric + metric.transpose()));
  Eigen::Vector2d l = es.eigenvalues().cwiseMax(lo).cwiseMin(hi);
  l = l.cwiseMax(p.aspect_min * p.aspect_min * l.maxCoeff());
  return es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
}

std::vector<Eigen::Matrix2d> vertex_metrics(const SheetMesh& sheet,
                                            const std::vector<Eigen::Matrix2d>& face_metrics) {
  const TriMesh& m = sheet.mesh();
  std::vector<Eigen::Matrix2d> sum(m.n_vertices(), Eigen::Matrix2d::Zero());
  std::vector<double> weight(m.n_vertices(), 0.0);
  for (auto f : m.faces()) {
    Eigen::Vector2d x[3];
    int k = 0;
    for (auto v : m.fv_range(f)) x[k++] = sheet.material_coord(v.idx());
    const double area = 0.5 * std::abs((x[1] - x[0]).x() * (x[2] - x[0]).y() -
                                       (x[1] - x[0]).y() * (x[2] - x[0]).x());
    for (auto v : m.fv_range(f)) {
      sum[v.idx()] += area * face_metrics[f.idx()];
      weight[v.idx()] += area;
    }
  }
  for (size_t v = 0; v < sum.size(); ++v)
    if (weight[v] > 0) sum[v] /= weight[v];
  return sum;
}

double aspect_ratio(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Eigen::Vector2d e1 = b - a, e2 = c - a;
  const double area = 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
  const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
  return perimeter > 0 ? 12.0 * std::sqrt(3.0) * area / (perimeter * perimeter) : 0.0;
}

namespace {

/// Gradient in material space of a per-vertex quantity (one row per corner) over a face whose
/// material edge matrix is dm = [X1 - X0, X2 - X0]: a (columns of q) by 2 matrix.
template <int N>
Eigen::Matrix<double, N, 2> material_gradient(const Eigen::Matrix<double, N, 3>& q,
                                              const Eigen::Matrix2d& dm_inv) {
  Eigen::Matrix<double, N, 2> dq;
  dq.col(0) = q.col(1) - q.col(0);
  dq.col(1) = q.col(2) - q.col(0);
  return dq * dm_inv;
}

/// ArcSim's obstacle metric from per-vertex distances d (corners with d < reach contribute
/// grad d grad d^T / d^2, averaged over the three corners).
Eigen::Matrix2d obstacle_metric(const Eigen::Vector3d& d, const Eigen::Matrix2d& dm_inv,
                                double reach, double floor) {
  const Eigen::Matrix<double, 1, 2> g =
      material_gradient<1>(Eigen::Matrix<double, 1, 3>(d.transpose()), dm_inv);
  Eigen::Matrix2d o = Eigen::Matrix2d::Zero();
  for (int k = 0; k < 3; ++k)
    if (d(k) < reach) o += g.transpose() * g / std::pow(std::max(d(k), floor), 2);
  return o / 3.0;
}

/// One face's corners (columns): material [m], world [m], velocities [m/s], obstacle distances
/// [m]; and its membrane strain when the caller gives it (else the chords').
struct FaceInputs {
  Eigen::Matrix<double, 2, 3> material;
  Eigen::Matrix3d world, velocity;
  Eigen::Vector3d distance = Eigen::Vector3d::Zero();
  std::optional<Eigen::Matrix2d> strain;
};

/// The unclamped criteria of one face (Narain et al. 2012, section 4); s is the face's curvature
/// in material coordinates [1/m], kp its plastic curvature [1/m].
SizingTerms face_terms(const FaceInputs& in, const Eigen::Matrix2d& s, const Eigen::Matrix2d& kp,
                       const RemeshParams& p, bool use_obstacles) {
  const Eigen::Matrix2d dm_inv =
      material_gradient<2>(in.material, Eigen::Matrix2d::Identity()).inverse();
  const Eigen::Matrix2d s2 = s.transpose() * s;
  const double a2 = p.refine_angle * p.refine_angle;
  SizingTerms t;
  t.curvature = s2 / a2;
  t.plastic = kp.transpose() * kp / a2;
  if (p.refine_compression > 0) {
    Eigen::Matrix2d green;
    if (in.strain) {
      green = *in.strain;
    } else {
      const Eigen::Matrix<double, 3, 2> def = material_gradient<3>(in.world, dm_inv);
      green = 0.5 * (def.transpose() * def - Eigen::Matrix2d::Identity());
    }
    Eigen::Matrix<double, 2, 3> edges;
    for (int k = 0; k < 3; ++k) edges.col(k) = in.material.col((k + 1) % 3) - in.material.col(k);
    t.compression =
        compression_metric_at_resolution(compression_metric(green, s2, p.refine_compression), edges,
                                         p.refine_compression, p.refine_angle);
  }
  if (p.refine_velocity > 0) {
    const Eigen::Matrix<double, 3, 2> grad_v = material_gradient<3>(in.velocity, dm_inv);
    t.velocity = grad_v.transpose() * grad_v / (p.refine_velocity * p.refine_velocity);
  }
  if (use_obstacles)
    t.obstacle = obstacle_metric(in.distance, dm_inv, p.obstacle_distance, 1e-3 * p.size_min);
  return t;
}

}  // namespace

std::vector<SizingTerms> sizing_terms(const SheetMesh& mesh, const RemeshState& state,
                                      const RemeshParams& p) {
  check_params(p);
  check_state(mesh, state);
  const std::vector<double> angles = edge_dihedral_angles(mesh, state.positions);
  const Eigen::MatrixX3i faces = mesh.faces();
  const Eigen::MatrixX3d plastic = mesh.plastic_curvature();
  const bool use_obstacles = p.obstacle_distance > 0 && state.obstacle_distance.size() > 0;
  std::vector<SizingTerms> out(faces.rows());
  for (int f = 0; f < faces.rows(); ++f) {
    FaceInputs in;
    for (int k = 0; k < 3; ++k) {
      const int v = faces(f, k);
      in.material.col(k) = mesh.material_coord(v);
      in.world.col(k) = state.positions.row(v).transpose();
      in.velocity.col(k) = state.velocities.row(v).transpose();
      if (use_obstacles) in.distance(k) = state.obstacle_distance(v);
    }
    if (state.membrane_strain.rows() > 0) {
      const Eigen::RowVector3d e = state.membrane_strain.row(f);
      in.strain = (Eigen::Matrix2d() << e[0], e[2], e[2], e[1]).finished();
    }
    Eigen::Matrix2d kp;
    kp << plastic(f, 0), plastic(f, 2), plastic(f, 2), plastic(f, 1);
    out[f] = face_terms(in, face_curvature(mesh, f, angles), kp, p, use_obstacles);
  }
  return out;
}

std::vector<Eigen::Matrix2d> sizing(const SheetMesh& mesh, const RemeshState& state,
                                    const RemeshParams& p) {
  const std::vector<SizingTerms> terms = sizing_terms(mesh, state, p);
  std::vector<Eigen::Matrix2d> out(terms.size());
  for (size_t f = 0; f < terms.size(); ++f) {
    const SizingTerms& t = terms[f];
    out[f] = clamp_metric(
        tensor_max({t.curvature, t.plastic, t.compression, t.velocity, t.obstacle}), p);
  }
  return out;
}

}  // namespace papersim::remesh
