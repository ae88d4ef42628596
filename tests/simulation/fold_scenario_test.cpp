// The fold scenario (SCENARIOS.md): keyframes of the pulled point and of the roller.
#include <gtest/gtest.h>

#include <cmath>

#include "collision/collider_factory.hpp"
#include "simulation/scenario.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

Eigen::Vector3d horizontal(const Eigen::Vector3d& v) { return {v.x(), v.y(), 0.0}; }

}  // namespace

TEST(FoldScenario, PulledPointFollowsTheKeyframesOverTheCentreAndIsReleased) {
  for (std::uint64_t seed : {0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u}) {
    const Scene s = make_scenario("fold", seed);
    ASSERT_EQ(s.handles.size(), 1u);
    const HandleSpec& h = s.handles[0];
    const Eigen::Vector2d p = h.material_point;
    // On the boundary of the sheet.
    const double to_edge = std::min({p.x(), p.y(), s.sheet.width - p.x(), s.sheet.height - p.y()});
    EXPECT_NEAR(to_edge, 0.0, 1e-12) << seed;
    const Eigen::Vector2d centre(0.5 * s.sheet.width, 0.5 * s.sheet.height);
    const double D = 2 * (centre - p).norm();
    const Eigen::Vector2d d = (centre - p).normalized();
    ASSERT_EQ(h.keyframes.size(), 7u);
    const double times[] = {0, 1, 2, 6, 7, 8, 9};
    const double along[] = {0, 0.5, 1, 1, 0.7, 0.15, 0};
    for (int k = 0; k < 7; ++k) {
      EXPECT_EQ(h.keyframes[k].time, times[k]);
      const Eigen::Vector3d u = h.keyframes[k].displacement;
      EXPECT_NEAR(u.x(), along[k] * D * d.x(), 1e-12);
      EXPECT_NEAR(u.y(), along[k] * D * d.y(), 1e-12);
    }
    // At t = 2 s the point lies over the mirror image of its start across the centre.
    const Eigen::Vector2d landed = p + h.keyframes[2].displacement.head<2>();
    EXPECT_NEAR((landed - (2 * centre - p)).norm(), 0.0, 1e-12);
    EXPECT_GE(h.keyframes[1].displacement.z(), 0.05);
    EXPECT_LE(h.keyframes[1].displacement.z(), 0.08);
    EXPECT_EQ(h.keyframes[2].displacement.z(), 0.02);
    EXPECT_EQ(h.keyframes[4].displacement.z(), 0.16);
    EXPECT_EQ(h.keyframes[5].displacement.z(), 0.08);
    EXPECT_EQ(h.release_time, 7.5);
    EXPECT_EQ(s.duration, 10.0);
    EXPECT_TRUE(s.self_contact.enabled);
    EXPECT_EQ(s.ground_friction, 2.0);
  }
}

TEST(FoldScenario, RollerRollsAcrossPerpendicularToTheFoldDirection) {
  for (std::uint64_t seed : {0u, 3u, 11u}) {
    const Scene s = make_scenario("fold", seed);
    ASSERT_EQ(s.obstacles.size(), 1u);
    const collision::ColliderSpec& spec = s.obstacles[0];
    EXPECT_EQ(spec.kind, collision::ColliderKind::cylinder);
    EXPECT_EQ(spec.radius, 0.05);
    EXPECT_EQ(spec.length, 0.5);
    EXPECT_EQ(spec.friction, 2.0);
    const auto roller = collision::make_collider(spec);
    const Eigen::Vector2d p = s.handles[0].material_point;
    const Eigen::Vector2d c2 = Eigen::Vector2d(0.5 * s.sheet.width, 0.5 * s.sheet.height) - p;
    const Eigen::Vector3d d(c2.normalized().x(), c2.normalized().y(), 0.0);
    // The sheet's centre is at the world origin (x, y).
    const Eigen::Vector3d centre(s.sheet.position.x(), s.sheet.position.y(), 0.0);
    for (double t : {0.0, 2.9, 3.0}) {
      const Eigen::Affine3d pose = roller->motion.pose(t);
      EXPECT_NEAR((horizontal(pose.translation()) - (centre + 0.35 * d)).norm(), 0.0, 1e-12) << t;
      EXPECT_NEAR(pose.translation().z(), 0.057, 1e-12);
    }
    const Eigen::Affine3d end = roller->motion.pose(6.0);
    EXPECT_NEAR((horizontal(end.translation()) - (centre - 0.35 * d)).norm(), 0.0, 1e-12);
    EXPECT_NEAR(end.translation().z(), 0.057, 1e-12);
    for (double t : {0.0, 4.5, 6.0}) {
      // Axis (local x) horizontal and perpendicular to d: 90 degrees, not the reference's ~63.
      const Eigen::Vector3d axis = roller->motion.pose(t).linear().col(0);
      EXPECT_NEAR(axis.z(), 0.0, 1e-9) << t;
      EXPECT_NEAR(axis.dot(d), 0.0, 1e-9) << t;
    }
    // Rolling without slipping: the lowest point of the roller is at rest mid-travel, and the
    // centre moves at 0.7 m / 3 s along -d.
    const double t = 4.55;
    const Eigen::Vector3d bottom = roller->motion.pose(t).translation() - Eigen::Vector3d(0, 0, 0.05);
    EXPECT_NEAR(roller->velocity(bottom, t).norm(), 0.0, 1e-9);
    const Eigen::Vector3d v = roller->motion.linear_velocity(t);
    EXPECT_NEAR((v + (0.7 / 3.0) * d).norm(), 0.0, 1e-9);
  }
}
