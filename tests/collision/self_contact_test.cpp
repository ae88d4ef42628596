// Self-contact geometry: exact distances against brute-force sampling, their derivatives
// against finite differences, the broad phase against brute force, and Additive CCD.
#include "collision/self_contact.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>

using namespace papersim::collision;

namespace {

Eigen::Vector3d random_point(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

/// Smallest distance from p to the triangle sampled on a barycentric grid of n x n.
double sampled_point_triangle(const PairPoints& x, int n) {
  double best = INFINITY;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double a = double(i) / n, b = double(j) / n;
      best = std::min(best, (x[0] - (x[1] + a * (x[2] - x[1]) + b * (x[3] - x[1]))).norm());
    }
  return best;
}

double sampled_edge_edge(const PairPoints& x, int n) {
  double best = INFINITY;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double s = double(i) / n, t = double(j) / n;
      best = std::min(best, ((x[0] + s * (x[1] - x[0])) - (x[2] + t * (x[3] - x[2]))).norm());
    }
  return best;
}

double diameter(const PairPoints& x) {
  double d = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) d = std::max(d, (x[i] - x[j]).norm());
  return d;
}

/// Central differences of distance_squared (stencil fixed) against its gradient and Hessian.
/// Step 1e-6 on coordinates of order 1: truncation O(h^2) and round-off O(1e-16 / h) both
/// below 1e-8 relative.
void check_stencil_derivatives(const DistanceStencil& s, const PairPoints& x) {
  Vector12d g;
  Matrix12d H;
  distance_squared_derivatives(s, x, g, &H);
  Vector12d g_fd;
  Matrix12d H_fd;
  const double h = 1e-6;
  for (int i = 0; i < 12; ++i) {
    PairPoints xp = x, xm = x;
    xp[i / 3][i % 3] += h;
    xm[i / 3][i % 3] -= h;
    g_fd[i] = (distance_squared(s, xp) - distance_squared(s, xm)) / (2 * h);
    Vector12d gp, gm;
    distance_squared_derivatives(s, xp, gp, nullptr);
    distance_squared_derivatives(s, xm, gm, nullptr);
    H_fd.col(i) = (gp - gm) / (2 * h);
  }
  EXPECT_LT((g - g_fd).norm(), 1e-7 * std::max(1.0, g.norm())) << "type " << int(s.type);
  EXPECT_LT((H - H_fd).norm(), 1e-6 * std::max(1.0, H.norm())) << "type " << int(s.type);
  EXPECT_LT((H - H.transpose()).norm(), 1e-12 * std::max(1.0, H.norm()));
}

}  // namespace

TEST(SelfContactDistance, PointTriangleMatchesSampling) {
  // Points all around the triangle, so that every distance type occurs. With an n-grid, the
  // sampled minimum exceeds the exact one by at most the grid spacing (diameter / n).
  std::mt19937 rng(5);
  const int n = 300;
  std::map<DistanceType, int> seen;
  for (int k = 0; k < 300; ++k) {
    PairPoints x = {random_point(rng, 1.5), random_point(rng, 1), random_point(rng, 1),
                    random_point(rng, 1)};
    const double exact = std::sqrt(point_triangle_distance_squared(x));
    const double sampled = sampled_point_triangle(x, n);
    EXPECT_LE(exact, sampled + 1e-12);
    EXPECT_LE(sampled - exact, diameter(x) / n);
    ++seen[point_triangle_stencil(x).type];
  }
  EXPECT_GT(seen[DistanceType::point_point], 0);
  EXPECT_GT(seen[DistanceType::point_edge], 0);
  EXPECT_GT(seen[DistanceType::point_triangle], 0);
}

TEST(SelfContactDistance, EdgeEdgeMatchesSampling) {
  std::mt19937 rng(6);
  const int n = 400;
  std::map<DistanceType, int> seen;
  for (int k = 0; k < 300; ++k) {
    PairPoints x = {random_point(rng, 1), random_point(rng, 1), random_point(rng, 1),
                    random_point(rng, 1)};
    const double exact = std::sqrt(edge_edge_distance_squared(x));
    const double sampled = sampled_edge_edge(x, n);
    EXPECT_LE(exact, sampled + 1e-12);
    EXPECT_LE(sampled - exact, diameter(x) / n);
    ++seen[edge_edge_stencil(x).type];
  }
  EXPECT_GT(seen[DistanceType::point_point], 0);
  EXPECT_GT(seen[DistanceType::point_edge], 0);
  EXPECT_GT(seen[DistanceType::edge_edge], 0);
}

TEST(SelfContactDistance, ParallelAndDegenerateEdges) {
  const Eigen::Vector3d a0(0, 0, 0), a1(1, 0, 0);
  // Parallel, overlapping: constant distance 0.1 along the overlap.
  PairPoints x = {a0, a1, Eigen::Vector3d(0.5, 0.1, 0), Eigen::Vector3d(1.5, 0.1, 0)};
  EXPECT_NEAR(std::sqrt(edge_edge_distance_squared(x)), 0.1, 1e-15);
  EXPECT_NE(edge_edge_stencil(x).type, DistanceType::edge_edge);
  // Parallel, disjoint along the line: endpoint to endpoint.
  x = {a0, a1, Eigen::Vector3d(2, 0.1, 0), Eigen::Vector3d(3, 0.1, 0)};
  EXPECT_NEAR(std::sqrt(edge_edge_distance_squared(x)), std::hypot(1.0, 0.1), 1e-15);
  EXPECT_EQ(edge_edge_stencil(x).type, DistanceType::point_point);
  // Anti-parallel and nearly parallel (1e-9 rad): within round-off of the parallel value.
  x = {a0, a1, Eigen::Vector3d(1.5, 0.1, 0), Eigen::Vector3d(0.5, 0.1 + 1e-9, 0)};
  EXPECT_NEAR(std::sqrt(edge_edge_distance_squared(x)), 0.1, 1e-9);
  // Collinear segments of a rotated straight boundary (found in a simulated strip): round-off
  // makes them "nearly parallel" and puts the line-line closest points inside both, at line
  // distance ~1e-12; the segment distance is the 7.5 mm gap between them.
  std::mt19937 rng(4);
  int wrong = 0;
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Matrix3d R = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const Eigen::Vector3d o = random_point(rng, 0.3);
    PairPoints c = {o + R * Eigen::Vector3d(0.2775, 0, 0), o + R * Eigen::Vector3d(0.285, 0, 0),
                    o + R * Eigen::Vector3d(0.2925, 0, 0), o + R * Eigen::Vector3d(0.3, 0, 0)};
    for (auto& p : c) p += random_point(rng, 1e-10);  // the noise of a simulated state
    wrong += std::abs(std::sqrt(edge_edge_distance_squared(c)) - 0.0075) > 1e-9;
  }
  EXPECT_EQ(wrong, 0);
  const PairPoints found = {
      Eigen::Vector3d(0.15834328594928068, 0.002893168993161133, 0.20453000012211286),
      Eigen::Vector3d(0.16577024128655374, 0.0039373597683123752, 0.20453000000392274),
      Eigen::Vector3d(0.17319719662630398, 0.004981550544265907, 0.20452999996880733),
      Eigen::Vector3d(0.18062415196645487, 0.0060257413224608447, 0.20452999998376886)};
  EXPECT_NEAR(std::sqrt(edge_edge_distance_squared(found)), 0.0075, 1e-9);
  // A degenerate (zero-length) edge is a point.
  x = {a0, a1, Eigen::Vector3d(0.3, 0.2, 0.1), Eigen::Vector3d(0.3, 0.2, 0.1)};
  EXPECT_NEAR(std::sqrt(edge_edge_distance_squared(x)), std::hypot(0.2, 0.1), 1e-15);
  // A collinear (zero-area) triangle is measured through its edges.
  x = {Eigen::Vector3d(0.5, 0.3, 0), a0, Eigen::Vector3d(0.5, 0, 0), a1};
  EXPECT_NEAR(std::sqrt(point_triangle_distance_squared(x)), 0.3, 1e-15);
}

TEST(SelfContactDistance, DerivativesOfEveryTypeMatchFiniteDifferences) {
  const Eigen::Vector3d t0(0, 0, 0), t1(1, 0.1, 0.05), t2(0.2, 0.9, -0.1);
  std::map<DistanceType, int> checked;
  // Point-triangle pairs: above the face, beside an edge, beyond a corner.
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.3, 0.3, 0.4), Eigen::Vector3d(0.5, -0.4, 0.2),
                                   Eigen::Vector3d(-0.3, -0.2, 0.3)}) {
    const PairPoints x = {p, t0, t1, t2};
    const DistanceStencil s = point_triangle_stencil(x);
    check_stencil_derivatives(s, x);
    ++checked[s.type];
  }
  // Edge-edge pairs: crossing (line-line), one end beside the other edge, end to end.
  const PairPoints crossing = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0),
                               Eigen::Vector3d(0.5, -0.5, 0.3), Eigen::Vector3d(0.4, 0.6, 0.2)};
  const PairPoints end_side = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0),
                               Eigen::Vector3d(0.5, 0.3, 0.3), Eigen::Vector3d(0.4, 1.6, 0.2)};
  const PairPoints end_end = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0),
                              Eigen::Vector3d(1.5, 0.3, 0.3), Eigen::Vector3d(2.4, 1.6, 0.2)};
  for (const PairPoints& x : {crossing, end_side, end_end}) {
    const DistanceStencil s = edge_edge_stencil(x);
    check_stencil_derivatives(s, x);
    ++checked[s.type];
  }
  EXPECT_EQ(checked[DistanceType::point_triangle], 1);
  EXPECT_EQ(checked[DistanceType::point_edge], 2);
  EXPECT_EQ(checked[DistanceType::point_point], 2);
  EXPECT_EQ(checked[DistanceType::edge_edge], 1);
}

TEST(SelfContactDistance, ClosestPointWeightsGiveTheDistanceVector) {
  std::mt19937 rng(8);
  for (int k = 0; k < 100; ++k) {
    PairPoints x = {random_point(rng, 1), random_point(rng, 1), random_point(rng, 1),
                    random_point(rng, 1)};
    for (bool ee : {false, true}) {
      const DistanceStencil s = ee ? edge_edge_stencil(x) : point_triangle_stencil(x);
      const Eigen::Vector4d w = closest_point_weights(s, x);
      Eigen::Vector3d r = Eigen::Vector3d::Zero();
      for (int i = 0; i < 4; ++i) r += w[i] * x[i];
      EXPECT_NEAR(r.squaredNorm(), distance_squared(s, x), 1e-12);
      EXPECT_NEAR(w.sum(), 0.0, 1e-12) << "r is a difference of two convex combinations";
    }
  }
}

TEST(SelfContactDistance, MollifierDerivatives) {
  // Nearly parallel edges (sin^2 angle 2.5e-4 < 1e-3): the mollifier is in its smooth ramp.
  const PairPoints x = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.01, 0.012),
                        Eigen::Vector3d(0.2, 0.3, 0.1), Eigen::Vector3d(1.1, 0.31, 0.1)};
  const double eps = edge_edge_mollifier_threshold(1.0, 0.9);
  Vector12d g;
  Matrix12d H;
  const double m = edge_edge_mollifier(x, eps, &g, &H);
  EXPECT_GT(m, 0.0);
  EXPECT_LT(m, 1.0);
  const double h = 1e-7;
  for (int i = 0; i < 12; ++i) {
    PairPoints xp = x, xm = x;
    xp[i / 3][i % 3] += h;
    xm[i / 3][i % 3] -= h;
    Vector12d gp, gm;
    const double fp = edge_edge_mollifier(xp, eps, &gp, nullptr),
                 fm = edge_edge_mollifier(xm, eps, &gm, nullptr);
    EXPECT_NEAR((fp - fm) / (2 * h), g[i], 1e-6 * g.norm());
    EXPECT_LT(((gp - gm) / (2 * h) - H.col(i)).norm(), 1e-5 * H.norm());
  }
  // Far from parallel it is exactly 1 with zero derivatives.
  const PairPoints crossing = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                               Eigen::Vector3d(0.5, -0.5, 0.1), Eigen::Vector3d(0.5, 0.5, 0.1)};
  EXPECT_EQ(edge_edge_mollifier(crossing, eps, &g, &H), 1.0);
  EXPECT_EQ(g.norm(), 0.0);
}

namespace {

/// Checks find_self_contact_candidates on (F, x0, x1, radius) against every pair's swept boxes:
/// each pair whose boxes come within `radius` in every axis is reported once and no other; every
/// pair closer than `radius` at x0 is among them. Returns the number of point-triangle pairs.
std::size_t check_broad_phase_against_brute_force(const Eigen::MatrixX3i& F,
                                                  const Eigen::VectorXd& x0,
                                                  const Eigen::VectorXd& x1, double radius) {
  const int nv = static_cast<int>(x0.size() / 3);
  const SelfContactMesh mesh = SelfContactMesh::from_faces(F, nv);
  const SelfContactCandidates c = find_self_contact_candidates(mesh, x0, x1, radius);
  std::set<std::array<int, 2>> pt(c.point_triangle.begin(), c.point_triangle.end());
  std::set<std::array<int, 2>> ee(c.edge_edge.begin(), c.edge_edge.end());
  EXPECT_EQ(pt.size(), c.point_triangle.size()) << "no duplicates";
  EXPECT_EQ(ee.size(), c.edge_edge.size()) << "no duplicates";
  auto box = [&](std::initializer_list<int> vs) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (int v : vs) {
      lo = lo.cwiseMin(x0.segment<3>(3 * v)).cwiseMin(x1.segment<3>(3 * v));
      hi = hi.cwiseMax(x0.segment<3>(3 * v)).cwiseMax(x1.segment<3>(3 * v));
    }
    return std::make_pair(lo, hi);
  };
  auto overlap = [&](const std::pair<Eigen::Vector3d, Eigen::Vector3d>& a,
                     const std::pair<Eigen::Vector3d, Eigen::Vector3d>& b) {
    return ((a.first.array() - radius) <= b.second.array()).all() &&
           ((b.first.array() - radius) <= a.second.array()).all();
  };
  size_t expected_pt = 0, expected_ee = 0;
  auto p0 = [&](int v) { return Eigen::Vector3d(x0.segment<3>(3 * v)); };
  for (int v = 0; v < nv; ++v)
    for (int k = 0; k < F.rows(); ++k) {
      if (F(k, 0) == v || F(k, 1) == v || F(k, 2) == v) continue;
      const bool boxes = overlap(box({v}), box({F(k, 0), F(k, 1), F(k, 2)}));
      expected_pt += boxes;
      EXPECT_EQ(boxes, pt.count({{v, k}}) == 1) << v << " " << k;
      const double d = std::sqrt(
          point_triangle_distance_squared({p0(v), p0(F(k, 0)), p0(F(k, 1)), p0(F(k, 2))}));
      if (d < radius) {
        EXPECT_EQ(pt.count({{v, k}}), 1u) << "a close pair is missing";
      }
    }
  for (int a = 0; a < mesh.edges.rows(); ++a)
    for (int b = a + 1; b < mesh.edges.rows(); ++b) {
      const int a0 = mesh.edges(a, 0), a1 = mesh.edges(a, 1), b0 = mesh.edges(b, 0),
                b1 = mesh.edges(b, 1);
      if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) continue;
      const bool boxes = overlap(box({a0, a1}), box({b0, b1}));
      expected_ee += boxes;
      EXPECT_EQ(boxes, ee.count({{a, b}}) == 1) << a << " " << b;
    }
  EXPECT_EQ(expected_pt, pt.size());
  EXPECT_EQ(expected_ee, ee.size());
  return pt.size();
}

/// Faces of an n x m grid of vertices (row-major), two per quad.
Eigen::MatrixX3i grid_faces(int n, int m) {
  Eigen::MatrixX3i F(2 * (n - 1) * (m - 1), 3);
  int f = 0;
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < m; ++j) {
      const int a = i * m + j, b = a + 1, c = a + m, d = c + 1;
      F.row(f++) << a, b, d;
      F.row(f++) << a, d, c;
    }
  return F;
}

}  // namespace

TEST(SelfContactBroadPhase, MatchesBruteForceBoxesAndHoldsEveryClosePair) {
  // A crumpled random sheet: a 12 x 12 grid with random heights folded over itself.
  const int n = 12;
  const Eigen::MatrixX3i F = grid_faces(n, n);
  EXPECT_EQ(SelfContactMesh::from_faces(F, n * n).edges.rows(),
            3 * (n - 1) * (n - 1) + 2 * (n - 1));
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  Eigen::VectorXd x0(3 * n * n), x1(3 * n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double s = double(j) / (n - 1), a = 3.0 * s;  // folded like a spiral
      x0.segment<3>(3 * (i * n + j)) << std::cos(a) * (1 - 0.5 * s), double(i) / (n - 1),
          std::sin(a) * (1 - 0.5 * s) + 0.05 * u(rng);
      x1.segment<3>(3 * (i * n + j)) =
          x0.segment<3>(3 * (i * n + j)) + 0.1 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    }
  EXPECT_GT(check_broad_phase_against_brute_force(F, x0, x1, 0.15), 100u)
      << "the test sheet really comes close to itself";
}

// The energy sums over the candidate pairs in the order of the list, so that order must not
// depend on where the set was found: a run continued from a checkpoint finds its set at the
// checkpoint's positions, the run it continues found its set at other ones. The same crumpled
// sheet, found at x0 and along x0 -> x1 (another grid: other boxes, other cells), gives lists
// that list the pairs they share in one order (each list sorted).
TEST(SelfContactBroadPhase, PairsComeInOneOrderWhereverTheSetWasFound) {
  const int n = 12;
  const Eigen::MatrixX3i F = grid_faces(n, n);
  const SelfContactMesh mesh = SelfContactMesh::from_faces(F, n * n);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  Eigen::VectorXd x0(3 * n * n), x1(3 * n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double s = double(j) / (n - 1), a = 3.0 * s;
      x0.segment<3>(3 * (i * n + j)) << std::cos(a) * (1 - 0.5 * s), double(i) / (n - 1),
          std::sin(a) * (1 - 0.5 * s) + 0.05 * u(rng);
      x1.segment<3>(3 * (i * n + j)) =
          x0.segment<3>(3 * (i * n + j)) + 0.2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    }
  const SelfContactCandidates still = find_self_contact_candidates(mesh, x0, x0, 0.15);
  const SelfContactCandidates swept = find_self_contact_candidates(mesh, x0, x1, 0.15);
  ASSERT_GT(still.point_triangle.size(), 100u);
  ASSERT_GT(swept.point_triangle.size(), still.point_triangle.size()) << "another set";
  // The pairs of the smaller set, in the order the larger one lists them.
  const auto shared_in_order = [](const std::vector<std::array<int, 2>>& of,
                                  const std::vector<std::array<int, 2>>& in) {
    const std::set<std::array<int, 2>> keep(of.begin(), of.end());
    std::vector<std::array<int, 2>> out;
    for (const auto& p : in)
      if (keep.count(p)) out.push_back(p);
    return out;
  };
  EXPECT_EQ(shared_in_order(still.point_triangle, swept.point_triangle), still.point_triangle);
  EXPECT_EQ(shared_in_order(still.edge_edge, swept.edge_edge), still.edge_edge);
  EXPECT_TRUE(std::is_sorted(swept.point_triangle.begin(), swept.point_triangle.end()));
  EXPECT_TRUE(std::is_sorted(swept.edge_edge.begin(), swept.edge_edge.end()));
}

TEST(SelfContactBroadPhase, AStripAlongTheDiagonalOfAHugeBoxMatchesBruteForce) {
  // A 2 x 300 strip of 1 mm faces along the diagonal of a 1 m cube, bent back on itself in
  // the middle so that its two halves lie 0.5 mm apart, and a lone face at the far corner: the
  // grid's cells are about a face's box (3-4 mm), so its extent holds 1.5e7-3e7 of them
  // against a few thousand entries (measured), and the cells' lists are kept sorted rather than
  // dense (BoxGrid); the pairs must be the same.
  const int m = 300, nv = 2 * m + 3;
  Eigen::MatrixX3i F(2 * (m - 1) + 1, 3);
  F << grid_faces(2, m), Eigen::RowVector3i(2 * m, 2 * m + 1, 2 * m + 2);
  const Eigen::Vector3d along = Eigen::Vector3d(1, 1, 1).normalized(),
                        across(1 / std::sqrt(2.0), -1 / std::sqrt(2.0), 0);
  const Eigen::Vector3d normal = along.cross(across);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1e-4, 1e-4);
  Eigen::VectorXd x0(3 * nv), x1(3 * nv);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < m; ++j) {
      const double s = j < m / 2 ? 1e-3 * j : 1e-3 * (m - 1 - j);  // back along the first half
      const double h = j < m / 2 ? 0.0 : 5e-4;
      x0.segment<3>(3 * (i * m + j)) = 0.85 * along + s * along + 1e-3 * i * across + h * normal;
    }
  // A lone 1 mm face at the cube's far corner stretches the grid's extent over the cube.
  x0.segment<3>(3 * 2 * m) << 0, 0, 0;
  x0.segment<3>(3 * (2 * m + 1)) << 1e-3, 0, 0;
  x0.segment<3>(3 * (2 * m + 2)) << 0, 1e-3, 0;
  for (int v = 0; v < nv; ++v)
    x1.segment<3>(3 * v) = x0.segment<3>(3 * v) + Eigen::Vector3d(u(rng), u(rng), u(rng));
  EXPECT_GT(check_broad_phase_against_brute_force(F, x0, x1, 1e-3), 500u)
      << "the halves face each other";
}

TEST(SelfContactCcd, HeadOnPointStopsBeforeTheFace) {
  // A point 1 above a triangle moving down by 2: contact at t = 0.5. Additive CCD stops where
  // 10% of the gap is left (exact relative speed here): t = 0.45.
  const PairPoints x = {Eigen::Vector3d(0.2, 0.2, 1), Eigen::Vector3d(0, 0, 0),
                        Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)};
  PairPoints dx = {Eigen::Vector3d(0, 0, -2), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                   Eigen::Vector3d::Zero()};
  const double t = point_triangle_ccd(x, dx, 1.0);
  EXPECT_NEAR(t, 0.45, 1e-12);
  // Moving away or sideways at constant height: no impact.
  dx[0] = Eigen::Vector3d(0, 0, 2);
  EXPECT_EQ(point_triangle_ccd(x, dx, 1.0), 1.0);
  dx[0] = Eigen::Vector3d(3, 1, 0);
  EXPECT_EQ(point_triangle_ccd(x, dx, 1.0), 1.0);
  dx[0].setZero();
  EXPECT_EQ(point_triangle_ccd(x, dx, 1.0), 1.0) << "no motion";
  // Already touching: no motion allowed.
  PairPoints touching = x;
  touching[0].z() = 0;
  dx[0] = Eigen::Vector3d(0, 0, -1);
  EXPECT_EQ(point_triangle_ccd(touching, dx, 1.0), 0.0);
}

TEST(SelfContactCcd, ParallelEdgesAndDegenerateTriangle) {
  // Parallel edges 1 apart closing at relative speed 2: contact at 0.5.
  const PairPoints x = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                        Eigen::Vector3d(0.2, 0, 1), Eigen::Vector3d(1.2, 0, 1)};
  const PairPoints dx = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                         Eigen::Vector3d(0, 0, -2), Eigen::Vector3d(0, 0, -2)};
  const double t = edge_edge_ccd(x, dx, 1.0);
  EXPECT_LE(t, 0.5);
  EXPECT_GE(t, 0.4);
  EXPECT_GT(edge_edge_distance_squared({x[0], x[1], x[2] + t * dx[2], x[3] + t * dx[3]}), 0.0);
  // A point moving onto a zero-area (collinear) triangle stops short of its segment.
  const PairPoints sliver = {Eigen::Vector3d(0.5, 0, 1), Eigen::Vector3d(0, 0, 0),
                             Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d(1, 0, 0)};
  const PairPoints down = {Eigen::Vector3d(0, 0, -3), Eigen::Vector3d::Zero(),
                           Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  const double ts = point_triangle_ccd(sliver, down, 1.0);
  EXPECT_LE(ts, 1.0 / 3.0);
  EXPECT_GT(ts, 0.25);
}

TEST(SelfContactCcd, ApproachingTrianglesNeverPassContact) {
  // Random triangle pairs driven through each other; the CCD time of impact over all 15
  // vertex-triangle and edge-edge pairs must leave every pair apart at every sampled time up
  // to it (2000 samples), and it must stop them before they cross (the true first contact is
  // bracketed by sampling too).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  int stopped = 0;
  for (int trial = 0; trial < 40; ++trial) {
    std::array<Eigen::Vector3d, 6> x, dx;
    for (int k = 0; k < 3; ++k) {
      x[k] = Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
      x[3 + k] = Eigen::Vector3d(u(rng), u(rng), 1.0 + 0.3 * u(rng));
      dx[k] = 0.2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      dx[3 + k] = Eigen::Vector3d(0.3 * u(rng), 0.3 * u(rng), -2.5 + 0.5 * u(rng));
    }
    auto pairs_min = [&](double t) {
      std::array<Eigen::Vector3d, 6> y;
      for (int k = 0; k < 6; ++k) y[k] = x[k] + t * dx[k];
      double d2 = INFINITY;
      for (int a = 0; a < 2; ++a) {
        const int o = 3 * a, q = 3 * (1 - a);
        for (int k = 0; k < 3; ++k)
          d2 = std::min(d2, point_triangle_distance_squared({y[o + k], y[q], y[q + 1], y[q + 2]}));
      }
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          d2 = std::min(
              d2, edge_edge_distance_squared({y[i], y[(i + 1) % 3], y[3 + j], y[3 + (j + 1) % 3]}));
      return std::sqrt(d2);
    };
    double toi = 1.0;
    for (int a = 0; a < 2; ++a) {
      const int o = 3 * a, q = 3 * (1 - a);
      for (int k = 0; k < 3; ++k)
        toi = point_triangle_ccd({x[o + k], x[q], x[q + 1], x[q + 2]},
                                 {dx[o + k], dx[q], dx[q + 1], dx[q + 2]}, toi);
    }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int i1 = (i + 1) % 3, j1 = 3 + (j + 1) % 3;
        toi =
            edge_edge_ccd({x[i], x[i1], x[3 + j], x[j1]}, {dx[i], dx[i1], dx[3 + j], dx[j1]}, toi);
      }
    double first_contact = 1.0;
    for (int s = 0; s <= 2000; ++s)
      if (pairs_min(s / 2000.0) < 1e-3) {
        first_contact = s / 2000.0;
        break;
      }
    for (int s = 0; s <= 2000; ++s)
      EXPECT_GT(pairs_min(toi * s / 2000.0), 0.0) << "trial " << trial;
    if (first_contact < 1.0) {
      EXPECT_LE(toi, first_contact) << "trial " << trial;
      ++stopped;
    }
  }
  EXPECT_GT(stopped, 10) << "most trials drive the triangles into contact";
}
