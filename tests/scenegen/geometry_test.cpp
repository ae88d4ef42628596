#include "scenegen/geometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <utility>

#include "scenegen/example_sheets.hpp"
#include "scenegen/random.hpp"
#include "scenegen/resting_pose.hpp"

namespace papersim::scenegen {
namespace {

TEST(Geometry, UvLocatorMapsMaterialPointsToTheMesh) {
  const SheetMesh m = make_example_sheet("flat");
  const UvLocator loc(m);
  Rng rng(1);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d uv(rng.uniform(), rng.uniform());
    const auto p = loc.world_point(uv);
    ASSERT_TRUE(p);
    EXPECT_NEAR(p->x(), (uv.x() - 0.5) * m.width, 1e-12);
    EXPECT_NEAR(p->y(), (uv.y() - 0.5) * m.height, 1e-12);
  }
  EXPECT_FALSE(loc.world_point({1.2, 0.5}));
}

TEST(Geometry, BvhFindsTheFirstHit) {
  const SheetMesh m = make_example_sheet("flat");
  const MeshBvh bvh(m);
  const auto hit = bvh.first_hit({0.01, 0.02, 1.0}, {0, 0, -1}, 0.0, 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 1.0, 1e-12);
  EXPECT_FALSE(bvh.first_hit({0.5, 0.5, 1.0}, {0, 0, -1}, 0.0, 10.0));
}

TEST(Geometry, NormalsPointToThePrintedSide) {
  const SheetMesh m = make_example_sheet("flat");
  const Eigen::MatrixX3d n = vertex_normals(m);
  EXPECT_NEAR(n.col(2).minCoeff(), 1.0, 1e-12);
}

TEST(RestingPose, FlatSheetRestsOnItsPlane) {
  const Stage s = find_resting_pose(make_example_sheet("flat"));
  EXPECT_TRUE(s.flat_sheet);
  EXPECT_NEAR(s.up.z(), 1.0, 1e-12);
  EXPECT_NEAR(s.origin.z(), 0.0, 1e-12);
}

TEST(RestingPose, CylinderRestsOnItsLowLine) {
  const SheetMesh m = make_example_sheet("cylinder");
  const Stage s = find_resting_pose(m);
  EXPECT_FALSE(s.flat_sheet);
  EXPECT_TRUE(s.stable);
  EXPECT_NEAR(s.up.z(), 1.0, 1e-9);
  EXPECT_NEAR(s.origin.z(), m.positions.col(2).minCoeff(), 1e-9);
}

TEST(RestingPose, UpsideDownBumpTurnsOverToAStablePose) {
  SheetMesh m = make_example_sheet("bump");
  m.positions.col(2) *= -1.0;  // bump pointing down: the sheet cannot rest on the bump's tip
  const Stage s = find_resting_pose(m);
  EXPECT_TRUE(s.stable);
  // The centre of mass projects inside the support polygon, and every vertex is above the plane.
  const Eigen::VectorXd h = (m.positions.rowwise() - s.origin.transpose()) * s.up;
  EXPECT_GE(h.minCoeff(), -1e-9);
  EXPECT_LT(s.up.z(), 0.999);  // tilted: resting on the bump and one edge
}

TEST(Rng, RandintCoversRangesWiderThanHalfTheInts) {
  // b - a + 1 is formed in 64 bits: over [0, INT_MAX] and over every int, the width does not
  // overflow an int (which gave draws outside the range), and the draws spread over it.
  Rng rng(7, "randint");
  for (const auto& [a, b] :
       {std::pair{0, INT_MAX}, std::pair{INT_MIN, INT_MAX}, std::pair{-5, 5}}) {
    int low = INT_MAX, high = INT_MIN;
    for (int k = 0; k < 2000; ++k) {
      const int v = rng.randint(a, b);
      ASSERT_GE(v, a);
      ASSERT_LE(v, b);
      low = std::min(low, v);
      high = std::max(high, v);
    }
    // 2000 uniform draws: the extremes lie within 1% of the width of the ends (fails with
    // probability about 2 e^-20).
    const double width = static_cast<double>(b) - a;
    EXPECT_LT(low - static_cast<double>(a), 0.01 * width + 1) << a << ".." << b;
    EXPECT_LT(static_cast<double>(b) - high, 0.01 * width + 1) << a << ".." << b;
  }
}

}  // namespace
}  // namespace papersim::scenegen
