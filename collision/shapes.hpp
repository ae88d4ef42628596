#pragma once
/// Exact signed distance functions of the analytic obstacle primitives, and a collider that
/// evaluates them directly (no grid).
///
/// Local frames (place the shape in the world with the collider's keyframes):
/// - sphere:   centred at the origin.
/// - inverted sphere: a spherical cavity centred at the origin: the solid is everything outside
///             the sphere, the free space inside it (phi = r - |p|, gradient towards the
///             centre). Not convex; its bounding box is the sphere's, though the solid is
///             unbounded (what lies outside the box is inside the solid).
/// - cylinder: axis along local x, centred at the origin, flat caps at x = +-length/2.
/// - capsule:  axis along local x, centred at the origin, tip to tip `length` (>= 2 radius).
/// - box:      centred at the origin, faces at +-half_extents.
/// - gable:    triangular prism along local x (x in [-length/2, length/2]) whose cross-section
///             has its base on z = 0 from y = -half_width to half_width and its ridge at
///             (y, z) = (0, height); ridge angle 2 atan(half_width / height). Closed (base
///             face included).
#include <Eigen/Core>
#include <array>
#include <vector>

#include "collision/collider.hpp"

namespace papersim::collision {

/// Which analytic primitive a Shape describes.
enum class ShapeKind { sphere, cylinder, capsule, box, gable, inverted_sphere };

/// An analytic primitive with its dimensions [m]; only the fields of its kind are read.
struct Shape {
  ShapeKind kind = ShapeKind::sphere;
  double radius = 0.05;  ///< sphere, inverted sphere, cylinder, capsule [m]
  double length = 0.1;   ///< cylinder, capsule (tip to tip), gable: extent along x [m]
  Eigen::Vector3d half_extents = Eigen::Vector3d::Constant(0.05);  ///< box [m]
  double half_width = 0.05;  ///< gable: half the base width (along y) [m]
  double height = 0.05;      ///< gable: ridge height above the base (along z) [m]
};

/// Checks every dimension the kind reads is finite and positive (and capsule length >=
/// 2 radius). @throw ColliderError naming the field and its value.
void validate(const Shape& shape);

/// Exact signed distance [m] from local point p [m] to the shape's surface (< 0 inside);
/// writes the unit outward gradient when `gradient` is not null (on the medial axis, where
/// the gradient is not defined, one of the valid directions).
double shape_distance(const Shape& shape, const Eigen::Vector3d& p, Eigen::Vector3d* gradient);

/// Local bounding box of the shape's surface [m].
Aabb shape_bounds(const Shape& shape);

/// Smallest feature size used to choose a grid resolution [m]: sphere, inverted sphere, cylinder
/// and capsule radius, box smallest half extent, gable min(half_width, height), never above
/// length/2.
double shape_smallest_feature(const Shape& shape);

/// Surface area [m^2] (to estimate a level set's voxel count before building it).
double shape_surface_area(const Shape& shape);

/// Corners and edges of a polyhedral primitive in its local frame [m].
struct PolytopeFeatures {
  std::vector<Eigen::Vector3d> corners;
  std::vector<std::array<int, 2>> edges;  ///< indices into corners
};

/// The corners and edges of a box (8 and 12) or a gable prism (6 and 9); empty for curved
/// primitives (sphere, cylinder, capsule). Sheet contact uses them so that an edge of the
/// obstacle cannot slip between the sheet's vertices.
PolytopeFeatures polytope_features(const Shape& shape);

/// A collider that evaluates the exact signed distance of a primitive: no grid, exact
/// distances and gradients, cheaper than a level set. Thread-safe (no mutable state).
class AnalyticCollider : public Collider {
 public:
  /// @throw ColliderError when a dimension is invalid (see validate).
  explicit AnalyticCollider(const Shape& shape);
  const Shape& shape() const { return m_shape; }
  const Shape* analytic_shape() const override { return &m_shape; }
  /// Every primitive but the inverted sphere (sphere, cylinder, capsule, box, gable prism) is
  /// convex.
  bool is_convex() const override { return m_shape.kind != ShapeKind::inverted_sphere; }
  /// Exact for the inverted sphere (see the .cpp); sphere tracing otherwise.
  double segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t, double limit,
                      double keep) const override;
  /// The inverted sphere's Hessian -(I - q q^T / |q|^2) / |q|, q = p - centre (negative
  /// semi-definite); false for the other primitives.
  bool distance_hessian(const Eigen::Vector3d& p, double t,
                        Eigen::Matrix3d& hessian) const override;
  /// Translation, plus any rotation of a sphere or inverted sphere, spin of a cylinder or
  /// capsule about its axis, and a uniform scale of the inverted sphere.
  bool moves_affinely(double t0, double t1) const override;
  /// Exact for these motions: the point's path in the obstacle's (non-spinning) frame is a
  /// segment, along which a convex field is convex (it stays above its tangent at the start)
  /// and the inverted sphere's field, with its radius linear in time, is concave (the bound is
  /// the root of a quadratic).
  double moving_segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                             double dt, double limit, double keep) const override;

 protected:
  double local_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const override;
  Aabb local_bounds() const override;

 private:
  /// moving_segment_step within one keyframe segment: the largest a in [0, length] keeping
  /// phi >= stop [m] from time t; t_inside is a time inside the segment (its velocities).
  double piece_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t, double dt,
                    double length, double stop, double t_inside) const;

  Shape m_shape;
};

}  // namespace papersim::collision
