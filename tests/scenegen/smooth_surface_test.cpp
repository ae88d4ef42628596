// The smooth render surface: interpolation of the simulated vertices, exact material
// coordinates, planar sheets kept planar, curved sheets approached better than by the mesh.
#include "scenegen/smooth_surface.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "scenegen/errors.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/job.hpp"
#include "test_support.hpp"

namespace papersim::scenegen {
namespace {

ExampleSheetParams coarse() {
  ExampleSheetParams p;
  p.nx = 8;
  p.ny = 11;
  return p;
}

TEST(SmoothSurface, KeepsVerticesAndSplitsEveryFaceInFourPerLevel) {
  const SheetMesh m = make_example_sheet("cylinder", coarse());
  for (int level : {0, 1, 2, 3}) {
    const SheetMesh r = refine_surface(m, SurfaceParams{level});
    EXPECT_EQ(r.num_faces(), m.num_faces() << (2 * level));
    EXPECT_EQ((r.positions.topRows(m.num_vertices()) - m.positions).norm(), 0.0) << level;
    EXPECT_EQ((r.uv.topRows(m.num_vertices()) - m.uv).norm(), 0.0) << level;
  }
  EXPECT_THROW(refine_surface(m, SurfaceParams{-1}), InputError);
  EXPECT_THROW(refine_surface(m, SurfaceParams{MAX_SURFACE_LEVEL + 1}), InputError);
}

TEST(SmoothSurface, UvIsLinearAndFacesKeepPositiveUvArea) {
  const SheetMesh r = refine_surface(make_example_sheet("fold", coarse()), SurfaceParams{2});
  for (int f = 0; f < r.num_faces(); ++f) {
    const Eigen::Vector2d a = r.uv.row(r.faces(f, 0)), b = r.uv.row(r.faces(f, 1)),
                          c = r.uv.row(r.faces(f, 2));
    EXPECT_GT((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x(), 0.0) << f;
  }
  // A regular grid's UV midpoints: every refined UV is on the 4x finer grid (to rounding).
  for (int i = 0; i < r.num_vertices(); ++i) {
    EXPECT_NEAR(r.uv(i, 0) * 7 * 4, std::round(r.uv(i, 0) * 7 * 4), 1e-9);
    EXPECT_NEAR(r.uv(i, 1) * 10 * 4, std::round(r.uv(i, 1) * 10 * 4), 1e-9);
  }
}

TEST(SmoothSurface, FlatStaysFlatWithStraightSides) {
  const SheetMesh r = refine_surface(make_example_sheet("flat", coarse()), SurfaceParams{3});
  const ExampleSheetParams p = coarse();
  double drift = 0;
  for (int i = 0; i < r.num_vertices(); ++i) {
    EXPECT_NEAR(r.positions(i, 2), 0.0, 1e-15);  // affine rules keep the plane
    drift = std::max(drift, std::hypot(r.positions(i, 0) - (r.uv(i, 0) - 0.5) * p.width,
                                       r.positions(i, 1) - (r.uv(i, 1) - 0.5) * p.height));
  }
  // This grid has valence-4 and -8 vertices (alternating diagonals): no sliding along the sheet.
  EXPECT_LT(drift, 1e-15);
}

TEST(SmoothSurface, NewVerticesLieCloserToTheCylinderThanTheMesh) {
  const ExampleSheetParams p = coarse();
  const SheetMesh m = make_example_sheet("cylinder", p);
  // Distance of a point from the cylinder axis (y axis through (0, *, R)) minus R.
  const auto off = [&](const Eigen::Vector3d& q) {
    return std::abs(std::hypot(q.x(), q.z() - p.cylinder_radius) - p.cylinder_radius);
  };
  double linear = 0, smooth = 0;
  int n_linear = 0, n_smooth = 0;
  const SheetMesh r = refine_surface(m, SurfaceParams{1});
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = m.positions.row(m.faces(f, k)),
                            b = m.positions.row(m.faces(f, (k + 1) % 3));
      linear += off(0.5 * (a + b));
      ++n_linear;
    }
  for (int i = m.num_vertices(); i < r.num_vertices(); ++i) {
    const bool side = r.uv(i, 0) < 1e-12 || r.uv(i, 0) > 1 - 1e-12 || r.uv(i, 1) < 1e-12 ||
                      r.uv(i, 1) > 1 - 1e-12;
    if (side) continue;
    smooth += off(r.positions.row(i).transpose());
    ++n_smooth;
  }
  linear /= n_linear;
  smooth /= n_smooth;
  std::cout << "[surface] mean distance from the cylinder: edge midpoints " << linear
            << " m, butterfly points inside the sheet " << smooth << " m\n";
  EXPECT_LT(smooth, 0.25 * linear);
}

TEST(SmoothSurface, FlipMirrorsAndKeepsThePrintedSideOrientation) {
  const SheetMesh m = make_example_sheet("bump", coarse());
  const SheetMesh f = flip_sheet(m);
  for (int i = 0; i < m.num_vertices(); ++i) {
    EXPECT_EQ(f.positions(i, 0), -m.positions(i, 0));
    EXPECT_EQ(f.uv(i, 0), 1.0 - m.uv(i, 0));
  }
  for (int k = 0; k < f.num_faces(); ++k) {
    const Eigen::Vector2d a = f.uv.row(f.faces(k, 0)), b = f.uv.row(f.faces(k, 1)),
                          c = f.uv.row(f.faces(k, 2));
    EXPECT_GT((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x(), 0.0);
  }
}

}  // namespace
}  // namespace papersim::scenegen

namespace papersim::scenegen {
namespace {

TEST(SmoothSurface, RenderedSurfaceNeverSinksIntoTheTable) {
  // The fold leaves the table with a 4 mm crease on a 6 mm mesh: the butterfly points overshoot
  // below the support plane there unless lifted (the table then shows through the sheet).
  test::TempDir dir("above");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "fold", "fold.obj");
  o.seed = 1;
  o.width = 64;
  o.height = 90;
  o.edge_lift = false;  // the curl only moves points up (EdgeLift tests)
  prepare_job(o, dir.str("job"));
  std::ifstream in(dir.path() / "job" / "job.json");
  const auto stage = nlohmann::json::parse(in)["meta"]["stage"];
  const Eigen::Vector3d origin(stage["origin"][0], stage["origin"][1], stage["origin"][2]);
  const Eigen::Vector3d up(stage["up"][0], stage["up"][1], stage["up"][2]);
  const SheetMesh rendered = read_sheet_obj(dir.str("job/sheet.obj"));
  const SheetMesh raw = refine_surface(read_sheet_obj(o.mesh_path), SurfaceParams{o.surface.level});
  ASSERT_EQ(rendered.num_vertices(), raw.num_vertices());
  double lowest = 0, lowest_raw = 0;
  for (int i = 0; i < rendered.num_vertices(); ++i) {
    lowest = std::min(lowest, (Eigen::Vector3d(rendered.positions.row(i)) - origin).dot(up));
    lowest_raw = std::min(lowest_raw, (Eigen::Vector3d(raw.positions.row(i)) - origin).dot(up));
  }
  const SheetMesh lifted = lift_above_plane(raw, origin, up);
  EXPECT_EQ((lifted.positions - rendered.positions).cwiseAbs().maxCoeff(), 0.0);  // 17 digits
  std::cout << "[surface] fold, level " << o.surface.level << ": lowest refined point "
            << lowest_raw << " m below the table before lifting, " << lowest << " m after\n";
  EXPECT_LT(lowest_raw, -1e-5);  // the overshoot this guards against is there
  EXPECT_GT(lowest, -1e-12);
}

}  // namespace
}  // namespace papersim::scenegen
