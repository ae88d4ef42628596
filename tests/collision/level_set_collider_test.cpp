#include "collision/level_set_collider.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <thread>

#include "collision/collider_factory.hpp"
#include "collision/errors.hpp"
#include "collision/shapes.hpp"

namespace pc = papersim::collision;

namespace {

struct FieldError {
  double max_error = 0.0;         ///< max |phi_grid - phi_exact| [m]
  double max_over_outside = 0.0;  ///< max (phi_grid - phi_exact) outside: non-conservative part [m]
  double min_gradient_dot = 1.0;  ///< min g_grid . g_exact where the exact field is smooth
  double mean_gradient_dot = 0.0;
  double max_gradient_norm_error = 0.0;
  int samples = 0;
};

/// Samples random points with |phi_exact| < exact_range around the shape and compares.
FieldError compare(const pc::Collider& grid, const pc::Shape& s, double exact_range, double h) {
  std::mt19937 rng(11);
  pc::Aabb b = pc::shape_bounds(s);
  b.inflate(exact_range);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  FieldError e;
  int smooth = 0;
  while (e.samples < 20000) {
    const Eigen::Vector3d p =
        b.lo + (b.hi - b.lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    Eigen::Vector3d g_exact, g;
    const double d_exact = pc::shape_distance(s, p, &g_exact);
    if (std::abs(d_exact) >= exact_range) continue;
    ++e.samples;
    const double d = grid.distance(p, 0.0, &g);
    e.max_error = std::max(e.max_error, std::abs(d - d_exact));
    if (d_exact > 0.0) e.max_over_outside = std::max(e.max_over_outside, d - d_exact);
    e.max_gradient_norm_error = std::max(e.max_gradient_norm_error, std::abs(g.norm() - 1.0));
    // Where the exact gradient turns by less than ~10 deg over +-2 voxels (away from the medial
    // axis and close to sharp edges) check the direction; near kinks it is a blend.
    bool is_smooth = true;
    for (int k = 0; k < 3 && is_smooth; ++k) {
      Eigen::Vector3d gk;
      pc::shape_distance(s, p + 2.0 * h * Eigen::Vector3d::Unit(k), &gk);
      is_smooth = (gk - g_exact).norm() < 0.2;
      pc::shape_distance(s, p - 2.0 * h * Eigen::Vector3d::Unit(k), &gk);
      is_smooth = is_smooth && (gk - g_exact).norm() < 0.2;
    }
    if (is_smooth && d_exact > 0.0) {
      e.min_gradient_dot = std::min(e.min_gradient_dot, g.dot(g_exact));
      e.mean_gradient_dot += g.dot(g_exact);
      ++smooth;
    }
  }
  e.mean_gradient_dot /= std::max(smooth, 1);
  return e;
}

void check_primitive(const pc::Shape& s, const char* name) {
  const auto grid = pc::LevelSetCollider::from_shape(s);
  const double h = grid->voxel_size();
  const FieldError e = compare(*grid, s, grid->exact_range(), h);
  std::printf(
      "[ figures  ] %-9s h = %.3g mm, band = %.3g mm, %zu voxels, max |error| = %.3g mm"
      " = %.3f h, outside overestimate <= %.3f h, gradient: | |g|-1 | <= %.1e, min dot = %.4f, "
      "mean dot = %.6f\n",
      name, h * 1e3, grid->band_width() * 1e3, grid->active_voxel_count(), e.max_error * 1e3,
      e.max_error / h, e.max_over_outside / h, e.max_gradient_norm_error, e.min_gradient_dot,
      e.mean_gradient_dot);
  EXPECT_LT(e.max_error, 0.5 * h) << name;
  EXPECT_LT(e.max_gradient_norm_error, 1e-9) << name;
  EXPECT_GT(e.min_gradient_dot, 0.95) << name;
  EXPECT_GT(e.mean_gradient_dot, 0.999) << name;
}

pc::Shape shape(pc::ShapeKind kind) {
  pc::Shape s;
  s.kind = kind;
  return s;
}

}  // namespace

TEST(LevelSet, SphereField) {
  pc::Shape s = shape(pc::ShapeKind::sphere);
  s.radius = 0.03;
  check_primitive(s, "sphere");
}

TEST(LevelSet, SmallSphereField) {
  pc::Shape s = shape(pc::ShapeKind::sphere);
  s.radius = 0.005;
  check_primitive(s, "sphere5mm");
}

TEST(LevelSet, CylinderField) {
  pc::Shape s = shape(pc::ShapeKind::cylinder);
  s.radius = 0.02;
  s.length = 0.15;
  check_primitive(s, "cylinder");
}

TEST(LevelSet, CapsuleField) {
  pc::Shape s = shape(pc::ShapeKind::capsule);
  s.radius = 0.015;
  s.length = 0.1;
  check_primitive(s, "capsule");
}

TEST(LevelSet, BoxField) {
  pc::Shape s = shape(pc::ShapeKind::box);
  s.half_extents = {0.04, 0.03, 0.01};
  check_primitive(s, "box");
}

TEST(LevelSet, GableField) {
  pc::Shape s = shape(pc::ShapeKind::gable);
  s.half_width = 0.03;
  s.height = 0.03;  // 90 deg ridge
  s.length = 0.15;
  check_primitive(s, "gable");
}

TEST(LevelSet, FarFieldIsConservative) {
  pc::Shape s = shape(pc::ShapeKind::sphere);
  s.radius = 0.02;
  const auto grid = pc::LevelSetCollider::from_shape(s);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const double exact = pc::shape_distance(s, p, nullptr);
    Eigen::Vector3d g;
    const double d = grid->distance(p, 0.0, &g);
    EXPECT_NEAR(g.norm(), 1.0, 1e-12);
    if (std::abs(exact) < grid->exact_range()) continue;
    // Outside the band: a lower bound on the distance, never below the band bound.
    if (exact > 0) {
      EXPECT_LE(d, exact + 1e-12);
      EXPECT_GE(d, grid->exact_range() - 1e-12);
    } else {
      EXPECT_GE(d, exact);
      EXPECT_LT(d, 0.0);
    }
  }
  // Far away the bound is the distance to the bounding box: useful for CCD.
  EXPECT_NEAR(grid->distance({1.0, 0.0, 0.0}, 0.0), 0.98, 1e-12);
  EXPECT_NEAR(grid->distance({0.0, 0.0, 0.0}, 0.0), -grid->exact_range(), 1e-12);
}

TEST(LevelSet, BandCoversContactThicknessAndReach) {
  pc::Shape s = shape(pc::ShapeKind::sphere);
  s.radius = 0.05;
  pc::LevelSetParams params;
  params.contact_thickness = 2e-3;
  params.reach = 3e-3;
  const auto grid = pc::LevelSetCollider::from_shape(s, params);
  EXPECT_DOUBLE_EQ(grid->voxel_size(), 2e-3);  // min(0.05 / 8, contact thickness)
  EXPECT_GE(grid->exact_range(), params.contact_thickness + params.reach - 1e-12);
  EXPECT_NEAR(grid->distance({0.0, 0.0, 0.0549}, 0.0), 0.0049, 0.5 * grid->voxel_size());
}

TEST(LevelSet, KeyframedGridFollowsMotion) {
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::sphere;
  spec.field = pc::FieldKind::level_set;
  spec.radius = 0.02;
  pc::Keyframe k0, k1;
  k0.time = 0.0;
  k1.time = 1.0;
  k1.translation = {0.1, 0.0, 0.05};
  k1.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  spec.keyframes = {k0, k1};
  const auto c = pc::make_collider(spec);
  const double h = dynamic_cast<const pc::LevelSetCollider&>(*c).voxel_size();
  for (double t : {0.0, 0.3, 0.5, 1.0, 2.0}) {
    const Eigen::Vector3d centre = std::min(t, 1.0) * k1.translation;
    const Eigen::Vector3d p = centre + Eigen::Vector3d(0.0, 0.021, 0.004);
    Eigen::Vector3d g;
    const double d = c->distance(p, t, &g);
    const Eigen::Vector3d n = (p - centre).normalized();
    EXPECT_NEAR(d, (p - centre).norm() - 0.02, 0.5 * h) << "t = " << t;
    EXPECT_GT(g.dot(n), 0.995) << "t = " << t;
  }
  // A box rotated by the keyframes: the gradient on a face follows the rotation.
  spec.kind = pc::ColliderKind::box;
  spec.half_extents = {0.05, 0.02, 0.02};
  const auto box = pc::make_collider(spec);
  Eigen::Vector3d g;
  const Eigen::Vector3d centre = 0.5 * k1.translation;
  const Eigen::Vector3d axis_x(std::cos(M_PI / 4), std::sin(M_PI / 4), 0.0);  // local x at t=0.5
  const double d = box->distance(centre + 0.052 * axis_x, 0.5, &g);
  EXPECT_NEAR(d, 0.002, 0.5 * h);
  EXPECT_GT(g.dot(axis_x), 0.999);
}

TEST(LevelSet, QueriesAreThreadSafe) {
  pc::Shape s = shape(pc::ShapeKind::gable);
  s.half_width = s.height = 0.02;
  s.length = 0.1;
  const auto grid = pc::LevelSetCollider::from_shape(s);
  std::vector<Eigen::Vector3d> points;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  for (int i = 0; i < 20000; ++i) points.emplace_back(u(rng), u(rng), u(rng) + 0.01);
  std::vector<double> serial(points.size()), parallel(points.size());
  for (size_t i = 0; i < points.size(); ++i) serial[i] = grid->distance(points[i], 0.0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (size_t i = t; i < points.size(); i += 4) parallel[i] = grid->distance(points[i], 0.0);
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(serial, parallel);
}

TEST(LevelSet, RefusesHugeGrids) {
  pc::Shape s = shape(pc::ShapeKind::box);
  s.half_extents = {1.0, 1.0, 1.0};
  pc::LevelSetParams params;
  params.voxel_size = 1e-4;
  try {
    pc::LevelSetCollider::from_shape(s, params);
    FAIL() << "expected ColliderError";
  } catch (const pc::ColliderError& e) {
    EXPECT_NE(std::string(e.what()).find("voxel"), std::string::npos) << e.what();
  }
}

// The contact models learn an obstacle's kind from the collider itself, never from its type:
// a plane says so, an analytic primitive gives its shape (kind and dimensions as specified),
// and the same primitive as a level set, like any mesh, gives none.
TEST(LevelSet, AColliderTellsTheContactModelsItsKind) {
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::plane;
  const auto plane = pc::make_collider(spec);
  EXPECT_TRUE(plane->is_plane());
  EXPECT_EQ(plane->analytic_shape(), nullptr);
  spec.kind = pc::ColliderKind::sphere;
  spec.radius = 0.03;
  const auto sphere = pc::make_collider(spec);
  EXPECT_FALSE(sphere->is_plane());
  ASSERT_NE(sphere->analytic_shape(), nullptr);
  EXPECT_EQ(sphere->analytic_shape()->kind, pc::ShapeKind::sphere);
  EXPECT_EQ(sphere->analytic_shape()->radius, 0.03);
  spec.kind = pc::ColliderKind::gable;
  const auto gable = pc::make_collider(spec);
  ASSERT_NE(gable->analytic_shape(), nullptr);
  EXPECT_EQ(gable->analytic_shape()->kind, pc::ShapeKind::gable);
  spec.field = pc::FieldKind::level_set;
  const auto gable_grid = pc::make_collider(spec);
  EXPECT_EQ(gable_grid->analytic_shape(), nullptr);
  EXPECT_FALSE(gable_grid->is_plane());
}
