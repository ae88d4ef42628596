// The drawn edge curl of the rendered surface: its profile, where it applies, that it keeps
// clear of a layer above and of the table, and that a sample renders and records exactly it.
#include "scenegen/edge_lift.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "scenegen/example_sheets.hpp"
#include "scenegen/geometry.hpp"
#include "scenegen/job.hpp"
#include "scenegen/meta.hpp"
#include "test_support.hpp"

namespace papersim::scenegen {
namespace {

const Eigen::Vector3d ORIGIN = Eigen::Vector3d::Zero();
const Eigen::Vector3d UP = Eigen::Vector3d::UnitZ();

EdgeLift curl(double amplitude, double width) {
  EdgeLift l;
  l.amplitude = amplitude;
  l.width = width;
  return l;
}

TEST(EdgeLift, FlatSheetCurlsByTheProfileAlongEveryEdge) {
  // A flat A4 sheet on z = 0 (3 mm grid): z = A (1 - d / w)^2 within w of the edge, d the
  // material distance to the nearest edge; exactly 0 beyond; UV untouched.
  ExampleSheetParams p;
  p.nx = 71;
  p.ny = 100;
  const SheetMesh flat = make_example_sheet("flat", p);
  const EdgeLift l = curl(0.6e-3, 12e-3);
  const SheetMesh lifted = lift_edges(flat, ORIGIN, UP, l);
  EXPECT_EQ((lifted.uv - flat.uv).cwiseAbs().maxCoeff(), 0.0);
  double worst = 0;
  int moved = 0;
  for (int i = 0; i < flat.num_vertices(); ++i) {
    const Eigen::Vector2d m = flat.material_point(flat.uv.row(i).transpose());
    const double d = std::min({m.x(), flat.width - m.x(), m.y(), flat.height - m.y()});
    const double s = std::max(0.0, 1.0 - d / l.width);
    worst = std::max(worst, std::abs(lifted.positions(i, 2) - l.amplitude * s * s));
    EXPECT_EQ(lifted.positions(i, 0), flat.positions(i, 0));
    EXPECT_EQ(lifted.positions(i, 1), flat.positions(i, 1));
    if (d >= l.width) {
      EXPECT_EQ(lifted.positions(i, 2), 0.0);
    }
    moved += lifted.positions(i, 2) > 0.0;
  }
  EXPECT_LT(worst, 1e-15);   // double rounding of a sub-millimetre value
  EXPECT_GT(moved, 4 * 60);  // four rows of vertices along each edge (3 mm grid, 12 mm band)
}

TEST(EdgeLift, ShadingNormalsFollowTheCurl) {
  // The normals after the curl are the curled surface's: away from the corners the profile is
  // z(d) with slope -2 A / w (1 - d / w) along the inward edge normal; area-weighted vertex
  // normals of a quadratic on a 3 mm grid match it to well under a milliradian.
  ExampleSheetParams p;
  p.nx = 71;
  p.ny = 100;
  const SheetMesh flat = make_example_sheet("flat", p);
  const EdgeLift l = curl(1e-3, 12e-3);
  const RenderedSurface r = rendered_surface(flat, ORIGIN, UP, SurfaceParams{0}, l);
  const double h = flat.width / (p.nx - 1);
  double worst = 0, steepest = 0;
  for (int i = 0; i < flat.num_vertices(); ++i) {
    const Eigen::Vector2d m = flat.material_point(flat.uv.row(i).transpose());
    const double d = m.x();  // the left edge, away from the corners
    if (d < h / 2 || d > l.width - h / 2 || m.y() < 2 * l.width ||
        m.y() > flat.height - 2 * l.width)
      continue;
    const double slope = 2 * l.amplitude / l.width * (1 - d / l.width);  // height falls with x
    const Eigen::Vector3d expected = Eigen::Vector3d(slope, 0, 1).normalized();
    worst =
        std::max(worst, std::acos(std::min(1.0, Eigen::Vector3d(r.normals.row(i)).dot(expected))));
    steepest = std::max(steepest, std::atan(slope));
  }
  std::cout << "[edge lift] normals in the curl: worst " << worst << " rad off, steepest tilt "
            << steepest << " rad\n";
  EXPECT_GT(steepest, 0.1);
  EXPECT_LT(worst, 1e-3);
  // Far from the edges the normals are the carried ones, bit for bit.
  const RenderedSurface none = rendered_surface(flat, ORIGIN, UP, SurfaceParams{0}, EdgeLift{});
  const int centre = (p.ny / 2) * p.nx + p.nx / 2;
  EXPECT_EQ(r.normals.row(centre), none.normals.row(centre));
}

TEST(EdgeLift, RaisedPartsStayAndNothingGoesBelowTheTable) {
  // The fold's flap stands up to ~8 cm: points above rest_high do not move, no point moves
  // down or by more than the amplitude.
  const SheetMesh fold = refine_surface(make_example_sheet("fold"), SurfaceParams{1});
  const SheetMesh on_table = lift_above_plane(fold, ORIGIN, UP);
  const EdgeLift l = curl(1e-3, 10e-3);
  const SheetMesh lifted = lift_edges(on_table, ORIGIN, UP, l);
  int raised = 0;
  for (int i = 0; i < fold.num_vertices(); ++i) {
    const double before = on_table.positions(i, 2), dz = lifted.positions(i, 2) - before;
    EXPECT_GE(dz, 0.0);
    EXPECT_LE(dz, l.amplitude);
    if (before >= l.rest_high) {
      EXPECT_EQ(dz, 0.0);
      ++raised;
    }
  }
  EXPECT_GT(raised, fold.num_vertices() / 10);
}

TEST(EdgeLift, KeepsHalfTheGapToALayerAbove) {
  // The fold turned over by 180 degrees with a 0.5 mm crease radius: the flap lies flat 1 mm
  // above the sheet, its free edges right above the lower layer's. Both layers rest (under
  // rest_low), so both curl; the lower one by at most half the gap, so the layers cannot meet.
  ExampleSheetParams p;
  p.fold_angle_deg = 180.0;
  p.fold_radius = 0.5e-3;
  const SheetMesh folded = lift_above_plane(make_example_sheet("fold", p), ORIGIN, UP);
  const EdgeLift l = curl(1e-3, 10e-3);
  const SheetMesh lifted = lift_edges(folded, ORIGIN, UP, l);
  const MeshBvh before(folded), after(lifted);
  int under = 0, guarded = 0;
  double least = 1;
  for (int i = 0; i < folded.num_vertices(); ++i) {
    const auto gap0 = before.first_hit(folded.positions.row(i).transpose(), UP, 0.0, 1.0, i);
    if (!gap0 || folded.positions(i, 2) > 1e-4) continue;  // the lower layer, under the flap
    ++under;
    const auto gap1 = after.first_hit(lifted.positions.row(i).transpose(), UP, 0.0, 1.0, i);
    ASSERT_TRUE(gap1) << "vertex " << i << " went through the layer above";
    EXPECT_GE(gap1->t, 0.5 * gap0->t - 1e-12);
    least = std::min(least, gap1->t);
    guarded += lifted.positions(i, 2) - folded.positions(i, 2) > 0 &&
               lifted.positions(i, 2) - folded.positions(i, 2) < l.amplitude * 0.99 &&
               lifted.positions(i, 2) - folded.positions(i, 2) == 0.5 * gap0->t;
  }
  std::cout << "[edge lift] folded flat: " << under << " vertices under the flap, " << guarded
            << " held at half the gap, least gap after " << least << " m\n";
  EXPECT_GT(under, 100);
  EXPECT_GT(guarded, 10);  // the guard acted: the curl alone would have reached the flap
  EXPECT_GT(least, 0.4e-3);
}

TEST(EdgeLift, SampleRendersRecordsAndReproducesTheDrawnCurl) {
  test::TempDir dir("edge_lift");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "fold", "fold.obj");
  o.seed = 1;
  o.width = 64;
  o.height = 90;
  prepare_job(o, dir.str("a"));
  prepare_job(o, dir.str("b"));
  o.edge_lift = false;
  prepare_job(o, dir.str("flat"));
  auto meta_of = [&](const std::string& job) {
    std::ifstream in(dir.path() / job / "job.json");
    return nlohmann::json::parse(in)["meta"];
  };
  const auto meta = meta_of("a"), off = meta_of("flat");
  const auto& e = meta["surface"]["edge_lift"];
  EXPECT_TRUE(e["enabled"].get<bool>());
  EXPECT_FALSE(off["surface"]["edge_lift"]["enabled"].get<bool>());
  EXPECT_EQ(e["amplitude_m"], off["surface"]["edge_lift"]["amplitude_m"]);  // drawn either way
  EXPECT_GE(e["amplitude_m"].get<double>(), EDGE_LIFT_AMPLITUDE_MIN);
  EXPECT_LT(e["amplitude_m"].get<double>(), EDGE_LIFT_AMPLITUDE_MAX);
  EXPECT_GE(e["width_m"].get<double>(), EDGE_LIFT_WIDTH_MIN);
  EXPECT_LT(e["width_m"].get<double>(), EDGE_LIFT_WIDTH_MAX);
  for (const char* f : {"sheet.obj", "sheet.inc", "shadow.inc", "contact.png", "sheet_normals.txt"})
    EXPECT_EQ(test::file_bytes(dir.str("a/") + f), test::file_bytes(dir.str("b/") + f)) << f;

  // sheet.obj (17 digits) is exactly the surface rebuilt from meta.json.
  const auto& st = meta["stage"];
  const Eigen::Vector3d origin(st["origin"][0], st["origin"][1], st["origin"][2]);
  const Eigen::Vector3d up(st["up"][0], st["up"][1], st["up"][2]);
  const SheetMesh mesh = read_sheet_obj(o.mesh_path);
  const SurfaceParams sp{meta["surface"]["level"].get<int>()};
  const SheetMesh curled =
      rendered_surface(mesh, origin, up, sp, edge_lift_from_json(meta["surface"])).surface;
  const SheetMesh flat =
      rendered_surface(mesh, origin, up, sp, edge_lift_from_json(off["surface"])).surface;
  EXPECT_EQ(
      (read_sheet_obj(dir.str("a/sheet.obj")).positions - curled.positions).cwiseAbs().maxCoeff(),
      0.0);
  EXPECT_EQ(
      (read_sheet_obj(dir.str("flat/sheet.obj")).positions - flat.positions).cwiseAbs().maxCoeff(),
      0.0);
  EXPECT_EQ((flat.positions - lift_above_plane(refine_surface(mesh, sp), origin, up).positions)
                .cwiseAbs()
                .maxCoeff(),
            0.0);
  const double most = ((curled.positions - flat.positions) * up).maxCoeff();
  std::cout << "[edge lift] fold seed 1: amplitude " << e["amplitude_m"] << " m, width "
            << e["width_m"] << " m, largest lift " << most << " m\n";
  EXPECT_NEAR(most, e["amplitude_m"].get<double>(), 1e-9);  // the resting edges reach it
}

}  // namespace
}  // namespace papersim::scenegen
