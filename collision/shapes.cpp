#include "collision/shapes.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "collision/errors.hpp"
#include "common/format.hpp"

namespace papersim::collision {

namespace {

double sign_of(double x) { return x < 0.0 ? -1.0 : 1.0; }

void require_positive(const char* field, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    std::ostringstream os;
    os << "collider shape: " << field << " must be finite and > 0, got " << value;
    throw ColliderError(os.str());
  }
}

/// Signed distance of the 2D disc of radius r at q; gradient in (y, z).
double disc_2d(const Eigen::Vector2d& q, double r, Eigen::Vector2d& g) {
  const double n = q.norm();
  g = n > 0.0 ? Eigen::Vector2d(q / n) : Eigen::Vector2d(0.0, 1.0);
  return n - r;
}

/// Exact signed distance of the 2D gable triangle (base y in [-w, w] at z = 0, apex (0, h)).
/// Outside: distance to the closest point of the three edges, gradient towards q. Inside
/// (convex): the distance to the nearest edge line, gradient its outward normal.
double gable_2d(const Eigen::Vector2d& q, double w, double h, Eigen::Vector2d& g) {
  const Eigen::Vector2d v[3] = {{-w, 0.0}, {w, 0.0}, {0.0, h}};
  double best = 1e300, inside_dist = -1e300;
  Eigen::Vector2d best_point = q, inside_normal(0.0, -1.0);
  bool inside = true;
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector2d a = v[e], b = v[(e + 1) % 3];
    const Eigen::Vector2d ab = b - a;
    const Eigen::Vector2d n = Eigen::Vector2d(ab.y(), -ab.x()).normalized();  // outward (CCW)
    const double s = n.dot(q - a);
    if (s > 0.0) inside = false;
    if (s > inside_dist) inside_dist = s, inside_normal = n;
    const double t = std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    const Eigen::Vector2d c = a + t * ab;
    const double dist = (q - c).norm();
    if (dist < best) best = dist, best_point = c;
  }
  if (inside) {
    g = inside_normal;
    return inside_dist;
  }
  g = best > 0.0 ? Eigen::Vector2d((q - best_point) / best) : inside_normal;
  return best;
}

/// Extrudes a 2D signed distance (d2, gradient g2 in (y, z)) along x over [-half, half]:
/// exact for prisms (distance to the union of side walls and caps).
double extrude(double d2, const Eigen::Vector2d& g2, double x, double half, Eigen::Vector3d* g) {
  const double wx = d2, wy = std::abs(x) - half;
  if (wx > 0.0 && wy > 0.0) {
    const double d = std::hypot(wx, wy);
    if (g) *g = Eigen::Vector3d(sign_of(x) * wy, wx * g2.x(), wx * g2.y()) / d;
    return d;
  }
  if (wx >= wy) {
    if (g) *g = Eigen::Vector3d(0.0, g2.x(), g2.y());
    return wx;
  }
  if (g) *g = Eigen::Vector3d(sign_of(x), 0.0, 0.0);
  return wy;
}

double sphere_distance(double r, const Eigen::Vector3d& p, Eigen::Vector3d* g) {
  const double n = p.norm();
  if (g) *g = n > 0.0 ? Eigen::Vector3d(p / n) : Eigen::Vector3d::UnitZ();
  return n - r;
}

/// r - |p|: the cavity's free space inside, the solid outside; gradient towards the centre.
double inverted_sphere_distance(double r, const Eigen::Vector3d& p, Eigen::Vector3d* g) {
  const double n = p.norm();
  if (g) *g = n > 0.0 ? Eigen::Vector3d(-p / n) : Eigen::Vector3d::UnitZ();
  return r - n;
}

double cylinder_distance(const Shape& s, const Eigen::Vector3d& p, Eigen::Vector3d* g) {
  Eigen::Vector2d g2;
  const double d2 = disc_2d(p.tail<2>(), s.radius, g2);
  return extrude(d2, g2, p.x(), 0.5 * s.length, g);
}

double capsule_distance(const Shape& s, const Eigen::Vector3d& p, Eigen::Vector3d* g) {
  const double half_segment = 0.5 * s.length - s.radius;
  const Eigen::Vector3d axis_point(std::clamp(p.x(), -half_segment, half_segment), 0.0, 0.0);
  const Eigen::Vector3d q = p - axis_point;
  const double n = q.norm();
  if (g) *g = n > 0.0 ? Eigen::Vector3d(q / n) : Eigen::Vector3d::UnitZ();
  return n - s.radius;
}

double box_distance(const Eigen::Vector3d& b, const Eigen::Vector3d& p, Eigen::Vector3d* g) {
  const Eigen::Vector3d q = p.cwiseAbs() - b;
  Eigen::Index i;
  const double qmax = q.maxCoeff(&i);
  if (qmax <= 0.0) {
    if (g) *g = sign_of(p[i]) * Eigen::Vector3d::Unit(i);
    return qmax;
  }
  const Eigen::Vector3d v = q.cwiseMax(0.0);
  const double d = v.norm();
  if (g)
    *g =
        Eigen::Vector3d(sign_of(p.x()) * v.x(), sign_of(p.y()) * v.y(), sign_of(p.z()) * v.z()) / d;
  return d;
}

double gable_distance(const Shape& s, const Eigen::Vector3d& p, Eigen::Vector3d* g) {
  Eigen::Vector2d g2;
  const double d2 = gable_2d(p.tail<2>(), s.half_width, s.height, g2);
  return extrude(d2, g2, p.x(), 0.5 * s.length, g);
}

}  // namespace

void validate(const Shape& s) {
  switch (s.kind) {
    case ShapeKind::sphere:
    case ShapeKind::inverted_sphere:
      require_positive("radius", s.radius);
      return;
    case ShapeKind::cylinder:
      require_positive("radius", s.radius);
      require_positive("length", s.length);
      return;
    case ShapeKind::capsule:
      require_positive("radius", s.radius);
      require_positive("length", s.length);
      if (s.length < 2.0 * s.radius)
        throw ColliderError("collider shape: capsule length (tip to tip) " +
                            common::format_number(s.length) +
                            " must be >= 2 radius = " + common::format_number(2.0 * s.radius));
      return;
    case ShapeKind::box:
      require_positive("half_extents.x", s.half_extents.x());
      require_positive("half_extents.y", s.half_extents.y());
      require_positive("half_extents.z", s.half_extents.z());
      return;
    case ShapeKind::gable:
      require_positive("half_width", s.half_width);
      require_positive("height", s.height);
      require_positive("length", s.length);
      return;
  }
  throw ColliderError("collider shape: unknown kind " + std::to_string(static_cast<int>(s.kind)));
}

double shape_distance(const Shape& s, const Eigen::Vector3d& p, Eigen::Vector3d* g) {
  switch (s.kind) {
    case ShapeKind::sphere:
      return sphere_distance(s.radius, p, g);
    case ShapeKind::inverted_sphere:
      return inverted_sphere_distance(s.radius, p, g);
    case ShapeKind::cylinder:
      return cylinder_distance(s, p, g);
    case ShapeKind::capsule:
      return capsule_distance(s, p, g);
    case ShapeKind::box:
      return box_distance(s.half_extents, p, g);
    case ShapeKind::gable:
      return gable_distance(s, p, g);
  }
  return 0.0;
}

Aabb shape_bounds(const Shape& s) {
  Aabb b;
  switch (s.kind) {
    case ShapeKind::sphere:
    case ShapeKind::inverted_sphere:
      b.hi = Eigen::Vector3d::Constant(s.radius);
      break;
    case ShapeKind::cylinder:
    case ShapeKind::capsule:
      b.hi = Eigen::Vector3d(0.5 * s.length, s.radius, s.radius);
      break;
    case ShapeKind::box:
      b.hi = s.half_extents;
      break;
    case ShapeKind::gable:
      b.lo = Eigen::Vector3d(-0.5 * s.length, -s.half_width, 0.0);
      b.hi = Eigen::Vector3d(0.5 * s.length, s.half_width, s.height);
      return b;
  }
  b.lo = -b.hi;
  return b;
}

double shape_smallest_feature(const Shape& s) {
  switch (s.kind) {
    case ShapeKind::sphere:
    case ShapeKind::inverted_sphere:
      return s.radius;
    case ShapeKind::cylinder:
      return std::min(s.radius, 0.5 * s.length);
    case ShapeKind::capsule:
      return s.radius;
    case ShapeKind::box:
      return s.half_extents.minCoeff();
    case ShapeKind::gable:
      return std::min({s.half_width, s.height, 0.5 * s.length});
  }
  return 0.0;
}

double shape_surface_area(const Shape& s) {
  const double r = s.radius, l = s.length;
  const Eigen::Vector3d& e = s.half_extents;
  switch (s.kind) {
    case ShapeKind::sphere:
    case ShapeKind::inverted_sphere:
      return 4.0 * M_PI * r * r;
    case ShapeKind::cylinder:
      return 2.0 * M_PI * r * (r + l);
    case ShapeKind::capsule:
      return 4.0 * M_PI * r * r + 2.0 * M_PI * r * (l - 2.0 * r);
    case ShapeKind::box:
      return 8.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
    case ShapeKind::gable: {
      const double slant = std::hypot(s.half_width, s.height);
      return (2.0 * s.half_width + 2.0 * slant) * l + 2.0 * s.half_width * s.height;
    }
  }
  return 0.0;
}

AnalyticCollider::AnalyticCollider(const Shape& shape) : m_shape(shape) { validate(m_shape); }

double AnalyticCollider::local_distance(const Eigen::Vector3d& p, Eigen::Vector3d* g) const {
  return shape_distance(m_shape, p, g);
}

Aabb AnalyticCollider::local_bounds() const { return shape_bounds(m_shape); }

bool AnalyticCollider::distance_hessian(const Eigen::Vector3d& p, double t,
                                        Eigen::Matrix3d& hessian) const {
  if (m_shape.kind != ShapeKind::inverted_sphere) return false;
  const Eigen::Vector3d q = p - motion.pose(t).translation();
  const double n = q.norm();
  if (!(n > 0)) return false;
  const Eigen::Vector3d u = q / n;
  hessian = -(Eigen::Matrix3d::Identity() - u * u.transpose()) / n;
  return true;
}

// Inverted sphere (centre c, radius R at time t): phi(p + a d) >= keep phi(p) exactly when
// |q + a d| <= R' = R - keep phi(p), q = p - c. |q + a d|^2 is a convex quadratic in a that is
// <= R'^2 at a = 0, so the set is an interval [a_-, a_+] holding 0: a_+ is the exact answer.
double AnalyticCollider::segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                                      double limit, double keep) const {
  if (m_shape.kind != ShapeKind::inverted_sphere)
    return Collider::segment_step(p, d, t, limit, keep);
  const double dd = d.squaredNorm();
  if (dd == 0) return limit;
  const Eigen::Affine3d pose = motion.pose(t);
  const double radius = m_shape.radius * pose.linear().col(0).norm();
  const Eigen::Vector3d q = p - pose.translation();
  const double gap = radius - q.norm();
  if (!(gap > 0)) return 0.0;
  const double inner = radius - keep * gap;
  const double qd = q.dot(d);
  const double c = q.squaredNorm() - inner * inner;  // < 0: q is inside the inner sphere
  // Larger root of dd a^2 + 2 qd a + c = 0, written to avoid cancellation.
  const double disc = std::sqrt(std::max(0.0, qd * qd - dd * c));
  const double root = qd <= 0 ? (-qd + disc) / dd : -c / (qd + disc);
  return std::clamp(root, 0.0, limit);
}

bool AnalyticCollider::moves_affinely(double t0, double t1) const {
  const bool any_rotation =
      m_shape.kind == ShapeKind::sphere || m_shape.kind == ShapeKind::inverted_sphere;
  const bool spin = m_shape.kind == ShapeKind::cylinder || m_shape.kind == ShapeKind::capsule;
  for (double t = t0; t < t1; t = motion.next_keyframe_time(t)) {
    if (motion.scale_rate(t) != 0 && m_shape.kind != ShapeKind::inverted_sphere) return false;
    const Eigen::Vector3d omega = motion.angular_velocity(t);
    if (any_rotation || omega.squaredNorm() == 0) continue;
    if (!spin) return false;
    // A spin about the axis keeps the axis where it is: omega along it.
    const Eigen::Vector3d axis = motion.pose(t).linear().col(0).normalized();
    if ((omega - omega.dot(axis) * axis).norm() > 1e-9 * omega.norm()) return false;
  }
  return true;
}

// The motion is taken piece by piece between keyframes, within which translation and scale are
// linear in time.
double AnalyticCollider::moving_segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d,
                                             double t, double dt, double limit, double keep) const {
  if (dt == 0) return segment_step(p, d, t, limit, keep);
  if (dt < 0 || !moves_affinely(t, t + limit * dt)) return -1.0;
  return step_over_pieces(
      p, d, t, dt, limit, keep,
      [&](const Eigen::Vector3d& q, double tq, double length, double stop, double t_inside) {
        return piece_step(q, d, tq, dt, length, stop, t_inside);
      });
}

double AnalyticCollider::piece_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                                    double dt, double length, double stop, double t_inside) const {
  if (m_shape.kind != ShapeKind::inverted_sphere)
    return convex_piece_step(p, d, t, dt, length, stop, t_inside);
  // phi(a) = s(a) R - |q + a r| with s linear in a: concave, so f(a) = |q + a r| - (s(a) R -
  // stop) is convex, negative at 0, and the admissible steps are [0, root].
  const Eigen::Affine3d pose = motion.pose(t);
  if (!(distance_at_pose(p, pose) > stop)) return 0.0;
  const Eigen::Vector3d r = d - dt * motion.linear_velocity(t_inside);
  const double s0 = pose.linear().col(0).norm(), rate_s = motion.scale_rate(t_inside) * dt;
  const Eigen::Vector3d q = p - pose.translation();
  const auto f = [&](double a) {
    return (q + a * r).norm() - ((s0 + a * rate_s) * m_shape.radius - stop);
  };
  if (f(length) < 0) return length;
  double lo = 0, hi = length;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < 0 ? lo : hi) = mid;
  }
  return lo;
}

PolytopeFeatures polytope_features(const Shape& s) {
  PolytopeFeatures f;
  if (s.kind == ShapeKind::box) {
    const Eigen::Vector3d& e = s.half_extents;
    for (int i = 0; i < 8; ++i)  // bit k of i: sign of axis k
      f.corners.emplace_back((i & 1 ? 1 : -1) * e.x(), (i & 2 ? 1 : -1) * e.y(),
                             (i & 4 ? 1 : -1) * e.z());
    for (int i = 0; i < 8; ++i)
      for (int k = 0; k < 3; ++k)
        if (!(i & (1 << k))) f.edges.push_back({{i, i | (1 << k)}});
  } else if (s.kind == ShapeKind::gable) {
    for (const double x : {-0.5 * s.length, 0.5 * s.length}) {  // base corners and ridge end
      f.corners.emplace_back(x, -s.half_width, 0.0);
      f.corners.emplace_back(x, s.half_width, 0.0);
      f.corners.emplace_back(x, 0.0, s.height);
    }
    for (int k = 0; k < 3; ++k) {
      f.edges.push_back({{k, k + 3}});                // along the prism
      f.edges.push_back({{k, (k + 1) % 3}});          // end triangle at -length/2
      f.edges.push_back({{k + 3, (k + 1) % 3 + 3}});  // end triangle at +length/2
    }
  }
  return f;
}

}  // namespace papersim::collision
