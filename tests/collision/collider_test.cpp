#include "collision/collider.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace pc = papersim::collision;

namespace {

Eigen::Quaterniond rot_z(double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
}

pc::Keyframe keyframe(double t, const Eigen::Vector3d& x, const Eigen::Quaterniond& q) {
  pc::Keyframe k;
  k.time = t;
  k.translation = x;
  k.rotation = q;
  return k;
}

}  // namespace

TEST(Aabb, DistanceBetweenBoxes) {
  pc::Aabb a, b;
  a.extend({0, 0, 0});
  a.extend({1, 1, 1});
  b.extend({2, 3, 0.5});
  b.extend({3, 4, 0.7});
  EXPECT_NEAR(a.distance_to(b), std::sqrt(1.0 + 4.0), 1e-14);
  EXPECT_NEAR(b.distance_to(a), std::sqrt(1.0 + 4.0), 1e-14);
  pc::Aabb c;
  c.extend({0.5, 0.5, 0.5});
  c.extend({5, 5, 5});
  EXPECT_EQ(a.distance_to(c), 0.0);
  EXPECT_TRUE(std::isinf(a.distance_to(pc::Aabb{})));
  EXPECT_NEAR(a.distance_to(Eigen::Vector3d(2, 0.5, -1)), std::sqrt(2.0), 1e-14);
}

TEST(Plane, DistanceAndGradient) {
  pc::PlaneCollider plane;
  Eigen::Vector3d g;
  EXPECT_DOUBLE_EQ(plane.distance({0.3, -2.0, 0.25}, 0.0, &g), 0.25);
  EXPECT_EQ(g, Eigen::Vector3d::UnitZ());
  EXPECT_DOUBLE_EQ(plane.distance({0.3, -2.0, -0.1}, 0.0), -0.1);
  const pc::Aabb b = plane.bounds(0.0);
  EXPECT_DOUBLE_EQ(b.lo.z(), 0.0);
  EXPECT_DOUBLE_EQ(b.hi.x(), plane.half_size);
}

TEST(Plane, TiltedPlaneRotatesGradient) {
  // Plane tilted about x by 30 deg and lifted by 1 m: normal (0, -sin, cos).
  const double a = M_PI / 6;
  pc::PlaneCollider plane;
  plane.motion = pc::RigidMotion({keyframe(
      0.0, {0, 0, 1}, Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX())))});
  const Eigen::Vector3d n(0, -std::sin(a), std::cos(a));
  Eigen::Vector3d g;
  const Eigen::Vector3d p(0.2, 0.4, 1.3);
  EXPECT_NEAR(plane.distance(p, 5.0, &g), n.dot(p - Eigen::Vector3d(0, 0, 1)), 1e-14);
  EXPECT_NEAR((g - n).norm(), 0.0, 1e-14);
  EXPECT_EQ(plane.velocity(p, 0.5), Eigen::Vector3d::Zero());
}

TEST(RigidMotion, RejectsNonIncreasingTimes) {
  EXPECT_THROW(
      pc::RigidMotion({keyframe(1.0, {0, 0, 0}, rot_z(0)), keyframe(1.0, {1, 0, 0}, rot_z(0))}),
      std::invalid_argument);
}

TEST(RigidMotion, InterpolatesTranslationAndSlerp) {
  const pc::RigidMotion m({keyframe(1.0, {0, 0, 0}, rot_z(0.0)),
                           keyframe(3.0, {2, 4, 0}, rot_z(M_PI / 2)),
                           keyframe(4.0, {2, 4, 1}, rot_z(M_PI / 2))});
  // Held before the first and after the last keyframe.
  EXPECT_TRUE(m.pose(0.0).isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_NEAR((m.pose(9.0).translation() - Eigen::Vector3d(2, 4, 1)).norm(), 0.0, 1e-14);
  // Halfway through the first segment: half the translation, half the angle.
  const Eigen::Affine3d x = m.pose(2.0);
  EXPECT_NEAR((x.translation() - Eigen::Vector3d(1, 2, 0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((x.linear() - rot_z(M_PI / 4).toRotationMatrix()).norm(), 0.0, 1e-14);
  EXPECT_NEAR((m.linear_velocity(2.0) - Eigen::Vector3d(1, 2, 0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((m.angular_velocity(2.0) - Eigen::Vector3d(0, 0, M_PI / 4)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((m.linear_velocity(3.5) - Eigen::Vector3d(0, 0, 1)).norm(), 0.0, 1e-14);
  EXPECT_EQ(m.angular_velocity(3.5), Eigen::Vector3d::Zero());
  EXPECT_EQ(m.linear_velocity(4.0), Eigen::Vector3d::Zero());
  EXPECT_FALSE(m.is_static());
  EXPECT_TRUE(pc::RigidMotion({keyframe(0, {1, 2, 3}, rot_z(1))}).is_static());
}

// translate_from: nothing changes before t0, the placement moves by delta from t1 on and by a
// linear part of it in between; the rest of the motion keeps its placement; inserted keyframes
// take rotation and scale from the motion given, so rebuilding from their times is exact.
TEST(RigidMotion, TranslateFromMovesThePlacementFromATimeOn) {
  const pc::RigidMotion before(
      {keyframe(1.0, {0, 0, 0}, rot_z(0.0)), keyframe(3.0, {2, 4, 0}, rot_z(M_PI / 2))});
  pc::RigidMotion m = before;
  const Eigen::Vector3d delta(0, 0, 0.5);
  m.translate_from(1.5, 2.0, delta, before);
  EXPECT_EQ(m.keyframes().size(), 4u);
  for (double t : {0.0, 1.0, 1.2, 1.5})
    EXPECT_NEAR((m.pose(t).matrix() - before.pose(t).matrix()).norm(), 0.0, 1e-14) << t;
  for (double t : {2.0, 2.5, 3.0, 7.0}) {
    EXPECT_NEAR((m.pose(t).translation() - before.pose(t).translation() - delta).norm(), 0.0, 1e-14)
        << t;
    EXPECT_NEAR((m.pose(t).linear() - before.pose(t).linear()).norm(), 0.0, 1e-14) << t;
  }
  EXPECT_NEAR((m.pose(1.75).translation() - before.pose(1.75).translation() - 0.5 * delta).norm(),
              0.0, 1e-14);
  EXPECT_NEAR((m.linear_velocity(1.75) - before.linear_velocity(1.75) - delta / 0.5).norm(), 0.0,
              1e-13);
  EXPECT_NEAR((m.angular_velocity(1.75) - before.angular_velocity(1.75)).norm(), 0.0, 1e-13);
  // A second change from the keyframe at 2.0 (within 1e-9 s: no new keyframe there), and one
  // beyond the last keyframe, where the motion was held.
  m.translate_from(2.0 + 1e-12, 2.25, -delta, before);
  EXPECT_EQ(m.keyframes().size(), 5u);
  EXPECT_NEAR((m.pose(2.5).translation() - before.pose(2.5).translation()).norm(), 0.0, 1e-14);
  m.translate_from(5.0, 6.0, delta, before);
  EXPECT_EQ(m.keyframes().size(), 7u);
  EXPECT_NEAR((m.pose(5.0).translation() - Eigen::Vector3d(2, 4, 0)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((m.pose(8.0).translation() - Eigen::Vector3d(2, 4, 0.5)).norm(), 0.0, 1e-14);
  // Rebuilt from the keyframe times and translations alone: the same keyframes to the bit.
  pc::RigidMotion rebuilt = before;
  for (const pc::Keyframe& k : m.keyframes())
    rebuilt.set_translation_at(k.time, k.translation, before);
  ASSERT_EQ(rebuilt.keyframes().size(), m.keyframes().size());
  for (size_t i = 0; i < m.keyframes().size(); ++i) {
    const pc::Keyframe &a = rebuilt.keyframes()[i], &b = m.keyframes()[i];
    EXPECT_TRUE(a.time == b.time && a.translation == b.translation &&
                a.rotation.coeffs() == b.rotation.coeffs() && a.scale == b.scale)
        << i;
  }
  EXPECT_THROW(m.translate_from(2.0, 2.0, delta, before), std::invalid_argument);
}

TEST(RigidMotion, SlerpTakesShortArc) {
  // -q is the same rotation as q: interpolation must not swing the long way round.
  Eigen::Quaterniond q = rot_z(0.2);
  q.coeffs() = -q.coeffs();
  const pc::RigidMotion m({keyframe(0.0, {0, 0, 0}, rot_z(0.0)), keyframe(1.0, {0, 0, 0}, q)});
  EXPECT_NEAR((m.pose(0.5).linear() - rot_z(0.1).toRotationMatrix()).norm(), 0.0, 1e-14);
  EXPECT_NEAR(m.angular_velocity(0.5).z(), 0.2, 1e-14);
}

TEST(Collider, KeyframedPlaneRotatesGradientAndMatchesVelocity) {
  // A plane rolling about the world y axis while translating: compare the analytic material
  // velocity with a finite difference of the pose, and the gradient with the rotated normal.
  pc::PlaneCollider plane;
  plane.motion = pc::RigidMotion(
      {keyframe(0.0, {0, 0, 0}, Eigen::Quaterniond::Identity()),
       keyframe(2.0, {0.5, 0, 0.2},
                Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d(0, 1, 0))))});
  const double t = 0.7;
  const Eigen::Affine3d x = plane.motion.pose(t);
  Eigen::Vector3d g;
  const Eigen::Vector3d p(0.3, 0.1, 0.4);
  const double d = plane.distance(p, t, &g);
  EXPECT_NEAR((g - x.linear().col(2)).norm(), 0.0, 1e-14);
  EXPECT_NEAR(d, x.linear().col(2).dot(p - x.translation()), 1e-14);
  EXPECT_NEAR(g.norm(), 1.0, 1e-14);
  // Material point at p: its local coordinates are fixed, so it moves as pose(t) * X.
  const Eigen::Vector3d X = x.inverse() * p;
  const double h = 1e-6;
  const Eigen::Vector3d fd =
      (plane.motion.pose(t + h) * X - plane.motion.pose(t - h) * X) / (2 * h);
  EXPECT_NEAR((plane.velocity(p, t) - fd).norm(), 0.0, 1e-8);
  // Same answer through the precomputed-pose entry point.
  Eigen::Vector3d g2;
  EXPECT_DOUBLE_EQ(plane.distance_at_pose(p, x, &g2), d);
  EXPECT_EQ(g2, g);
}

TEST(Collider, BoundsFollowPose) {
  pc::PlaneCollider plane;
  plane.half_size = 1.0;
  plane.motion = pc::RigidMotion(
      {keyframe(0.0, {0, 0, 0}, rot_z(0.0)), keyframe(1.0, {0, 0, 2}, rot_z(M_PI / 4))});
  const pc::Aabb b = plane.bounds(1.0);
  EXPECT_NEAR(b.hi.x(), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(b.lo.z(), 2.0, 1e-12);
  const pc::Aabb s = plane.swept_bounds(0.0, 1.0);
  // Conservative: padded by the chord deviation of the rotation (tiny here).
  EXPECT_NEAR(s.lo.z(), 0.0, 1e-3);
  EXPECT_NEAR(s.hi.z(), 2.0, 1e-3);
  EXPECT_GE(s.hi.x(), std::sqrt(2.0) - 1e-12);
  // Every corner at every intermediate time is inside the swept box.
  for (int k = 0; k <= 100; ++k) {
    const Eigen::Affine3d x = plane.motion.pose(k / 100.0);
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d q = x * Eigen::Vector3d((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, 0);
      EXPECT_TRUE((q.array() >= s.lo.array() - 1e-12).all() &&
                  (q.array() <= s.hi.array() + 1e-12).all());
    }
  }
}
