#include "validation/compare.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "remesh/sheet_generator.hpp"

namespace pv = papersim::validation;

namespace {

/// A flat rectangle mesh (material = world xy) with the given grid.
pv::SheetGeometry flat(int nx, int ny, papersim::remesh::Triangulation t) {
  papersim::remesh::RectangleOptions o;
  o.width = 0.1;
  o.height = 0.05;
  o.nx = nx;
  o.ny = ny;
  o.triangulation = t;
  const auto mesh = papersim::remesh::make_rectangle(o);
  pv::SheetGeometry g;
  g.material = mesh.material_coords();
  g.faces = mesh.faces();
  g.positions.resize(g.material.rows(), 3);
  g.positions << g.material, Eigen::VectorXd::Zero(g.material.rows());
  return g;
}

}  // namespace

TEST(CompareSheets, ClosestPointOnTriangleRegions) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(
      pv::closest_point_on_triangle({0.2, 0.2, 3}, a, b, c).isApprox(Eigen::Vector3d(0.2, 0.2, 0)));
  EXPECT_TRUE(pv::closest_point_on_triangle({-1, -1, 0}, a, b, c).isApprox(a));
  EXPECT_TRUE(pv::closest_point_on_triangle({2, -1, 0}, a, b, c).isApprox(b));
  EXPECT_TRUE(
      pv::closest_point_on_triangle({1, 1, 0}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.5, 0)));
  EXPECT_TRUE(
      pv::closest_point_on_triangle({0.5, -2, 1}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0, 0)));
}

TEST(CompareSheets, SameSurfaceDifferentMeshesIsZero) {
  const auto ref = flat(41, 21, papersim::remesh::Triangulation::alternating);
  const auto test = flat(11, 6, papersim::remesh::Triangulation::random);
  const auto d = pv::compare_sheets(ref, test);
  EXPECT_LT(d.rms, 1e-15);
  EXPECT_LT(d.max, 1e-15);
  EXPECT_LT(d.hausdorff, 1e-15);
  EXPECT_EQ(d.outside, 0);
}

TEST(CompareSheets, OffsetAlongTheNormalAndInThePlane) {
  const auto ref = flat(41, 21, papersim::remesh::Triangulation::alternating);
  auto test = flat(11, 6, papersim::remesh::Triangulation::alternating);
  test.positions.col(2).array() += 2e-3;  // lifted by 2 mm: every norm is 2 mm
  auto d = pv::compare_sheets(ref, test);
  EXPECT_NEAR(d.rms, 2e-3, 1e-12);
  EXPECT_NEAR(d.max, 2e-3, 1e-12);
  EXPECT_NEAR(d.hausdorff, 2e-3, 1e-12);
  // Slid 1 mm within its plane: the same points are 1 mm off, but the surfaces nearly overlap
  // (the Hausdorff distance is the 1 mm overhang at the ends only).
  test = flat(11, 6, papersim::remesh::Triangulation::alternating);
  test.positions.col(0).array() += 1e-3;
  d = pv::compare_sheets(ref, test);
  EXPECT_NEAR(d.rms, 1e-3, 1e-12);
  EXPECT_NEAR(d.max, 1e-3, 1e-12);
  EXPECT_NEAR(d.hausdorff, 1e-3, 1e-12);
}

TEST(CompareSheets, BentSheetAgainstItsLinearInterpolation) {
  // Reference: z = x^2 on a fine mesh; test: the coarse mesh's vertices on the same surface.
  // At the test vertices the material-correspondence error is the reference's own
  // interpolation error, at most h_ref^2 / 8 * z'' = (2.5 mm)^2 / 8 * 2.
  auto ref = flat(41, 21, papersim::remesh::Triangulation::alternating);
  auto test = flat(11, 6, papersim::remesh::Triangulation::alternating);
  for (int v = 0; v < ref.positions.rows(); ++v)
    ref.positions(v, 2) = std::pow(ref.positions(v, 0), 2);
  for (int v = 0; v < test.positions.rows(); ++v)
    test.positions(v, 2) = std::pow(test.positions(v, 0), 2);
  const auto d = pv::compare_sheets(ref, test);
  EXPECT_LT(d.max, 2.5e-3 * 2.5e-3 / 8 * 2 + 1e-15);
  // The coarse chords sag by up to (10 mm)^2 / 8 * 2 = 25 micrometres below the fine surface.
  EXPECT_GT(d.hausdorff, 0.5 * 1e-2 * 1e-2 / 4);
  EXPECT_LT(d.hausdorff, 1e-2 * 1e-2 / 4 + 1e-12);
}

TEST(CompareSheets, ARigidMotionLeavesTheShapeErrorZeroAndAShapeChangeSurvivesTheAlignment) {
  // Reference: z = 5 x^2 (a curved sheet, so the alignment is unique). Test: the same surface on
  // a coarser mesh, turned by 0.3 rad about a tilted axis and moved by (30, -20, 5) mm.
  auto ref = flat(41, 21, papersim::remesh::Triangulation::alternating);
  auto test = flat(11, 6, papersim::remesh::Triangulation::random);
  const auto bend = [](pv::SheetGeometry& g) {
    for (int v = 0; v < g.positions.rows(); ++v)
      g.positions(v, 2) = 5 * std::pow(g.positions(v, 0), 2);
  };
  bend(ref);
  bend(test);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.03, -0.02, 0.005);
  const Eigen::MatrixX3d original = test.positions;
  for (int v = 0; v < test.positions.rows(); ++v)
    test.positions.row(v) = (R * original.row(v).transpose() + t).transpose();
  auto d = pv::compare_sheets(ref, test);
  // The test's vertices lie on the reference's fine interpolation to within its chord error,
  // (2.5 mm)^2 / 8 * 10 = 7.8 micrometres; the alignment undoes the motion to that level.
  EXPECT_LT(d.rms_aligned, 8e-6);
  EXPECT_LT(d.max_aligned, 2e-5);
  EXPECT_GT(d.rms, 1e-2);  // the motion moves every point by centimetres
  // Each point's position error is its displacement by the motion (to the chord error).
  double worst = 0;
  for (int v = 0; v < test.positions.rows(); ++v)
    worst = std::max(worst, (test.positions.row(v) - original.row(v)).norm());
  EXPECT_NEAR(d.max, worst, 1e-5);
  // The best rigid motion of exact point sets is the motion itself.
  Eigen::Matrix3d R_fit;
  Eigen::Vector3d t_fit;
  pv::best_rigid_motion(original, test.positions, R_fit, t_fit);
  EXPECT_LT((R_fit - R).norm(), 1e-12);
  EXPECT_LT((t_fit - t).norm(), 1e-12);
  // A change of shape stays: a 1 mm step up on a quarter of the sheet (x in [50, 75] mm, no
  // rigid motion fits it) keeps an RMS shape error of a good part of the step.
  test = flat(11, 6, papersim::remesh::Triangulation::random);
  bend(test);
  for (int v = 0; v < test.positions.rows(); ++v)
    if (test.positions(v, 0) > 0.05 - 1e-9 && test.positions(v, 0) < 0.075 + 1e-9)
      test.positions(v, 2) += 1e-3;
  d = pv::compare_sheets(ref, test);
  EXPECT_GT(d.rms_aligned, 0.25e-3);
  EXPECT_LE(d.rms_aligned, d.rms + 1e-12);  // the alignment never adds error in the RMS sense
}
