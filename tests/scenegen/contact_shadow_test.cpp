// The contact shadow's occlusion map: the sky a sheet hides from the table. Checked against the
// analytic form factor of a disc, and for the properties the photo relies on: darkest along a
// touching edge and under a raised part near where it leaves the table, nothing beyond the
// reach, the same values whatever the thread count, the same file for the same seed.
#include "scenegen/contact_shadow.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "scenegen/job.hpp"
#include "test_support.hpp"

namespace papersim::scenegen {
namespace {
namespace fs = std::filesystem;

/// A polyline profile z(x) over x in [0, width], extruded along y in [0, depth], n x m quads.
template <class Profile>
SheetMesh extruded(double width, double depth, int n, int m, Profile z) {
  SheetMesh s;
  s.width = width;
  s.height = depth;
  s.positions.resize((n + 1) * (m + 1), 3);
  s.uv.resize((n + 1) * (m + 1), 2);
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = width * i / n;
      s.positions.row(j * (n + 1) + i) << x, depth * j / m, z(x);
      s.uv.row(j * (n + 1) + i) << double(i) / n, double(j) / m;
    }
  s.faces.resize(2 * n * m, 3);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      s.faces.row(2 * (j * n + i)) << a, b, d;
      s.faces.row(2 * (j * n + i) + 1) << a, d, c;
    }
  return s;
}

/// A horizontal disc of radius r at height h above the support plane z = 0 (a fan of k triangles).
SheetMesh disc(double r, double h, int k) {
  SheetMesh s;
  s.width = s.height = 2 * r;
  s.positions.resize(k + 1, 3);
  s.uv.resize(k + 1, 2);
  s.positions.row(0) << 0, 0, h;
  s.uv.row(0) << 0.5, 0.5;
  for (int i = 0; i < k; ++i) {
    const double t = 2 * M_PI * i / k;
    s.positions.row(i + 1) << r * std::cos(t), r * std::sin(t), h;
    s.uv.row(i + 1) << 0.5 + 0.5 * std::cos(t), 0.5 + 0.5 * std::sin(t);
  }
  s.faces.resize(k, 3);
  for (int i = 0; i < k; ++i) s.faces.row(i) << 0, i + 1, (i + 1) % k + 1;
  return s;
}

/// Occlusion at the cell containing stage point (x, y).
double occlusion_at(const SheetHeightField& f, const std::vector<float>& occ, double x, double y) {
  const int i = static_cast<int>(std::floor((x - f.x0) / f.cell));
  const int j = static_cast<int>(std::floor((y - f.y0) / f.cell));
  EXPECT_TRUE(i >= 0 && j >= 0 && i < f.width && j < f.height)
      << "(" << x << ", " << y << ") is off the map";
  return occ[std::size_t(j) * f.width + i];
}

TEST(ContactShadow, UnderADiscItIsTheDiscsFormFactor) {
  // The cosine-weighted part of the sky hidden by a disc of radius R at height H, seen from
  // below its centre, is sin^2 of its half-angle: R^2 / (R^2 + H^2).
  ContactParams p;
  p.gap = 0.0;
  p.reach = 0.08;
  p.cell = 1e-3;
  const Stage stage;  // support plane z = 0
  for (double h : {0.01, 0.03, 0.06}) {
    const SheetHeightField f = sheet_height_field(disc(0.05, h, 96), stage, p);
    const auto occ = contact_occlusion(f, p);
    const double expected = 0.05 * 0.05 / (0.05 * 0.05 + h * h);
    EXPECT_NEAR(occlusion_at(f, occ, 0.0005, 0.0005), expected, 0.02) << "height " << h;
  }
}

TEST(ContactShadow, DarkestAlongATouchingEdgeAndZeroBeyondTheReach) {
  // A flat sheet resting on the support plane (0.3 mm above the table).
  const ContactParams p;
  const SheetHeightField f =
      sheet_height_field(extruded(0.1, 0.1, 10, 10, [](double) { return 0.0; }), Stage{}, p);
  const auto occ = contact_occlusion(f, p);
  // The first cell right of the sheet's edge x = 0.1 that the sheet does not cover.
  const int j = static_cast<int>((0.05 - f.y0) / f.cell);
  int i = static_cast<int>((0.1 - f.x0) / f.cell) - 2;
  while (f.covered(i, j)) ++i;
  const auto at = [&](int di) {
    return static_cast<double>(occ[std::size_t(j) * f.width + i + di]);
  };
  const double at_edge = at(0), beside = at(4), far = at(40);
  // A 0.3 mm gap under a flat sheet: the line is about a millimetre wide.
  EXPECT_GT(at_edge, 0.05) << "no contact line";
  EXPECT_GT(at_edge, 4 * beside);
  EXPECT_GT(beside, far);
  EXPECT_LT(far, 0.01);
  // Beyond the reach no table point sees the sheet: the map's corners read exactly 0 (no
  // darkening), as does everything off the map in the scene.
  EXPECT_EQ(occ.front(), 0.0f);
  EXPECT_EQ(occ.back(), 0.0f);
  EXPECT_EQ(occ[std::size_t(f.width) - 1], 0.0f);
  // Under the resting sheet the sky is all but hidden.
  EXPECT_GT(occlusion_at(f, occ, 0.05, 0.05), 0.99);
}

TEST(ContactShadow, UnderARaisedPartDarkestWhereItLeavesTheTable) {
  // Flat for x < 0.1, then rising at 30 degrees to x = 0.2 (about 5.8 cm up).
  const double slope = std::tan(30 * M_PI / 180);
  const SheetMesh sheet =
      extruded(0.2, 0.15, 40, 30, [&](double x) { return x < 0.1 ? 0.0 : (x - 0.1) * slope; });
  const ContactParams p;
  const SheetHeightField f = sheet_height_field(sheet, Stage{}, p);
  const auto occ = contact_occlusion(f, p);
  const double y = 0.075;
  const double near_hinge = occlusion_at(f, occ, 0.105, y);
  const double middle = occlusion_at(f, occ, 0.15, y);
  const double under_tip = occlusion_at(f, occ, 0.195, y);
  const double past_tip = occlusion_at(f, occ, 0.23, y);
  EXPECT_GT(near_hinge, middle);
  EXPECT_GT(middle, under_tip);
  EXPECT_GT(under_tip, past_tip);
  EXPECT_GT(past_tip, 0.0) << "the raised part shadows the table beyond its edge";
  // Soft: no step between neighbouring cells under the raised part.
  for (double x = 0.102; x < 0.2; x += p.cell)
    EXPECT_LT(std::abs(occlusion_at(f, occ, x + p.cell, y) - occlusion_at(f, occ, x, y)), 0.05)
        << "x = " << x;
}

TEST(ContactShadow, MapStaysBoundedForEverySheetSizeTheLimitsAccept) {
  // A 3 m and a 1,000 m flat sheet (the largest the limits accept): the map is built, with
  // coarser cells, and still shows the contact line beside the edge.
  for (double side : {3.0, 1000.0}) {
    ContactParams p = contact_params_for(side);
    EXPECT_GT(p.cell, ContactParams{}.cell);
    const SheetHeightField f =
        sheet_height_field(extruded(side, side, 4, 4, [](double) { return 0.0; }), Stage{}, p);
    EXPECT_LE(std::max(f.width, f.height), 2000);
    p.azimuths = 8;  // the property, not the quality, is checked here
    const auto occ = contact_occlusion(f, p);
    EXPECT_GT(occlusion_at(f, occ, side / 2, side / 2), 0.99) << side;
    EXPECT_EQ(occ.front(), 0.0f) << side;
  }
  // Sheets up to 0.8 m keep the default settings.
  EXPECT_EQ(contact_params_for(0.3).cell, ContactParams{}.cell);
  EXPECT_EQ(contact_params_for(0.3).reach, ContactParams{}.reach);
}

TEST(ContactShadow, SameValuesWhateverTheThreadCount) {
  const SheetMesh sheet = make_example_sheet("fold");
  ContactParams p;
  p.cell = 1e-3;
  const SheetHeightField f = sheet_height_field(sheet, Stage{}, p);
  const auto one = contact_occlusion(f, p, 1);
  EXPECT_EQ(one, contact_occlusion(f, p, 3));
  EXPECT_EQ(one, contact_occlusion(f, p, 8));
}

TEST(ContactShadow, SameSeedGivesTheSameMapAndTheGroundTruthSurfaceIsUntouched) {
  test::TempDir dir("contact");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "fold", "fold.obj");
  o.seed = 3;
  o.width = 64;
  o.height = 90;
  o.surface.level = 1;
  prepare_job(o, dir.str("a"));
  prepare_job(o, dir.str("b"));
  o.contact_shadow = false;
  prepare_job(o, dir.str("off"));
  ASSERT_TRUE(fs::exists(dir.path() / "a" / "contact.png"));
  EXPECT_EQ(test::file_bytes(dir.path() / "a" / "contact.png"),
            test::file_bytes(dir.path() / "b" / "contact.png"));
  EXPECT_EQ(test::file_bytes(dir.path() / "a" / "scene.inc"),
            test::file_bytes(dir.path() / "b" / "scene.inc"));
  EXPECT_FALSE(fs::exists(dir.path() / "off" / "contact.png"));
  // Ground-truth passes alone never see the table: no map is made for them.
  o.contact_shadow = true;
  o.passes = {Pass::albedo, Pass::uv, Pass::mask};
  prepare_job(o, dir.str("gt"));
  EXPECT_FALSE(fs::exists(dir.path() / "gt" / "contact.png"));
  // The contact shadow is a layer on the table: the surface every pass is cast or rendered on,
  // and the sheet's scene text, are the same with and without it.
  for (const char* name : {"sheet.obj", "sheet_normals.txt", "sheet.inc", "shadow.inc", "main.pov"})
    EXPECT_EQ(test::file_bytes(dir.path() / "a" / name),
              test::file_bytes(dir.path() / "off" / name))
        << name;
  const ImageF map = read_png((dir.path() / "a" / "contact.png").string());
  float lo = 1, hi = 0;
  for (float v : map.data) lo = std::min(lo, v), hi = std::max(hi, v);
  EXPECT_EQ(lo, 0.0f);
  EXPECT_GT(hi, 0.99f);
}

}  // namespace
}  // namespace papersim::scenegen

namespace papersim::scenegen {
namespace {

/// Mean of the photo's channels over the pixels `select` picks (mask: the sheet's mask pass).
template <class Select>
double mean_where(const ImageF& photo, const ImageF& mask, Select select) {
  double sum = 0;
  long n = 0;
  for (int y = 0; y < photo.height; ++y)
    for (int x = 0; x < photo.width; ++x)
      if (select(x, y, mask))
        for (int c = 0; c < photo.channels; ++c) sum += photo.at(x, y, c), ++n;
  EXPECT_GT(n, 0);
  return n > 0 ? sum / n : 0.0;
}

/// Distance [pixels] to the nearest mask pixel, by brute force over a window of `radius`.
int distance_to_mask(const ImageF& mask, int x, int y, int radius) {
  int best = radius + 1;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const int u = x + dx, v = y + dy;
      if (u < 0 || v < 0 || u >= mask.width || v >= mask.height || mask.at(u, v, 0) < 0.5f)
        continue;
      best = std::min(best, std::max(std::abs(dx), std::abs(dy)));
    }
  return best;
}

TEST(Render, ContactShadowDarkensTheTableBesideTheSheetAndNoGroundTruthPass) {
  test::TempDir dir("contact_render");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "fold", "fold.obj");
  o.seed = 3;
  o.width = 128;
  o.height = 180;
  o.document_dpi = 60;
  render_sample(o, dir.str("on"), RunOptions{});
  o.contact_shadow = false;
  render_sample(o, dir.str("off"), RunOptions{});
  for (const char* name :
       {"uv.exr", "coords.exr", "normal.exr", "mask.png", "albedo.png", "backward.npy"})
    EXPECT_EQ(test::file_bytes(dir.path() / "on" / name),
              test::file_bytes(dir.path() / "off" / name))
        << name;
  const ImageF mask = read_png((dir.path() / "on" / "mask.png").string());
  const ImageF on = read_png((dir.path() / "on" / "image.png").string());
  const ImageF off = read_png((dir.path() / "off" / "image.png").string());
  // The table within 2 pixels of the sheet (about 2 mm at this size) is darker with the
  // contact shadow (0.7 / 255 on average over the ring when written: the line is about a pixel
  // wide here); the table far from the sheet is not changed by it.
  const auto beside = [](int x, int y, const ImageF& m) {
    return m.at(x, y, 0) < 0.5f && distance_to_mask(m, x, y, 2) <= 2;
  };
  const auto far = [](int x, int y, const ImageF& m) {
    return m.at(x, y, 0) < 0.5f && distance_to_mask(m, x, y, 30) > 30;
  };
  const double beside_on = mean_where(on, mask, beside), beside_off = mean_where(off, mask, beside);
  std::cout << "table beside the sheet: " << beside_on << " with, " << beside_off
            << " without the contact shadow\n";
  EXPECT_LT(beside_on, beside_off - 0.4 / 255);
  EXPECT_NEAR(mean_where(on, mask, far), mean_where(off, mask, far), 0.1 / 255);
}

}  // namespace
}  // namespace papersim::scenegen
