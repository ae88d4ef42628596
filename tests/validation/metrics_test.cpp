// Known-answer tests of the isometry, developability and quality metrics.
#include "validation/metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "remesh/sheet_generator.hpp"
#include "remesh/sheet_io.hpp"
#include "test_meshes.hpp"

namespace papersim::validation {
namespace {

using test::PI;
using test::ROUNDING;

constexpr double GAUSS_BONNET_TOLERANCE = 1e-9;

MeshMetrics measure(const Eigen::MatrixX2d& material, const Eigen::MatrixX3d& positions,
                    const Eigen::MatrixX3i& faces, MetricsOptions options = {}) {
  return compute_metrics(material, positions, faces, Eigen::MatrixX3d(0, 3), options);
}

TEST(Metrics, FlatSheetIsAllZero) {
  const test::Grid g = test::make_grid(11, 8, 0.2, 0.14);
  const MeshMetrics m = measure(g.material, test::flat_positions(g.material), g.faces);
  EXPECT_EQ(m.vertices, 88);
  EXPECT_EQ(m.faces, 140);
  EXPECT_EQ(m.edges, 10 * 8 + 11 * 7 + 10 * 7);
  EXPECT_EQ(m.boundary_edges, 2 * (10 + 7));
  EXPECT_LT(m.isometry.edge_strain_max, ROUNDING);
  EXPECT_NEAR(m.isometry.s1_max, 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.s2_min, 1.0, ROUNDING);
  EXPECT_LT(std::abs(m.isometry.total_area_change), ROUNDING);
  EXPECT_LT(m.developability.angle_defect_max, ROUNDING);
  EXPECT_LT(m.developability.angle_defect_integral, ROUNDING);
  EXPECT_LT(std::abs(m.developability.gauss_bonnet_residual), GAUSS_BONNET_TOLERANCE);
  EXPECT_EQ(m.developability.euler_characteristic, 1);
  EXPECT_LT(m.developability.covariance_energy, ROUNDING);
  EXPECT_EQ(m.creases.edges, 0);
  EXPECT_EQ(m.creases.lines, 0);
  EXPECT_EQ(m.creases.sharpest_angle_deg, 0.0);
  EXPECT_EQ(m.self_intersections, 0);
  // Right isosceles triangles: 45 degrees, aspect 12 sqrt(3) (1/2) / (2 + sqrt(2))^2.
  EXPECT_NEAR(m.quality.min_angle_deg, 45.0, 1e-9);
  EXPECT_NEAR(m.quality.aspect_min, 6.0 * std::sqrt(3.0) / std::pow(2.0 + std::sqrt(2.0), 2),
              1e-12);
  EXPECT_NEAR(m.quality.edge_length_min, 0.02, 1e-15);
  EXPECT_NEAR(m.quality.edge_length_max, 0.02 * std::sqrt(2.0), 1e-15);
}

// The grid wrapped on a cylinder: every vertex on the cylinder, so edges along the axis keep
// their length and edges across it become chords c = 2 R sin(dphi / 2) < dx. Each grid cell
// stays a planar rectangle (c by dy): the mesh is a prism, developable exactly, with
// dihedral dphi = dx / R across the axial edges and 0 across the others.
TEST(Metrics, CylinderWrapHasZeroDefectAndKnownDihedrals) {
  const double radius = 0.05;
  const test::Grid g = test::make_grid(21, 6, 0.2, 0.1);
  const Eigen::MatrixX3d p = test::cylinder_positions(g.material, radius);
  const double dphi = g.dx / radius;
  const double chord = 2.0 * radius * std::sin(0.5 * dphi);
  const MeshMetrics m = measure(g.material, p, g.faces);

  EXPECT_NEAR(m.isometry.edge_compression_max, 1.0 - chord / g.dx, ROUNDING);
  EXPECT_LT(m.isometry.edge_stretch_max, ROUNDING);
  EXPECT_NEAR(m.isometry.s1_max, 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.s2_min, chord / g.dx, ROUNDING);
  EXPECT_NEAR(m.isometry.area_change_max, chord / g.dx - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.area_change_min, chord / g.dx - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.total_area_change, chord / g.dx - 1.0, ROUNDING);

  EXPECT_LT(m.developability.angle_defect_max, ROUNDING);
  EXPECT_LT(m.developability.angle_defect_integral, 100 * ROUNDING);
  EXPECT_LT(std::abs(m.developability.gauss_bonnet_residual), GAUSS_BONNET_TOLERANCE);
  EXPECT_LT(m.developability.covariance_max, ROUNDING);  // two normals per vertex: rank 2
  EXPECT_NEAR(m.creases.sharpest_angle_deg, dphi * 180.0 / PI, 1e-9);
  EXPECT_EQ(m.creases.edges, 0);  // 11.5 deg < 30 deg

  const MeshTopology t = build_topology(g.faces, static_cast<int>(p.rows()));
  const Eigen::VectorXd strain = edge_strains(g.material, p, t);
  const Eigen::VectorXd dihedral = dihedral_angles(p, g.faces, t);
  const double diagonal = std::hypot(chord, g.dy) / std::hypot(g.dx, g.dy) - 1.0;
  for (Eigen::Index e = 0; e < t.edges.rows(); ++e) {
    const int a = t.edges(e, 0), b = t.edges(e, 1);
    const bool axial = a % g.nx == b % g.nx, across = a / g.nx == b / g.nx;
    const double expected_strain = axial ? 0.0 : across ? chord / g.dx - 1.0 : diagonal;
    EXPECT_NEAR(strain(e), expected_strain, ROUNDING) << "edge " << a << "-" << b;
    const bool interior = t.edge_faces(e, 1) >= 0;
    // Bending towards the normals (+z side up) is positive.
    EXPECT_NEAR(dihedral(e), interior && axial ? dphi : 0.0, 1e-12) << "edge " << a << "-" << b;
  }

  // With a threshold below dphi every interior axial line is a crease running across.
  MetricsOptions low;
  low.crease_angle_deg = 10.0;
  const MeshMetrics c = measure(g.material, p, g.faces, low);
  EXPECT_EQ(c.creases.lines, g.nx - 2);
  EXPECT_EQ(c.creases.junctions, 0);
  EXPECT_NEAR(c.creases.total_length, (g.nx - 2) * 0.1, 1e-12);
  EXPECT_NEAR(c.creases.length_min, 0.1, 1e-12);
  EXPECT_NEAR(c.creases.length_max, 0.1, 1e-12);
}

// Apex defect of a cone: 2 pi - n alpha, alpha = 2 asin(sin(beta) sin(pi / n)) the apex angle
// of one isosceles face (legs = slant, base = chord of the ring). The ring vertices lie on
// rulings through the apex, so the faces between rings are planar trapezoids: zero defect there.
TEST(Metrics, ConeHasKnownApexDefect) {
  const int n = 12;
  const double beta = PI / 3.0;
  const test::Cone c = test::make_cone(n, Eigen::Vector2d(0.05, 0.1), beta);
  const double alpha = 2.0 * std::asin(std::sin(beta) * std::sin(PI / n));
  const double expected = 2.0 * PI - n * alpha;

  const MeshTopology t = build_topology(c.faces, static_cast<int>(c.positions.rows()));
  const Eigen::VectorXd defect = angle_defects(c.positions, c.faces, t);
  EXPECT_NEAR(defect(0), expected, ROUNDING);
  for (int k = 1; k <= n; ++k) EXPECT_NEAR(defect(k), 0.0, ROUNDING) << "ring vertex " << k;

  const MeshMetrics m = measure(c.material, c.positions, c.faces);
  EXPECT_NEAR(m.developability.angle_defect_max, expected, ROUNDING);
  EXPECT_NEAR(m.developability.angle_defect_integral, expected, 10 * ROUNDING);
  EXPECT_LT(std::abs(m.developability.gauss_bonnet_residual), GAUSS_BONNET_TOLERANCE);
  EXPECT_EQ(m.developability.euler_characteristic, 1);
  EXPECT_GT(m.developability.covariance_max, 0.1);  // the apex: normals around a cone
}

// Stretch by (1.1, 0.95) along (x, y): F = diag(1.1, 0.95) everywhere.
TEST(Metrics, StretchedSheetHasKnownStrain) {
  const double sx = 1.1, sy = 0.95;
  const test::Grid g = test::make_grid(9, 7, 0.16, 0.12);
  const Eigen::MatrixX3d p = test::map_positions(
      g.material, [&](double x, double y) { return Eigen::Vector3d(sx * x, sy * y, 0.0); });
  const MeshMetrics m = measure(g.material, p, g.faces);
  const double diagonal = std::hypot(sx * g.dx, sy * g.dy) / std::hypot(g.dx, g.dy) - 1.0;
  const double n_across = (g.nx - 1) * g.ny, n_axial = g.nx * (g.ny - 1),
               n_diagonal = (g.nx - 1) * (g.ny - 1);
  const double mean =
      (n_across * (sx - 1.0) + n_axial * (1.0 - sy) + n_diagonal * std::abs(diagonal)) /
      (n_across + n_axial + n_diagonal);
  EXPECT_NEAR(m.isometry.edge_strain_max, sx - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.edge_stretch_max, sx - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.edge_compression_max, 1.0 - sy, ROUNDING);
  EXPECT_NEAR(m.isometry.edge_strain_p99, sx - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.edge_strain_mean, mean, ROUNDING);
  EXPECT_NEAR(m.isometry.s1_max, sx, ROUNDING);
  EXPECT_NEAR(m.isometry.s2_min, sy, ROUNDING);
  EXPECT_NEAR(m.isometry.stretch_max, sx - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.compression_max, 1.0 - sy, ROUNDING);
  EXPECT_NEAR(m.isometry.stretch_p99, sx - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.area_change_max, sx * sy - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.area_change_min, sx * sy - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.area_change_mean, sx * sy - 1.0, ROUNDING);
  EXPECT_NEAR(m.isometry.total_area_change, sx * sy - 1.0, ROUNDING);
  EXPECT_LT(m.developability.angle_defect_max, ROUNDING);  // planar: still flat
  EXPECT_EQ(m.self_intersections, 0);
}

TEST(Metrics, PrincipalStretchesOfShearAreSorted) {
  // Simple shear x += g y with g = 0.5: s1 s2 = 1, s1 - s2 = g, so s1 = (g + sqrt(g^2 + 4)) / 2.
  const double shear = 0.5;
  const test::Grid g = test::make_grid(3, 3, 0.1, 0.1);
  const Eigen::MatrixX3d p = test::map_positions(
      g.material, [&](double x, double y) { return Eigen::Vector3d(x + shear * y, y, 0.0); });
  const Eigen::MatrixX2d s = principal_stretches(g.material, p, g.faces);
  const double s1 = 0.5 * (shear + std::sqrt(shear * shear + 4.0));
  for (Eigen::Index f = 0; f < s.rows(); ++f) {
    EXPECT_NEAR(s(f, 0), s1, ROUNDING);
    EXPECT_NEAR(s(f, 1), 1.0 / s1, ROUNDING);
  }
}

// Gauss-Bonnet holds for any triangulated disk, whatever the positions.
TEST(Metrics, GaussBonnetResidualOnBumpySheet) {
  const test::Grid g = test::make_grid(31, 23, 0.21, 0.297);
  const Eigen::MatrixX3d p = test::map_positions(g.material, [](double x, double y) {
    return Eigen::Vector3d(x + 0.01 * std::sin(40 * y), y,
                           0.03 * std::sin(30 * x) * std::cos(25 * y));
  });
  const MeshMetrics m = measure(g.material, p, g.faces);
  EXPECT_GT(m.developability.angle_defect_integral, 0.1);
  EXPECT_LT(std::abs(m.developability.gauss_bonnet_residual), GAUSS_BONNET_TOLERANCE);
}

TEST(Metrics, GaussBonnetResidualOnClosedSurfaceAndAnnulus) {
  // Octahedron: chi = 2, each vertex defect 2 pi - 4 (pi / 3) = 2 pi / 3.
  Eigen::MatrixX3d p(6, 3);
  p << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  Eigen::MatrixX3i f(8, 3);
  f << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  const MeshTopology t = build_topology(f, 6);
  const DevelopabilityMetrics d = developability_metrics(p, f, t);
  EXPECT_EQ(d.euler_characteristic, 2);
  EXPECT_NEAR(d.angle_defect_max, 2.0 * PI / 3.0, ROUNDING);
  EXPECT_NEAR(d.angle_defect_integral, 4.0 * PI, ROUNDING);
  EXPECT_LT(std::abs(d.gauss_bonnet_residual), GAUSS_BONNET_TOLERANCE);

  // The cone without its apex fan is an annulus: chi = 0.
  test::Cone c = test::make_cone(10, Eigen::Vector2d(0.05, 0.1), 1.0);
  const Eigen::MatrixX3i ring = c.faces.bottomRows(20);
  const MeshTopology tr = build_topology(ring, static_cast<int>(c.positions.rows()));
  const DevelopabilityMetrics dr = developability_metrics(c.positions, ring, tr);
  EXPECT_EQ(dr.euler_characteristic, 0);
  EXPECT_LT(std::abs(dr.gauss_bonnet_residual), GAUSS_BONNET_TOLERANCE);
}

TEST(Metrics, RejectsBadInput) {
  const test::Grid g = test::make_grid(3, 3, 0.1, 0.1);
  const Eigen::MatrixX3d p = test::flat_positions(g.material);
  Eigen::MatrixX3i out_of_range = g.faces;
  out_of_range(0, 0) = 99;
  EXPECT_THROW(measure(g.material, p, out_of_range), MetricsInputError);
  Eigen::MatrixX3i flipped = g.faces;
  flipped.row(0) << g.faces(0, 0), g.faces(0, 2), g.faces(0, 1);
  EXPECT_THROW(measure(g.material, p, flipped), MetricsInputError);
  Eigen::MatrixX3i tripled(3, 3);
  tripled << 0, 1, 3, 1, 0, 4, 0, 1, 5;
  EXPECT_THROW(build_topology(tripled, 9), MetricsInputError);
  Eigen::MatrixX2d collapsed = g.material;
  collapsed.row(1) = collapsed.row(0);
  EXPECT_THROW(measure(collapsed, p, g.faces), MetricsInputError);
  Eigen::MatrixX3d nan = p;
  nan(2, 2) = std::nan("");
  EXPECT_THROW(measure(g.material, nan, g.faces), MetricsInputError);
}

TEST(Metrics, SheetDataOverloadMatchesArrays) {
  remesh::RectangleOptions r;
  r.nx = 12;
  r.ny = 15;
  r.jitter = 0.3;
  r.triangulation = remesh::Triangulation::random;
  remesh::SheetData sheet;
  sheet.mesh = remesh::make_rectangle(r);
  sheet.positions = test::cylinder_positions(sheet.mesh.material_coords(), 0.1);
  sheet.width = r.width;
  sheet.height = r.height;
  const MeshMetrics from_sheet = compute_metrics(sheet, {}, false);
  const MeshMetrics from_arrays =
      measure(sheet.mesh.material_coords(), sheet.positions, sheet.mesh.faces());
  EXPECT_EQ(metric_fields(from_sheet), metric_fields(from_arrays));
  EXPECT_FALSE(from_sheet.creases.has_plastic_data);
  EXPECT_TRUE(compute_metrics(sheet, {}, true).creases.has_plastic_data);
}

TEST(Metrics, FieldsAreConsistentAcrossWriters) {
  const test::Grid g = test::make_grid(5, 5, 0.1, 0.1);
  const MeshMetrics m =
      measure(g.material, test::folded_positions(g.material, 0.05, PI / 2), g.faces);
  const auto fields = metric_fields(m);
  std::ostringstream header, row, table;
  write_csv_header(header);
  write_csv_row(row, "a,b", m);
  write_table(table, m);
  const auto columns = [](const std::string& line) {
    return std::count(line.begin(), line.end(), ',');
  };
  EXPECT_EQ(columns(header.str()), static_cast<long>(fields.size()));
  EXPECT_EQ(columns(row.str()), static_cast<long>(fields.size()) + 1);  // "a,b" is quoted
  EXPECT_EQ(row.str().rfind("\"a,b\",", 0), 0u);
  const nlohmann::json j = to_json(m);
  EXPECT_EQ(j["creases"]["lines"], 1);
  EXPECT_EQ(j["creases"]["line_lengths"].size(), 1u);
  EXPECT_NEAR(j["creases"]["total_length"].get<double>(), 0.1, 1e-12);
  EXPECT_EQ(j["self_intersection"]["pairs"], 0);
  EXPECT_NE(table.str().find("creases.junctions"), std::string::npos);
  const std::vector<FieldSummary> s = summarize({m, m});
  ASSERT_EQ(s.size(), fields.size());
  for (std::size_t k = 0; k < s.size(); ++k) {
    EXPECT_EQ(s[k].name, fields[k].first);
    EXPECT_NEAR(s[k].mean, fields[k].second, 1e-12 * (1.0 + std::abs(fields[k].second)));
  }
}

}  // namespace
}  // namespace papersim::validation
