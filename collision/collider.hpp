#pragma once
/// Obstacles as signed distance fields with a possibly keyframed placement: a rotation, a
/// translation and a uniform scale of the shape about its local origin.
///
/// phi(p) < 0 inside the obstacle, > 0 outside, |grad phi| = 1 near the surface. Because the
/// field is 1-Lipschitz, a point at distance d cannot reach the surface by moving less than d:
/// the solver uses that as conservative continuous collision detection. Scaling keeps that
/// property: the field of the scaled shape is s phi_local(X / s), again 1-Lipschitz.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <memory>
#include <vector>

namespace papersim::collision {

struct Shape;

/// Axis-aligned box in world space [m].
struct Aabb {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300);
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-1e300);
  void extend(const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  /// Distance between two boxes (0 when they overlap) [m]; +inf when either is empty.
  double distance_to(const Aabb& other) const;
  /// Distance from point p to the box (0 inside) [m].
  double distance_to(const Eigen::Vector3d& p) const;
  /// True when the box holds no point (lo > hi in some axis).
  bool is_empty() const { return (lo.array() > hi.array()).any(); }
  /// Grow by r [m] in every direction.
  void inflate(double r) {
    lo.array() -= r;
    hi.array() += r;
  }
  /// Grow to hold box b.
  void extend(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
};

/// A placement at a time: world point = rotation * (scale * local point) + translation.
struct Keyframe {
  double time = 0.0;                                      ///< [s]
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  ///< [m]
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  double scale = 1.0;  ///< uniform scale of the shape about its local origin, finite and > 0 [-]
};

/// Piecewise-linear motion: translation and scale interpolated linearly, rotation by slerp;
/// held constant before the first and after the last keyframe. One keyframe = a fixed pose.
/// (The name predates the scale: with every scale 1 the motion is rigid.)
class RigidMotion {
 public:
  RigidMotion() = default;
  /// @throw std::invalid_argument when keyframe times are not increasing or a scale is not
  ///        finite and > 0.
  explicit RigidMotion(std::vector<Keyframe> keyframes);
  /// Placement at time t [s]: linear part rotation * scale, translation [m]; identity when
  /// there is no keyframe.
  Eigen::Affine3d pose(double t) const;
  /// Uniform scale at time t [-] (1 when there is no keyframe).
  double scale(double t) const;
  /// d scale / dt at time t [1/s] (0 outside the keyframe range; at a keyframe time the
  /// segment that starts there is used).
  double scale_rate(double t) const;
  const std::vector<Keyframe>& keyframes() const { return m_keyframes; }
  /// Velocity of the local origin at time t [m/s] (0 outside the keyframe range; at a keyframe
  /// time the segment that starts there is used).
  Eigen::Vector3d linear_velocity(double t) const;
  /// World angular velocity at time t [rad/s] (constant over a slerp segment).
  Eigen::Vector3d angular_velocity(double t) const;
  /// True when the placement does not change with time (at most one keyframe, or all equal).
  bool is_static() const;
  /// Time of the first keyframe after t [s] (+infinity when there is none): translation and
  /// scale move linearly, and rotation turns at a constant rate, between t and that time.
  double next_keyframe_time(double t) const;
  /// True when the placement changes at some time in [t0, t1) [s].
  bool moves_during(double t0, double t1) const;
  /// The placement at time t [s] as a keyframe (translation and scale linear, rotation by slerp
  /// between the keyframes around t).
  Keyframe keyframe_at(double t) const;
  /// Changes the motion from t0 on: before t0 [s] nothing changes, from t1 > t0 on the placement
  /// is translated by `delta` [m] more than before, and in between the extra translation grows
  /// linearly. Keyframes are inserted at t0 and t1 where none lies within 1e-9 s, with the
  /// translation this motion has there and the rotation and scale `turning` has there: with
  /// `turning` the motion before any translate_from, every keyframe's rotation and scale follow
  /// from its time alone (a motion rebuilt from saved times and translations is the same to the
  /// bit), and the placement between keyframes is the same as before to rounding.
  /// @throw std::invalid_argument when t1 <= t0
  void translate_from(double t0, double t1, const Eigen::Vector3d& delta,
                      const RigidMotion& turning);
  /// Sets the translation of the keyframe at time t [s] (inserted as translate_from does where
  /// none lies within 1e-9 s): a motion saved as keyframe times and translations is rebuilt by
  /// calling this for each on a copy of `turning`.
  void set_translation_at(double t, const Eigen::Vector3d& translation, const RigidMotion& turning);

 private:
  /// Index i of the segment [t_i, t_i+1) holding t, or -1 outside the keyframe range.
  int segment(double t) const;
  /// Index of the keyframe within 1e-9 s of t, inserted (translate_from) when there is none.
  size_t keyframe_index(double t, const RigidMotion& turning);

 private:
  std::vector<Keyframe> m_keyframes;
};

/// An obstacle: a signed distance field in its local frame, a motion and a friction coefficient.
class Collider {
 public:
  virtual ~Collider() = default;

  /// Signed distance [m] of world point p at time t [s]; writes the unit outward gradient when
  /// `gradient` is not null. Thread-safe.
  double distance(const Eigen::Vector3d& p, double t, Eigen::Vector3d* gradient = nullptr) const;

  /// Same as distance(p, t, gradient) with the placement already evaluated (pose =
  /// motion.pose(t), linear part rotation * scale): saves the keyframe search and slerp when
  /// many points are queried at one time. The field is s phi_local(X / s), X the point in the
  /// rotated frame. Thread-safe.
  double distance_at_pose(const Eigen::Vector3d& p, const Eigen::Affine3d& pose,
                          Eigen::Vector3d* gradient = nullptr) const;

  /// World bounding box of the obstacle's surface at time t.
  Aabb bounds(double t) const;

  /// A world box holding the obstacle's surface at every time in [t0, t1] [s] (conservative:
  /// rotating segments are sampled and padded by the chord-to-arc deviation at the largest
  /// scale; translation and scale are linear between keyframes, so boxes at the samples and
  /// keyframe times hold them exactly).
  Aabb swept_bounds(double t0, double t1) const;

  /// Bounding box of the surface in the collider's own frame [m].
  Aabb bounds_local() const { return local_bounds(); }

  /// Velocity of the obstacle's material point that is at world point p at time t [m/s]:
  /// c' + omega x (p - c) + (s' / s) (p - c), c the origin of the local frame in the world and
  /// s the scale (a growing or shrinking surface moves along its radius from c).
  Eigen::Vector3d velocity(const Eigen::Vector3d& p, double t) const;

  /// True when the obstacle is a convex solid with an exact field. Then the field is a convex
  /// function and the tangent plane at any surface point bounds the solid (it lies behind the
  /// plane): continuous collision detection can use that plane instead of sphere tracing.
  virtual bool is_convex() const { return false; }

  /// What the contact models need to know of the obstacle's kind, so that they never ask for
  /// its type: the analytic primitive it is (AnalyticCollider: a sphere's radius, a polytope's
  /// corners and edges), null for any other obstacle.
  virtual const Shape* analytic_shape() const { return nullptr; }
  /// True for a plane, whose contact with a sheet face is that of the face's vertices.
  virtual bool is_plane() const { return false; }

  /// Continuous collision detection of a point moving on the segment p -> p + a d at time t:
  /// a step a in [0, limit] such that every point p + b d, b in [0, a], keeps
  /// phi >= keep phi(p) (keep in [0, 1), e.g. 0.1: the point closes at most 90% of its gap).
  /// Conservative (may return less than the largest such a); 0 when phi(p) <= 0. The default
  /// is sphere tracing on the 1-Lipschitz field. Thread-safe.
  virtual double segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                              double limit, double keep) const;

  /// Hessian of the field at world point p at time t [1/m], written to `hessian`; false (and
  /// nothing written) when the collider does not provide it. Contact adds its curvature term
  /// where provided (the inverted sphere: there the term is positive semi-definite and keeps
  /// Newton from sliding a vertex straight through the curved wall).
  virtual bool distance_hessian(const Eigen::Vector3d& p, double t, Eigen::Matrix3d& hessian) const;

  /// True when over [t0, t1] the field moves so that a point on a straight line stays on a
  /// straight line in the obstacle's frame: translation (and, for a shape that allows it, a
  /// uniform scale), rotations that leave the field unchanged aside (a sphere's, a cylinder's or
  /// capsule's spin about its axis). moving_segment_step then bounds the joint motion exactly.
  /// Default: only an obstacle that does not move over [t0, t1].
  virtual bool moves_affinely(double t0, double t1) const;

  /// Continuous collision detection of a point moving on p -> p + a d while the obstacle moves
  /// from time t to t + a dt, a in [0, limit]: a step a such that every point passed keeps
  /// phi >= keep phi(p, t). Needs moves_affinely(t, t + limit dt) and dt >= 0; returns a
  /// negative value when the collider cannot bound the motion. The default handles an obstacle
  /// that does not move over the interval (segment_step).
  virtual double moving_segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                                     double dt, double limit, double keep) const;

  double friction = 0.3;  ///< Coulomb coefficient sheet-obstacle [-]
  RigidMotion motion;     ///< world pose over time

 protected:
  /// moving_segment_step's walk over the keyframe pieces of [t, t + limit dt], within each of
  /// which translation and scale are linear in time: `piece(q, tq, length, stop, t_inside)` is
  /// the largest step in [0, length] of the point q = p + a d, moving from time tq = t + a dt,
  /// that keeps phi >= stop [m] (stop = keep phi(p, t)); t_inside is a time inside the piece.
  template <class Piece>
  double step_over_pieces(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t, double dt,
                          double limit, double keep, Piece&& piece) const {
    const double phi0 = distance(p, t);
    if (!(phi0 > 0)) return 0.0;
    const double stop = keep * phi0;
    double a = 0;
    for (double tk = motion.next_keyframe_time(t); a < limit; tk = motion.next_keyframe_time(tk)) {
      const double end = std::min(limit, (tk - t) / dt);
      if (end <= a) continue;
      const double b = piece(p + a * d, t + a * dt, end - a, stop, t + 0.5 * (a + end) * dt);
      if (b < end - a) return a + b;
      a = end;
    }
    return limit;
  }

  /// One piece of step_over_pieces for a convex field whose frame translates within the piece
  /// (it may also turn or scale in ways that leave the field unchanged): the field is convex
  /// along the point's path relative to the frame, so it stays above its tangent at the start,
  /// phi(a) >= phi + a n.r, r = d - dt c'(t_inside); exact for a plane.
  double convex_piece_step(const Eigen::Vector3d& q, const Eigen::Vector3d& d, double tq, double dt,
                           double length, double stop, double t_inside) const;

  /// Signed distance in the local frame; gradient (unit, local frame) when not null.
  virtual double local_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const = 0;
  /// Local bounding box of the surface.
  virtual Aabb local_bounds() const = 0;
};

/// The plane z = 0 of the local frame (normal +z, solid below). Analytic: no grid.
class PlaneCollider : public Collider {
 public:
  bool is_convex() const override { return true; }
  bool is_plane() const override { return true; }
  /// Translation, and any turn about the plane's normal (which leaves the field unchanged).
  bool moves_affinely(double t0, double t1) const override;
  /// Exact for these motions: the distance is linear along the joint motion within a keyframe
  /// piece (a pressing plate, a moving floor).
  double moving_segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                             double dt, double limit, double keep) const override;

 protected:
  double local_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const override;
  Aabb local_bounds() const override;

 public:
  double half_size = 1e3;  ///< half extent in x and y of the bounding box [m]
};

}  // namespace papersim::collision
