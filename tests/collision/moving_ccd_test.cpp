// Continuous collision detection of a point against an obstacle that moves during the step
// (Collider::moving_segment_step): the joint motion p + a d, t + a dt, for the motions the
// solver follows (a cylinder rolling along, a shrinking cavity, a plate pressing down).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "collision/collider_factory.hpp"
#include "collision/shapes.hpp"

namespace pc = papersim::collision;

namespace {

/// A roller as the fold scenario has it: a cylinder (radius 5 cm, length 50 cm) whose axis is
/// along world y, resting until 1 s and then rolling without slipping along -x at 0.25 m/s,
/// one keyframe per 0.1 s.
std::unique_ptr<pc::Collider> roller() {
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::cylinder;
  spec.radius = 0.05;
  spec.length = 0.5;
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  const Eigen::Quaterniond base =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), axis);
  pc::Keyframe k;
  k.translation = Eigen::Vector3d(0, 0, 0.057);
  k.rotation = base;
  spec.keyframes.push_back(k);
  for (int i = 0; i <= 10; ++i) {
    const double s = 0.025 * i;  // distance rolled [m]
    k.time = 1.0 + 0.1 * i;
    k.translation = Eigen::Vector3d(-s, 0, 0.057);
    k.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-s / spec.radius, axis)) * base;
    spec.keyframes.push_back(k);
  }
  return pc::make_collider(spec);
}

/// A cavity of radius 0.2 m centred at (0, 0, 0.25) m that holds until 1 s and shrinks to a
/// quarter at 5 s (the crumple scenario's).
std::unique_ptr<pc::Collider> cavity() {
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::inverted_sphere;
  spec.radius = 0.2;
  pc::Keyframe k;
  k.translation = Eigen::Vector3d(0, 0, 0.25);
  k.time = 1.0;
  spec.keyframes.push_back(k);
  k.time = 5.0;
  k.scale = 0.25;
  spec.keyframes.push_back(k);
  return pc::make_collider(spec);
}

/// A pressing plate: the plane turned over (solid above, normal -z), at z = 0.04 m until 0.5 s,
/// down to 0.005 m at 1.5 s, up again by 2 s.
std::unique_ptr<pc::Collider> plate() {
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::plane;
  pc::Keyframe k;
  k.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  for (const auto& [t, z] : {std::pair{0.5, 0.04}, {1.5, 0.005}, {2.0, 0.04}}) {
    k.time = t;
    k.translation = Eigen::Vector3d(0.01, -0.02, z);
    spec.keyframes.push_back(k);
  }
  return pc::make_collider(spec);
}

/// The smallest of phi along the joint motion over [0, a], sampled at `samples` points, over
/// phi at the start.
double smallest_relative_gap(const pc::Collider& c, const Eigen::Vector3d& p,
                             const Eigen::Vector3d& d, double t, double dt, double a,
                             int samples = 400) {
  const double phi0 = c.distance(p, t);
  double m = INFINITY;
  for (int k = 0; k <= samples; ++k) {
    const double b = a * k / samples;
    m = std::min(m, c.distance(p + b * d, t + b * dt) / phi0);
  }
  return m;
}

}  // namespace

TEST(MovingCcd, RollerAndCavityMoveAffinelyARotatingBoxDoesNot) {
  EXPECT_TRUE(roller()->moves_affinely(1.03, 1.05));
  EXPECT_TRUE(roller()->moves_affinely(0.5, 1.5));  // across keyframes
  EXPECT_TRUE(cavity()->moves_affinely(2.0, 2.01));
  // A cylinder turning about a line across its axis, a box turning at all, and a sphere
  // (convex) changing its size are not followed.
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::cylinder;
  spec.radius = 0.05;
  spec.length = 0.5;
  pc::Keyframe a, b;
  b.time = 1.0;
  b.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  spec.keyframes = {a, b};
  EXPECT_FALSE(pc::make_collider(spec)->moves_affinely(0.1, 0.2));
  spec.kind = pc::ColliderKind::box;
  spec.half_extents = Eigen::Vector3d(0.1, 0.1, 0.1);
  EXPECT_FALSE(pc::make_collider(spec)->moves_affinely(0.1, 0.2));
  EXPECT_TRUE(pc::make_collider(spec)->moves_affinely(1.1, 1.2));  // held after the last keyframe
  spec.kind = pc::ColliderKind::sphere;
  b.rotation = Eigen::Quaterniond::Identity();
  b.scale = 2.0;
  spec.keyframes = {a, b};
  EXPECT_FALSE(pc::make_collider(spec)->moves_affinely(0.1, 0.2));
}

// Random points near the rolling cylinder, moving in random directions while the roller moves
// on by up to 20 ms (5 mm, and it spins by 0.1 rad): no sampled point of the joint motion
// comes closer than the 10% of its gap the step keeps, and a point carried along with the
// roller's translation is never held back however close it is.
TEST(MovingCcd, RollingCylinderKeepsEveryPointOutsideAndLetsACarriedPointGo) {
  const auto c = roller();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  int limited = 0;
  for (int i = 0; i < 2000; ++i) {
    const double t = 1.0 + 0.99 * u(rng), dt = 0.02 * u(rng);
    const Eigen::Vector3d centre = c->motion.pose(t).translation();
    const double angle = 2 * M_PI * u(rng);
    const double gap = std::pow(10.0, -7 + 5 * u(rng));
    const Eigen::Vector3d p =
        centre + Eigen::Vector3d((0.05 + gap) * std::cos(angle), 0.4 * (u(rng) - 0.5),
                                 (0.05 + gap) * std::sin(angle));
    const Eigen::Vector3d d = 0.01 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    const double a = c->moving_segment_step(p, d, t, dt, 1.0, 0.1);
    ASSERT_GE(a, 0.0);
    if (a < 1.0) ++limited;
    EXPECT_GE(smallest_relative_gap(*c, p, d, t, dt, a), 0.1 * (1 - 1e-9)) << "point " << i;
    // Carried with the roller's translation over the step: the whole step is allowed.
    const Eigen::Vector3d with = dt * c->motion.linear_velocity(t);
    EXPECT_GE(c->moving_segment_step(p, with, t, dt, 1.0, 0.1),
              std::min(1.0, (c->motion.next_keyframe_time(t) - t) / dt) * (1 - 1e-12));
  }
  EXPECT_GT(limited, 200);  // the test does exercise the bound
}

// The shrinking cavity: the bound is the exact root, so the point reaches 10% of its gap at the
// step returned (when that is shorter than asked), and never comes closer before.
TEST(MovingCcd, ShrinkingCavityBoundIsExact) {
  const auto c = cavity();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  int exact = 0;
  for (int i = 0; i < 2000; ++i) {
    const double t = 1.0 + 3.9 * u(rng), dt = 0.05 * u(rng);
    const Eigen::Affine3d pose = c->motion.pose(t);
    const double radius = 0.2 * c->motion.scale(t);
    const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const double gap = std::pow(10.0, -7 + 5 * u(rng));
    const Eigen::Vector3d p = pose.translation() + (radius - gap) * dir;
    const Eigen::Vector3d d = 0.01 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    const double a = c->moving_segment_step(p, d, t, dt, 1.0, 0.1);
    ASSERT_GE(a, 0.0);
    EXPECT_GE(smallest_relative_gap(*c, p, d, t, dt, a), 0.1 * (1 - 1e-6)) << "point " << i;
    if (a < 1.0 && t + dt < 5.0) {
      ++exact;
      EXPECT_NEAR(c->distance(p + a * d, t + a * dt) / c->distance(p, t), 0.1, 1e-6)
          << "point " << i;
    }
  }
  EXPECT_GT(exact, 200);
}

// The pressing plate: its field is linear along the joint motion, so the bound is exact (the
// point reaches 10% of its gap at the step returned, across the keyframe at 1.5 s too), a point
// that moves with the plate is never held back, and a plate that tilts is not followed.
TEST(MovingCcd, PressingPlateBoundIsExactAndATiltingPlateIsNotFollowed) {
  const auto c = plate();
  EXPECT_TRUE(c->moves_affinely(0.0, 3.0));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  int exact = 0;
  for (int i = 0; i < 2000; ++i) {
    const double t = 0.4 + 1.5 * u(rng), dt = 0.05 * u(rng);
    const double top = c->motion.pose(t).translation().z();
    const double gap = std::pow(10.0, -7 + 5 * u(rng));
    const Eigen::Vector3d p(0.2 * (u(rng) - 0.5), 0.2 * (u(rng) - 0.5), top - gap);
    ASSERT_NEAR(c->distance(p, t), gap, 1e-12);
    const Eigen::Vector3d d = 0.01 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    const double a = c->moving_segment_step(p, d, t, dt, 1.0, 0.1);
    ASSERT_GE(a, 0.0);
    EXPECT_GE(smallest_relative_gap(*c, p, d, t, dt, a), 0.1 * (1 - 1e-6)) << "point " << i;
    if (a < 1.0) {
      ++exact;
      EXPECT_NEAR(c->distance(p + a * d, t + a * dt) / c->distance(p, t), 0.1, 1e-6)
          << "point " << i;
    }
    // Carried down with the plate within its keyframe piece: the whole piece is allowed.
    const Eigen::Vector3d with = dt * c->motion.linear_velocity(t);
    EXPECT_GE(c->moving_segment_step(p, with, t, dt, 1.0, 0.1),
              std::min(1.0, (c->motion.next_keyframe_time(t) - t) / dt) * (1 - 1e-12));
  }
  EXPECT_GT(exact, 200);
  // A point at rest under the plate coming down at 0.035 m/s stops at 10% of its gap.
  const Eigen::Vector3d rest(0, 0, 0.02);
  const double phi0 = c->distance(rest, 1.0);
  EXPECT_NEAR(c->moving_segment_step(rest, Eigen::Vector3d::Zero(), 1.0, 1.0, 1.0, 0.1),
              0.9 * phi0 / 0.035, 1e-12);

  // Turning about its normal leaves the plane where it is (followed); tilting does not.
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::plane;
  pc::Keyframe a, b;
  b.time = 1.0;
  b.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  spec.keyframes = {a, b};
  EXPECT_TRUE(pc::make_collider(spec)->moves_affinely(0.1, 0.2));
  b.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  spec.keyframes = {a, b};
  EXPECT_FALSE(pc::make_collider(spec)->moves_affinely(0.1, 0.2));
  EXPECT_LT(pc::make_collider(spec)->moving_segment_step(rest, Eigen::Vector3d::Zero(), 0.1, 0.1,
                                                         1.0, 0.1),
            0.0);
}
