// Exact self-intersection counting (collision/self_intersection). The meshes with known answers
// are the metrics tests' (header-only, Eigen alone).
#include "collision/self_intersection.hpp"

#include <gtest/gtest.h>

#include "../validation/test_meshes.hpp"

namespace papersim::collision {
namespace {

using validation::test::PI;

Eigen::MatrixX3d rows(std::initializer_list<Eigen::RowVector3d> points) {
  Eigen::MatrixX3d p(static_cast<Eigen::Index>(points.size()), 3);
  Eigen::Index i = 0;
  for (const auto& row : points) p.row(i++) = row;
  return p;
}

TEST(SelfIntersection, TwoCrossingTrianglesAreOnePair) {
  // A horizontal triangle and a vertical one piercing it; no shared vertex.
  const Eigen::MatrixX3d p =
      rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -0.5}, {0.3, 0.2, 0.5}, {0.2, 0.3, 0.5}});
  Eigen::MatrixX3i f(2, 3);
  f << 0, 1, 2, 3, 4, 5;
  const SelfIntersections s = find_self_intersections(p, f);
  EXPECT_EQ(s.count(), 1);
  EXPECT_EQ(s.disjoint_pairs, 1);
  EXPECT_EQ(s.pairs(0, 0), 0);
  EXPECT_EQ(s.pairs(0, 1), 1);
  EXPECT_EQ(count_self_intersections(p, f), 1);
}

TEST(SelfIntersection, SeparatedAndTouchingTriangles) {
  Eigen::MatrixX3d p =
      rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, 0.1}, {0.3, 0.2, 0.5}, {0.2, 0.3, 0.5}});
  Eigen::MatrixX3i f(2, 3);
  f << 0, 1, 2, 3, 4, 5;
  EXPECT_EQ(count_self_intersections(p, f), 0);  // hovering 0.1 above
  p(3, 2) = 0.0;                                 // a corner now rests on the other: touching
  EXPECT_EQ(count_self_intersections(p, f), 1);
}

TEST(SelfIntersection, SharedVertexCountsOnlyBeyondIt) {
  // Triangles (s, a, b) and (s, c, d) share s. First: second leaves s upwards -> no contact.
  Eigen::MatrixX3d p = rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 1}, {0.2, 0.7, 1}});
  Eigen::MatrixX3i f(2, 3);
  f << 0, 1, 2, 0, 3, 4;
  EXPECT_EQ(count_self_intersections(p, f), 0);
  // Now the second dips through the first: its edge cd crosses the plane inside the first.
  p.row(3) << 0.4, 0.3, -0.5;
  p.row(4) << 0.3, 0.4, 0.5;
  const SelfIntersections s = find_self_intersections(p, f);
  EXPECT_EQ(s.count(), 1);
  EXPECT_EQ(s.vertex_pairs, 1);
  // Coplanar and overlapping beyond s.
  p.row(3) << 0.5, 0.1, 0;
  p.row(4) << 0.1, 0.5, 0;
  EXPECT_EQ(count_self_intersections(p, f), 1);
  // Coplanar, on the other side of s: only s in common.
  p.row(3) << -0.5, -0.1, 0;
  p.row(4) << -0.1, -0.5, 0;
  EXPECT_EQ(count_self_intersections(p, f), 0);
}

TEST(SelfIntersection, SharedEdgeCountsOnlyWhenFoldedFlatOntoItself) {
  // Triangles (p, q, a) and (q, p, b) share pq.
  Eigen::MatrixX3d p = rows({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}});
  Eigen::MatrixX3i f(2, 3);
  f << 0, 1, 2, 1, 0, 3;
  EXPECT_EQ(count_self_intersections(p, f), 0);  // flat, opposite sides
  p.row(3) << 0.5, 1e-9, 1;                      // folded nearly shut, not flat
  EXPECT_EQ(count_self_intersections(p, f), 0);
  p.row(3) << 0.3, 0.5, 0;  // folded flat onto the first
  const SelfIntersections s = find_self_intersections(p, f);
  EXPECT_EQ(s.count(), 1);
  EXPECT_EQ(s.edge_pairs, 1);
}

TEST(SelfIntersection, DegenerateTriangleIsTestedThroughItsEdges) {
  // The second triangle is collinear (a needle) and pierces the first.
  const Eigen::MatrixX3d p =
      rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -1}, {0.2, 0.2, 0.5}, {0.2, 0.2, 1}});
  Eigen::MatrixX3i f(2, 3);
  f << 0, 1, 2, 3, 4, 5;
  EXPECT_EQ(count_self_intersections(p, f), 1);
}

TEST(SelfIntersection, FoldedSheetIntersectsOnlyWhenPushedThrough) {
  const validation::test::Grid g = validation::test::make_grid(21, 11, 0.2, 0.1);
  const double a = 0.1;
  EXPECT_EQ(count_self_intersections(validation::test::flat_positions(g.material), g.faces), 0);
  // Folded by 170 degrees the halves approach (8.7 mm apart at the far edge) but stay apart.
  // (A static test cannot see that a fold by 200 degrees went through: it is a fold by -160.)
  Eigen::MatrixX3d p = validation::test::folded_positions(g.material, a, 170 * PI / 180);
  EXPECT_EQ(count_self_intersections(p, g.faces), 0);
  // Push one vertex of the upper half 5 mm below the lower half: its 6 faces pierce it.
  p(g.index(15, 5), 2) = -0.005;
  const SelfIntersections s = find_self_intersections(p, g.faces);
  EXPECT_GT(s.count(), 0);
  EXPECT_EQ(s.count(), s.disjoint_pairs);
}

TEST(SelfIntersection, RejectsBadInput) {
  const Eigen::MatrixX3d p = rows({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  Eigen::MatrixX3i f(1, 3);
  f << 0, 1, 3;
  EXPECT_THROW(count_self_intersections(p, f), std::invalid_argument);
}

}  // namespace
}  // namespace papersim::collision
