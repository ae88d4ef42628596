// Known-answer tests of crease detection, grouping into lines, junctions and plasticity.
#include <gtest/gtest.h>

#include <cmath>

#include "test_meshes.hpp"
#include "validation/metrics.hpp"

namespace papersim::validation {
namespace {

using test::PI;
using test::ROUNDING;

// A 0.2 x 0.1 sheet, 21 x 11 vertices (spacing 0.01), folded up by 90 degrees about x = 0.08,
// a column of vertices: one crease line along the column, of length 0.1 and angle 90 degrees,
// and an isometry (zero strain, zero defect).
struct FoldedSheet : ::testing::Test {
  test::Grid g = test::make_grid(21, 11, 0.2, 0.1);
  double fold_x = 0.08;
  double angle = PI / 2;
  Eigen::MatrixX3d p = test::folded_positions(g.material, fold_x, angle);

  /// Plastic curvature k_xx on the faces touching the fold column, such that the rest
  /// dihedral of a fold edge is `rest`: rest = k_xx (A1 + A2) / L = k_xx dx dy / dy.
  Eigen::MatrixX3d plastic_curvature(double rest) const {
    Eigen::MatrixX3d k = Eigen::MatrixX3d::Zero(g.faces.rows(), 3);
    const int column = static_cast<int>(std::lround(fold_x / g.dx));
    for (Eigen::Index f = 0; f < g.faces.rows(); ++f)
      for (int c = 0; c < 3; ++c)
        if (g.faces(f, c) % g.nx == column) k(f, 0) = rest / g.dx;
    return k;
  }
};

TEST_F(FoldedSheet, OneCreaseOfKnownLengthAndAngle) {
  const MeshMetrics m = compute_metrics(g.material, p, g.faces, Eigen::MatrixX3d(0, 3));
  EXPECT_EQ(m.creases.edges, g.ny - 1);
  EXPECT_EQ(m.creases.lines, 1);
  EXPECT_EQ(m.creases.junctions, 0);
  EXPECT_NEAR(m.creases.total_length, 0.1, ROUNDING);
  EXPECT_NEAR(m.creases.length_median, 0.1, ROUNDING);
  EXPECT_NEAR(m.creases.sharpest_angle_deg, 90.0, 1e-9);
  ASSERT_EQ(m.creases.crease_lines.size(), 1u);
  EXPECT_NEAR(m.creases.crease_lines[0].max_angle_deg, 90.0, 1e-9);
  EXPECT_FALSE(m.creases.crease_lines[0].closed);
  EXPECT_FALSE(m.creases.has_plastic_data);
  EXPECT_EQ(m.creases.plastic_length, 0.0);
  EXPECT_LT(m.isometry.edge_strain_max, ROUNDING);
  EXPECT_LT(m.developability.angle_defect_max, ROUNDING);
  EXPECT_EQ(m.self_intersections, 0);
}

TEST_F(FoldedSheet, ThresholdAboveTheFoldAngleFindsNothing) {
  MetricsOptions options;
  options.crease_angle_deg = 91.0;
  const MeshMetrics m = compute_metrics(g.material, p, g.faces, Eigen::MatrixX3d(0, 3), options);
  EXPECT_EQ(m.creases.lines, 0);
  EXPECT_NEAR(m.creases.sharpest_angle_deg, 90.0, 1e-9);
}

TEST_F(FoldedSheet, PlasticWhenTheRestAngleExceedsTheThreshold) {
  const MeshMetrics plastic = compute_metrics(g.material, p, g.faces, plastic_curvature(PI / 2));
  EXPECT_TRUE(plastic.creases.has_plastic_data);
  EXPECT_NEAR(plastic.creases.plastic_length, 0.1, ROUNDING);
  EXPECT_NEAR(plastic.creases.elastic_length, 0.0, ROUNDING);
  EXPECT_EQ(plastic.creases.plastic_lines, 1);

  // Rest angle 20 degrees < 30: the fold would spring back, so it is elastic.
  const MeshMetrics elastic =
      compute_metrics(g.material, p, g.faces, plastic_curvature(20 * PI / 180));
  EXPECT_NEAR(elastic.creases.plastic_length, 0.0, ROUNDING);
  EXPECT_NEAR(elastic.creases.elastic_length, 0.1, ROUNDING);
  EXPECT_EQ(elastic.creases.plastic_lines, 0);
}

// A tent z = -c (|x - a| + |y - b|): planar on each quadrant, creases along x = a and y = b
// crossing at one vertex. Normals (c sx, c sy, 1) / sqrt(2 c^2 + 1) with signs sx, sy of the
// quadrant, so across either line cos(angle) = 1 / (2 c^2 + 1).
TEST_F(FoldedSheet, PlasticNetworkComesFromThePlasticStateAloneFlatOrFolded) {
  // The fold's plastic state on a flat sheet: no crease in the shape, one plastic line of
  // material length 0.1 in the network; the same on the folded sheet. A rest angle of 50 deg
  // on the fold edges: the plastic faces (two columns) give the next columns of edges 25 deg
  // and the diagonals between them 50 / (2 sqrt 2) = 17.7 deg, below the 30 deg threshold.
  const Eigen::MatrixX3d k = plastic_curvature(50 * PI / 180);
  const MeshMetrics flat =
      compute_metrics(g.material, test::flat_positions(g.material), g.faces, k);
  EXPECT_EQ(flat.creases.edges, 0);
  EXPECT_EQ(flat.creases.plastic_network_lines, 1);
  EXPECT_EQ(flat.creases.plastic_network_edges, g.ny - 1);
  EXPECT_NEAR(flat.creases.plastic_network_length, 0.1, ROUNDING);
  EXPECT_EQ(flat.creases.plastic_network_junctions, 0);
  const MeshMetrics folded = compute_metrics(g.material, p, g.faces, k);
  EXPECT_NEAR(folded.creases.plastic_network_length, 0.1, ROUNDING);
  // Below the threshold (a rest angle of 20 degrees): no plastic network.
  const MeshMetrics weak =
      compute_metrics(g.material, p, g.faces, plastic_curvature(20 * PI / 180));
  EXPECT_EQ(weak.creases.plastic_network_lines, 0);
  EXPECT_EQ(weak.creases.plastic_network_length, 0.0);
}

TEST(Creases, LogNormalGoodnessOfFit) {
  // Lengths at the midpoint quantiles of a log-normal fit it closely: the Kolmogorov-Smirnov
  // distance of n midpoint quantiles to their own distribution is 1 / (2n) when the fitted
  // parameters equal the true ones; estimating them moves it by O(1/n).
  const int n = 200;
  std::vector<double> lognormal, bimodal;
  for (int i = 0; i < n; ++i) {
    const double u = (i + 0.5) / n;
    // Inverse normal CDF by bisection on erfc.
    double lo = -10, hi = 10;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (0.5 * std::erfc(-mid / std::sqrt(2.0)) < u ? lo : hi) = mid;
    }
    lognormal.push_back(std::exp(std::log(0.02) + 0.7 * lo));
    bimodal.push_back(i % 2 ? 0.01 : 0.1);
  }
  const LogNormalFit good = fit_log_normal(lognormal);
  EXPECT_NEAR(good.mean, std::log(0.02), 1e-3);
  EXPECT_NEAR(good.std, 0.7, 0.01);
  EXPECT_LT(good.ks, 3.0 / n);
  // Two spikes: the CDF jumps by 1/2 where the log-normal rises smoothly.
  const LogNormalFit bad = fit_log_normal(bimodal);
  EXPECT_GT(bad.ks, 0.89 / std::sqrt(n)) << "rejected at 5%";
  EXPECT_EQ(fit_log_normal({0.1, 0.2}).ks, 0.0) << "too few lengths to judge";
}

TEST(Creases, TwoCrossingFoldsMeetAtOneJunction) {
  const test::Grid g = test::make_grid(21, 11, 0.2, 0.1);
  const double a = 0.12, b = 0.04, c = 1.0;
  const Eigen::MatrixX3d p = test::map_positions(g.material, [&](double x, double y) {
    return Eigen::Vector3d(x, y, -c * (std::abs(x - a) + std::abs(y - b)));
  });
  const MeshMetrics m = compute_metrics(g.material, p, g.faces, Eigen::MatrixX3d(0, 3));
  const double angle = std::acos(1.0 / (2 * c * c + 1)) * 180.0 / PI;  // 70.53 degrees
  EXPECT_EQ(m.creases.junctions, 1);
  EXPECT_EQ(m.creases.lines, 4);  // lines end at the junction
  EXPECT_EQ(m.creases.edges, (g.nx - 1) + (g.ny - 1));
  const double length = std::sqrt(1 + c * c);  // world length per unit of material length
  EXPECT_NEAR(m.creases.total_length, length * (0.2 + 0.1), 1e-12);
  EXPECT_NEAR(m.creases.length_max, length * 0.12, 1e-12);  // from the junction to x = 0
  EXPECT_NEAR(m.creases.length_min, length * 0.04, 1e-12);  // from the junction to y = 0
  EXPECT_NEAR(m.creases.sharpest_angle_deg, angle, 1e-9);
  EXPECT_LT(std::abs(m.developability.gauss_bonnet_residual), 1e-9);
  EXPECT_EQ(m.self_intersections, 0);
  EXPECT_EQ(m.creases.junction_degrees[1], 1) << "the junction has crease valence 4";
  EXPECT_EQ(m.creases.junction_degrees[0] + m.creases.junction_degrees[2], 0);
}

// A lamp shade: a steep cone (half-angle 30 deg, 12 sides) standing on a flat annulus. The
// rim of the cone is a closed crease of 12 chords, each of dihedral ~60.9 deg; the spokes of
// the cone bend by ~26 deg, under the 40 deg threshold.
TEST(Creases, ClosedRimIsOneClosedLine) {
  const int n = 12;
  test::Cone c = test::make_cone(n, Eigen::Vector2d(0.05, 0.08), PI / 6);
  const double r1 = 0.05 * std::sin(PI / 6), h1 = 0.05 * std::cos(PI / 6);
  for (int k = 0; k < n; ++k) {  // flatten the outer ring onto the rim's plane
    const double phi = 2.0 * PI * k / n, r2 = r1 + 0.03;
    c.positions.row(1 + n + k) << r2 * std::cos(phi), r2 * std::sin(phi), -h1;
  }
  MetricsOptions options;
  options.crease_angle_deg = 40.0;
  const MeshMetrics m =
      compute_metrics(c.material, c.positions, c.faces, Eigen::MatrixX3d(0, 3), options);
  const double tilt = std::atan(h1 / (r1 * std::cos(PI / n)));  // cone face against the plane
  EXPECT_EQ(m.creases.lines, 1);
  EXPECT_EQ(m.creases.edges, n);
  EXPECT_EQ(m.creases.junctions, 0);
  ASSERT_EQ(m.creases.crease_lines.size(), 1u);
  EXPECT_TRUE(m.creases.crease_lines[0].closed);
  EXPECT_NEAR(m.creases.total_length, n * 2.0 * r1 * std::sin(PI / n), ROUNDING);
  EXPECT_NEAR(m.creases.sharpest_angle_deg, tilt * 180.0 / PI, 1e-9);
  EXPECT_LT(std::abs(m.developability.gauss_bonnet_residual), 1e-9);
}

}  // namespace
}  // namespace papersim::validation
