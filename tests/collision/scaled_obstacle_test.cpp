// Obstacles whose size follows keyframes (uniform scale about the local origin) and the
// inverted sphere (a spherical cavity): fields, gradients, surface velocity, bounds and CCD.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "collision/collider_factory.hpp"
#include "collision/errors.hpp"
#include "collision/shapes.hpp"

namespace pc = papersim::collision;

namespace {

pc::Keyframe keyframe(double t, const Eigen::Vector3d& x, double angle_z, double scale) {
  pc::Keyframe k;
  k.time = t;
  k.translation = x;
  k.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(angle_z, Eigen::Vector3d::UnitZ()));
  k.scale = scale;
  return k;
}

/// A box turning, moving and shrinking to 40% over [0, 2] s, then growing back by 2.5x.
std::unique_ptr<pc::Collider> morphing_box() {
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::box;
  spec.half_extents = Eigen::Vector3d(0.05, 0.03, 0.02);
  spec.keyframes = {keyframe(0.0, {0, 0, 0}, 0.0, 1.0), keyframe(2.0, {0.1, -0.05, 0.02}, 0.8, 0.4),
                    keyframe(3.0, {0.1, -0.05, 0.02}, 0.8, 1.0)};
  return pc::make_collider(spec);
}

pc::ColliderSpec sphere_spec(pc::ColliderKind kind, double radius, std::vector<pc::Keyframe> keys) {
  pc::ColliderSpec spec;
  spec.kind = kind;
  spec.radius = radius;
  spec.keyframes = std::move(keys);
  return spec;
}

}  // namespace

TEST(ScaledMotion, ScaleIsLinearBetweenKeyframesAndHeldOutside) {
  const pc::RigidMotion m({keyframe(1.0, {0, 0, 0}, 0, 2.0), keyframe(3.0, {0, 0, 0}, 0, 0.5)});
  EXPECT_DOUBLE_EQ(m.scale(0.0), 2.0);
  EXPECT_DOUBLE_EQ(m.scale(2.0), 1.25);
  EXPECT_DOUBLE_EQ(m.scale(5.0), 0.5);
  EXPECT_DOUBLE_EQ(m.scale_rate(2.0), -0.75);
  EXPECT_DOUBLE_EQ(m.scale_rate(0.5), 0.0);
  EXPECT_DOUBLE_EQ(m.scale_rate(3.5), 0.0);
  EXPECT_FALSE(m.is_static());
  // The placement's linear part is rotation * scale.
  EXPECT_NEAR(m.pose(2.0).linear().col(1).norm(), 1.25, 1e-15);
}

TEST(ScaledMotion, RejectsScalesThatAreNotPositiveAndFinite) {
  for (double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(pc::RigidMotion({keyframe(0, {0, 0, 0}, 0, 1.0), keyframe(1, {0, 0, 0}, 0, bad)}),
                 std::invalid_argument);
    pc::ColliderSpec spec =
        sphere_spec(pc::ColliderKind::sphere, 0.1, {keyframe(0, {0, 0, 0}, 0, bad)});
    try {
      pc::make_collider(spec);
      ADD_FAILURE() << "no error";
    } catch (const pc::ColliderError& e) {
      EXPECT_NE(std::string(e.what()).find("scale"), std::string::npos) << e.what();
    }
  }
}

// The field of a uniformly scaled shape is the shape's field with scaled dimensions: compared
// with the exact field of a box whose half extents are scaled (and rotated, moved).
TEST(ScaledCollider, FieldIsTheFieldOfTheScaledShape) {
  const auto box = morphing_box();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.1, 0.1), tu(0.0, 3.5);
  for (int i = 0; i < 200; ++i) {
    const double t = tu(rng);
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const double s = box->motion.scale(t);
    pc::Shape scaled;
    scaled.kind = pc::ShapeKind::box;
    scaled.half_extents = s * Eigen::Vector3d(0.05, 0.03, 0.02);
    const Eigen::Affine3d pose = box->motion.pose(t);
    const Eigen::Matrix3d R = pose.linear() / s;
    const Eigen::Vector3d local = R.transpose() * (p - pose.translation());
    Eigen::Vector3d g_ref, g;
    const double ref = pc::shape_distance(scaled, local, &g_ref);
    EXPECT_NEAR(box->distance(p, t, &g), ref, 1e-14);
    EXPECT_NEAR((g - R * g_ref).norm(), 0.0, 1e-12);
  }
}

// Gradient against central differences in space (away from the box's medial axis and edges,
// where the field is smooth), and unit length (the scaled field stays 1-Lipschitz).
TEST(ScaledCollider, GradientMatchesFiniteDifferencesInSpace) {
  const auto box = morphing_box();
  pc::ColliderSpec sphere_s =
      sphere_spec(pc::ColliderKind::sphere, 0.05,
                  {keyframe(0, {0, 0, 0}, 0, 1.0), keyframe(1, {0.01, 0, 0}, 0.3, 0.3)});
  pc::ColliderSpec cavity_s =
      sphere_spec(pc::ColliderKind::inverted_sphere, 0.2,
                  {keyframe(0, {0, 0, 0}, 0, 1.0), keyframe(1, {0, 0.02, 0}, 0, 0.25)});
  const auto sphere = pc::make_collider(sphere_s), cavity = pc::make_collider(cavity_s);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.12, 0.12), tu(0.0, 1.2);
  const double h = 1e-7;
  int checked = 0;
  for (const pc::Collider* c : {box.get(), sphere.get(), cavity.get()}) {
    for (int i = 0; i < 200; ++i) {
      const double t = tu(rng);
      const Eigen::Vector3d p(u(rng), u(rng), u(rng));
      Eigen::Vector3d g;
      c->distance(p, t, &g);
      Eigen::Vector3d fd;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e = Eigen::Vector3d::Unit(k) * h;
        fd[k] = (c->distance(p + e, t) - c->distance(p - e, t)) / (2 * h);
      }
      if (std::abs(fd.norm() - 1.0) > 1e-4) continue;  // a kink of the box field within h
      EXPECT_NEAR((g - fd).norm(), 0.0, 1e-6);
      EXPECT_NEAR(g.norm(), 1.0, 1e-12);
      ++checked;
    }
  }
  EXPECT_GT(checked, 500);  // most samples are away from kinks
}

// velocity(p, t) is d/dt of the material point pose(t) X, translation, rotation and scale all
// changing; at a surface point it gives the field's time derivative: d phi / dt = -grad phi . v.
TEST(ScaledCollider, VelocityIsTheTimeDerivativeOfTheSurfacePoint) {
  const auto box = morphing_box();
  const double h = 1e-6;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.1, 0.1), tu(0.05, 2.95);
  for (int i = 0; i < 100; ++i) {
    const double t = tu(rng);
    if (std::abs(t - 2.0) < 2 * h) continue;  // a keyframe: the velocity jumps there
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const Eigen::Vector3d X = box->motion.pose(t).inverse() * p;
    const Eigen::Vector3d fd =
        (box->motion.pose(t + h) * X - box->motion.pose(t - h) * X) / (2 * h);
    EXPECT_NEAR((box->velocity(p, t) - fd).norm(), 0.0, 1e-8 * (1 + fd.norm()));
  }
  // Spheres and cavities, growing and shrinking: at surface points.
  for (pc::ColliderKind kind : {pc::ColliderKind::sphere, pc::ColliderKind::inverted_sphere}) {
    for (double end_scale : {0.25, 3.0}) {
      const auto c = pc::make_collider(sphere_spec(
          kind, 0.1,
          {keyframe(0, {0, 0, 0}, 0, 1.0), keyframe(2, {0.05, 0.02, -0.03}, 0.5, end_scale)}));
      for (int i = 0; i < 50; ++i) {
        const double t = tu(rng) * 0.6;
        Eigen::Vector3d dir(u(rng), u(rng), u(rng));
        dir.normalize();
        const Eigen::Vector3d p = c->motion.pose(t).translation() + 0.1 * c->motion.scale(t) * dir;
        Eigen::Vector3d n;
        ASSERT_NEAR(c->distance(p, t, &n), 0.0, 1e-15);
        const double dphi_dt = (c->distance(p, t + h) - c->distance(p, t - h)) / (2 * h);
        EXPECT_NEAR(dphi_dt, -n.dot(c->velocity(p, t)), 1e-8);
        // The radial part: a surface point moves along its radius at radius x s'/s.
        const double radial = dir.dot(c->velocity(p, t) - c->motion.linear_velocity(t));
        EXPECT_NEAR(radial, 0.1 * c->motion.scale_rate(t), 1e-12);
      }
    }
  }
}

// Swept bounds hold every corner of a turning, moving, shrinking and growing box at every time.
TEST(ScaledCollider, SweptBoundsHoldTheSurfaceAtEveryTime) {
  const auto box = morphing_box();
  const pc::Aabb s = box->swept_bounds(0.5, 2.7);
  for (int k = 0; k <= 400; ++k) {
    const double t = 0.5 + 2.2 * k / 400;
    const Eigen::Affine3d x = box->motion.pose(t);
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d q = x * Eigen::Vector3d((c & 1) ? 0.05 : -0.05, (c & 2) ? 0.03 : -0.03,
                                                    (c & 4) ? 0.02 : -0.02);
      EXPECT_TRUE((q.array() >= s.lo.array() - 1e-12).all() &&
                  (q.array() <= s.hi.array() + 1e-12).all());
    }
  }
}

TEST(InvertedSphere, FieldIsRadiusMinusDistanceWithInwardNormal) {
  const auto c = pc::make_collider(
      sphere_spec(pc::ColliderKind::inverted_sphere, 0.2,
                  {keyframe(0, {0.1, 0, 0}, 0, 1.0), keyframe(1, {0.1, 0, 0}, 0, 0.5)}));
  EXPECT_FALSE(c->is_convex());
  Eigen::Vector3d g;
  EXPECT_NEAR(c->distance({0.1, 0, 0.05}, 0.0, &g), 0.15, 1e-15);
  EXPECT_NEAR((g - Eigen::Vector3d(0, 0, -1)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(c->distance({0.1, 0, 0.05}, 1.0), 0.05, 1e-15);  // radius 0.1 at t = 1
  EXPECT_NEAR(c->distance({0.1, 0.3, 0}, 0.0), -0.1, 1e-15);   // outside the cavity: in the solid
  pc::ColliderSpec level = sphere_spec(pc::ColliderKind::inverted_sphere, 0.2, {});
  level.field = pc::FieldKind::level_set;
  EXPECT_THROW(pc::make_collider(level), pc::ColliderError);
  EXPECT_EQ(pc::collider_kind_from_string("inverted_sphere"), pc::ColliderKind::inverted_sphere);
}

// r - |p - c| is concave in p, so over a triangle inside the cavity its minimum is at a vertex:
// the vertex terms are the exact face contact. Dense barycentric sampling never goes below
// the smallest vertex value.
TEST(InvertedSphere, MinimumOverATriangleIsAtAVertex) {
  const auto c = pc::make_collider(sphere_spec(pc::ColliderKind::inverted_sphere, 0.2, {}));
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> r(0.0, 0.2);
  for (int i = 0; i < 200; ++i) {
    Eigen::Vector3d v[3];
    double vertex_min = INFINITY;
    for (auto& p : v) {
      p = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * r(rng);
      vertex_min = std::min(vertex_min, c->distance(p, 0));
    }
    double sampled_min = INFINITY;
    const int N = 40;
    for (int a = 0; a <= N; ++a)
      for (int b = 0; a + b <= N; ++b) {
        const Eigen::Vector3d p = (a * v[0] + b * v[1] + (N - a - b) * v[2]) / N;
        sampled_min = std::min(sampled_min, c->distance(p, 0));
      }
    EXPECT_GE(sampled_min, vertex_min - 1e-15);
    EXPECT_LE(sampled_min, vertex_min + 1e-15);  // the vertices are among the samples
  }
}

// CCD of a vertex on a segment inside the cavity: the exact step keeps the point at
// phi >= keep phi(p) all along (dense check), never tunnels out for random segments, and
// is the largest such step (the point at the returned step sits on the inner sphere when
// the step is below the limit).
TEST(InvertedSphere, SegmentStepNeverTunnelsAndIsTight) {
  const auto c = pc::make_collider(
      sphere_spec(pc::ColliderKind::inverted_sphere, 0.2,
                  {keyframe(0, {0.01, 0.02, 0}, 0, 1.0), keyframe(1, {0, 0, 0}, 0, 0.3)}));
  std::mt19937 rng(13);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> r(0.0, 1.0), tu(0.0, 1.2);
  int tight = 0;
  for (int i = 0; i < 2000; ++i) {
    const double t = tu(rng);
    const double radius = 0.2 * c->motion.scale(t);
    const Eigen::Vector3d centre = c->motion.pose(t).translation();
    const Eigen::Vector3d p =
        centre + Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * radius * r(rng);
    const Eigen::Vector3d d = Eigen::Vector3d(n(rng), n(rng), n(rng)) * radius * 3 * r(rng);
    const double keep = 0.1, phi0 = c->distance(p, t);
    const double a = c->segment_step(p, d, t, 1.0, keep);
    ASSERT_GE(a, 0.0);
    ASSERT_LE(a, 1.0);
    for (int k = 0; k <= 200; ++k)
      EXPECT_GE(c->distance(p + a * k / 200.0 * d, t), keep * phi0 - 1e-12);
    if (a < 1.0) {
      EXPECT_NEAR(c->distance(p + a * d, t), keep * phi0, 1e-12);
      ++tight;
    }
  }
  EXPECT_GT(tight, 500);  // many segments would leave the cavity
  // The generic sphere tracing (used for other non-convex fields) is conservative too.
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d p = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * 0.1 * r(rng);
    const Eigen::Vector3d d = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.2;
    const double exact = c->segment_step(p, d, 0.0, 1.0, 0.1);
    EXPECT_LE(c->Collider::segment_step(p, d, 0.0, 1.0, 0.1), exact + 1e-12);
  }
}
