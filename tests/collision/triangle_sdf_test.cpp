#include "collision/triangle_sdf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "collision/level_set_collider.hpp"
#include "collision/shapes.hpp"

namespace pc = papersim::collision;

namespace {

/// Minimum of the field over a dense barycentric grid (reference).
double dense_min(const pc::Collider& c, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                 const Eigen::Vector3d& d, int n) {
  double best = 1e300;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      best = std::min(best, c.distance((1 - u - v) * a + u * b + v * d, 0.0));
    }
  return best;
}

pc::Shape gable() {
  pc::Shape s;
  s.kind = pc::ShapeKind::gable;
  s.half_width = s.height = 0.03;
  s.length = 0.3;
  return s;
}

}  // namespace

TEST(TriangleSdf, FindsGableRidgeBetweenVertices) {
  // A 6 cm triangle lying 0.4 mm above a 90 deg ridge that crosses it; its vertices are
  // 1.5-2.5 cm from the obstacle, so a vertex-only test sees nothing.
  const pc::AnalyticCollider ridge(gable());
  const double z = 0.03 + 4e-4;
  const Eigen::Vector3d a(-0.02, -0.03, z), b(0.03, 0.02, z), c(0.0, 0.035, z);
  for (const Eigen::Vector3d& v : {a, b, c}) EXPECT_GT(ridge.distance(v, 0.0), 0.01);
  const pc::TriangleSdfResult r =
      pc::triangle_min_distance(ridge, a, b, c, Eigen::Isometry3d::Identity());
  std::printf("[ figures  ] ridge: min %.4g mm (exact 0.4), lower bound %.4g mm, %d queries\n",
              r.distance * 1e3, r.lower_bound * 1e3, r.evaluations);
  EXPECT_NEAR(r.distance, 4e-4, 1e-6);
  EXPECT_LE(r.lower_bound, 4e-4 + 1e-12);
  EXPECT_NEAR(r.point.y(), 0.0, 1e-3);
  EXPECT_NEAR(r.barycentric.sum(), 1.0, 1e-12);
  EXPECT_GE(r.barycentric.minCoeff(), 0.0);
  EXPECT_NEAR(
      (r.point - (r.barycentric[0] * a + r.barycentric[1] * b + r.barycentric[2] * c)).norm(), 0.0,
      1e-15);
  EXPECT_LT(r.evaluations, 2048);
}

TEST(TriangleSdf, FindsSmallSphereUnderLargeTriangle) {
  pc::Shape s;
  s.kind = pc::ShapeKind::sphere;
  s.radius = 0.005;
  const auto grid = pc::LevelSetCollider::from_shape(s);
  const pc::AnalyticCollider exact(s);
  const double z = 0.005 + 3e-4;
  const Eigen::Vector3d a(-0.03, -0.02, z), b(0.04, -0.01, z), c(0.0, 0.04, z);
  for (const pc::Collider* collider :
       {static_cast<const pc::Collider*>(&exact), static_cast<const pc::Collider*>(grid.get())}) {
    pc::TriangleSdfParams params;
    params.lipschitz = collider == grid.get() ? 1.05 : 1.0;
    const pc::TriangleSdfResult r =
        pc::triangle_min_distance(*collider, a, b, c, Eigen::Isometry3d::Identity(), params);
    const double reference = dense_min(*collider, a, b, c, 400);
    std::printf(
        "[ figures  ] 5 mm sphere (%s): min %.4g mm, dense-grid min %.4g mm, lower "
        "bound %.4g mm, %d queries\n",
        collider == grid.get() ? "grid" : "exact", r.distance * 1e3, reference * 1e3,
        r.lower_bound * 1e3, r.evaluations);
    EXPECT_LE(r.distance, reference + 1e-6);
    EXPECT_LE(r.lower_bound, reference);
    EXPECT_NEAR(r.point.head<2>().norm(), 0.0, 1e-3);
    EXPECT_NEAR(r.gradient.z(), 1.0, 1e-2);  // grid: the minimiser is within a voxel fraction
  }
}

TEST(TriangleSdf, FarTriangleCostsOneQuery) {
  const pc::AnalyticCollider ridge(gable());
  const pc::TriangleSdfResult r = pc::triangle_min_distance(
      ridge, {0, 0, 0.5}, {0.01, 0, 0.5}, {0, 0.01, 0.5}, Eigen::Isometry3d::Identity());
  EXPECT_EQ(r.evaluations, 1);
  EXPECT_GT(r.lower_bound, 1e-3);
  EXPECT_LE(r.lower_bound, r.distance);
}

TEST(TriangleSdf, MeshHelperKeepsFacesInRange) {
  const pc::AnalyticCollider ridge(gable());
  const double z = 0.03 + 2e-4;
  const std::vector<Eigen::Vector3d> x = {{-0.05, -0.05, z}, {0.05, -0.05, z}, {0.05, 0.05, z},
                                          {-0.05, 0.05, z},  {0.0, 0.0, 0.2},  {0.01, 0.0, 0.2},
                                          {0.0, 0.01, 0.2}};
  const std::vector<Eigen::Vector3i> faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}};
  const auto contacts = pc::mesh_edges_faces_vs_sdf(ridge, x, faces, Eigen::Isometry3d::Identity());
  ASSERT_EQ(contacts.size(), 2u);
  EXPECT_EQ(contacts[0].face, 0);
  EXPECT_EQ(contacts[1].face, 1);
  for (const auto& c : contacts) EXPECT_NEAR(c.result.distance, 2e-4, 1e-6);
}
