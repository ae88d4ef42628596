#include "collision/shapes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "collision/errors.hpp"
#include "validation/compare.hpp"

namespace pc = papersim::collision;
namespace pv = papersim::validation;

namespace {

using Triangle = std::array<Eigen::Vector3d, 3>;

double unsigned_distance(const Eigen::Vector3d& p, const std::vector<Triangle>& tris) {
  double best = 1e300;
  for (const Triangle& t : tris)
    best = std::min(best, (p - pv::closest_point_on_triangle(p, t[0], t[1], t[2])).norm());
  return best;
}

/// The gable prism as triangles (exact: it is a polyhedron).
std::vector<Triangle> gable_triangles(double w, double h, double l) {
  const double x0 = -l / 2, x1 = l / 2;
  const Eigen::Vector3d a0(x0, -w, 0), b0(x0, w, 0), c0(x0, 0, h);
  const Eigen::Vector3d a1(x1, -w, 0), b1(x1, w, 0), c1(x1, 0, h);
  return {{a0, c0, b0}, {a1, b1, c1}, {a0, b0, b1}, {a0, b1, a1},
          {b0, c0, c1}, {b0, c1, b1}, {c0, a0, a1}, {c0, a1, c1}};
}

std::vector<Triangle> box_triangles(const Eigen::Vector3d& e) {
  std::vector<Triangle> tris;
  for (int axis = 0; axis < 3; ++axis)
    for (double s : {-1.0, 1.0}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      Eigen::Vector3d q[4];
      for (int k = 0; k < 4; ++k) {
        q[k][axis] = s * e[axis];
        q[k][u] = ((k == 1 || k == 2) ? 1 : -1) * e[u];
        q[k][v] = (k >= 2 ? 1 : -1) * e[v];
      }
      tris.push_back({q[0], q[1], q[2]});
      tris.push_back({q[0], q[2], q[3]});
    }
  return tris;
}

/// Checks |phi| against a brute-force polyhedron distance and the gradient against a central
/// difference at random points around the shape.
void check_polyhedron(const pc::Shape& s, const std::vector<Triangle>& tris) {
  std::mt19937 rng(7);
  pc::Aabb b = pc::shape_bounds(s);
  b.inflate(0.02);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d p =
        b.lo + (b.hi - b.lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    Eigen::Vector3d g;
    const double d = pc::shape_distance(s, p, &g);
    ASSERT_NEAR(std::abs(d), unsigned_distance(p, tris), 1e-12) << p.transpose();
    ASSERT_NEAR(g.norm(), 1.0, 1e-12);
    const double h = 1e-7;
    Eigen::Vector3d fd;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(k) * h;
      fd[k] =
          (pc::shape_distance(s, p + e, nullptr) - pc::shape_distance(s, p - e, nullptr)) / (2 * h);
    }
    // The field is smooth except on the medial axis: count disagreements, allow a few.
    if ((fd - g).norm() > 1e-5) {
      static int kinks = 0;
      ASSERT_LT(++kinks, 40) << "gradient mismatch at " << p.transpose();
    }
  }
}

}  // namespace

TEST(Shapes, BoxMatchesPolyhedronDistance) {
  pc::Shape s;
  s.kind = pc::ShapeKind::box;
  s.half_extents = {0.03, 0.02, 0.01};
  check_polyhedron(s, box_triangles(s.half_extents));
  EXPECT_NEAR(pc::shape_distance(s, {0, 0, 0}, nullptr), -0.01, 1e-15);
}

TEST(Shapes, GableMatchesPolyhedronDistance) {
  pc::Shape s;
  s.kind = pc::ShapeKind::gable;
  s.half_width = 0.04;
  s.height = 0.03;
  s.length = 0.2;
  check_polyhedron(s, gable_triangles(s.half_width, s.height, s.length));
  Eigen::Vector3d g;
  EXPECT_NEAR(pc::shape_distance(s, {0.0, 0.0, 0.05}, &g), 0.02, 1e-15);  // above the ridge
  EXPECT_NEAR((g - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-15);
}

TEST(Shapes, RoundShapes) {
  pc::Shape s;
  Eigen::Vector3d g;
  s.kind = pc::ShapeKind::sphere;
  s.radius = 0.05;
  EXPECT_NEAR(pc::shape_distance(s, {0.03, 0.04, 0.12}, &g), 0.13 - 0.05, 1e-15);
  EXPECT_NEAR((g - Eigen::Vector3d(0.03, 0.04, 0.12) / 0.13).norm(), 0.0, 1e-15);
  s.kind = pc::ShapeKind::cylinder;
  s.length = 0.2;
  EXPECT_NEAR(pc::shape_distance(s, {0.05, 0.0, 0.08}, &g), 0.03, 1e-15);  // side
  EXPECT_NEAR(pc::shape_distance(s, {0.13, 0.0, 0.01}, &g), 0.03, 1e-15);  // cap
  EXPECT_NEAR((g - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-15);
  EXPECT_NEAR(pc::shape_distance(s, {0.13, 0.0, 0.09}, &g), 0.05, 1e-15);  // rim: 3-4-5
  EXPECT_NEAR(pc::shape_distance(s, {0.0, 0.0, 0.0}, &g), -0.05, 1e-15);
  s.kind = pc::ShapeKind::capsule;
  EXPECT_NEAR(pc::shape_distance(s, {0.13, 0.0, 0.0}, &g), 0.03, 1e-15);  // tip at x = 0.1
  EXPECT_NEAR(pc::shape_distance(s, {0.0, 0.06, 0.0}, &g), 0.01, 1e-15);
  EXPECT_NEAR((g - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-15);
}

TEST(Shapes, InvalidDimensionsNameTheField) {
  pc::Shape s;
  s.kind = pc::ShapeKind::gable;
  s.height = -1.0;
  try {
    pc::AnalyticCollider c(s);
    FAIL() << "expected ColliderError";
  } catch (const pc::ColliderError& e) {
    EXPECT_NE(std::string(e.what()).find("height"), std::string::npos) << e.what();
  }
  s.kind = pc::ShapeKind::capsule;
  s.radius = 0.1;
  s.length = 0.1;
  EXPECT_THROW(pc::AnalyticCollider{s}, pc::ColliderError);
}

// Corners and edges of the polyhedra: on the surface, each corner on 3 edges (both solids are
// simple polyhedra), and Euler's V - E + F = 2 with 6 (box) and 5 (gable) faces, so no face
// diagonal or missing edge slips in.
TEST(Shapes, PolytopeFeaturesAreTheCornersAndEdges) {
  pc::Shape box;
  box.kind = pc::ShapeKind::box;
  box.half_extents = {0.03, 0.02, 0.01};
  pc::Shape gable;
  gable.kind = pc::ShapeKind::gable;
  gable.half_width = 0.04;
  gable.height = 0.03;
  gable.length = 0.2;
  for (const auto& [shape, faces] : {std::pair{box, 6}, std::pair{gable, 5}}) {
    const pc::PolytopeFeatures f = pc::polytope_features(shape);
    const int v = static_cast<int>(f.corners.size()), e = static_cast<int>(f.edges.size());
    EXPECT_EQ(v - e + faces, 2);
    std::vector<int> degree(v, 0);
    for (const auto& c : f.corners) EXPECT_NEAR(pc::shape_distance(shape, c, nullptr), 0.0, 1e-15);
    for (const auto& [a, b] : f.edges) {
      ++degree[a];
      ++degree[b];
      EXPECT_NEAR(pc::shape_distance(shape, 0.5 * (f.corners[a] + f.corners[b]), nullptr), 0.0,
                  1e-15);
    }
    for (int d : degree) EXPECT_EQ(d, 3);
  }
  pc::Shape sphere;
  EXPECT_TRUE(pc::polytope_features(sphere).corners.empty());
}
