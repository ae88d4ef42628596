// Ground truth by ray casting: the pixel rays hit the triangles where geometry says they do,
// the result does not depend on the thread count, and the ray-cast mask, UV, coords and normals
// agree with POV-Ray's exact emissive renders of the same scene.
#include "scenegen/raycast.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "scenegen/errors.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/job.hpp"
#include "scenegen/meta.hpp"
#include "test_support.hpp"

namespace papersim::scenegen {
namespace {
namespace fs = std::filesystem;

/// A flat sheet in the plane z = 0 (u along x, v along y, corner at the origin), split into
/// n x n squares of two triangles each.
SheetMesh flat_grid(double width, double height, int n) {
  SheetMesh m;
  m.width = width;
  m.height = height;
  m.positions.resize((n + 1) * (n + 1), 3);
  m.uv.resize((n + 1) * (n + 1), 2);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const int k = j * (n + 1) + i;
      m.uv.row(k) << double(i) / n, double(j) / n;
      m.positions.row(k) << width * i / n, height * j / n, 0.0;
    }
  m.faces.resize(2 * n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.faces.row(2 * (j * n + i)) << a, b, d;
      m.faces.row(2 * (j * n + i) + 1) << a, d, c;
    }
  return m;
}

/// A camera above the plane z = 0, tilted, looking at `target`.
Camera oblique_camera(const Eigen::Vector3d& target, int width, int height) {
  Camera cam;
  cam.width = width;
  cam.height = height;
  cam.position = target + Eigen::Vector3d(0.05, -0.2, 0.5);
  cam.forward = (target - cam.position).normalized();
  cam.right = cam.forward.cross(Eigen::Vector3d::UnitY()).normalized();
  cam.up = cam.right.cross(cam.forward).normalized();
  cam.focal_px = 0.05 / 0.036 * std::max(width, height);
  return cam;
}

TEST(Raycast, HitsThePlaneWhereGeometrySaysWithTheSameResultOnAnyThreadCount) {
  const SheetMesh sheet = flat_grid(0.21, 0.297, 12);
  const Camera cam = oblique_camera({0.105, 0.15, 0.0}, 160, 224);
  const PixelHits hits = cast_pixel_rays(sheet, cam, 1);
  const ImageF uv = uv_from_hits(hits, sheet);
  const ImageF xyz = coords_from_hits(hits, sheet);
  int inside = 0, boundary = 0;
  double max_uv = 0.0, max_z = 0.0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      // The ray through the pixel centre meets z = 0 at t = -o.z / d.z.
      const Eigen::Vector3d d = cam.ray(x + 0.5, y + 0.5);
      const Eigen::Vector3d p = cam.position - cam.position.z() / d.z() * d;
      const double u = p.x() / sheet.width, v = p.y() / sheet.height;
      const double margin = std::min({u, v, 1.0 - u, 1.0 - v});
      if (std::abs(margin) < 1e-9) {
        ++boundary;
        continue;
      }  // on the outline: either answer
      ASSERT_EQ(uv.at(x, y, 2) > 0.5f, margin > 0.0) << "pixel " << x << "," << y;
      if (margin < 0.0) continue;
      ++inside;
      max_uv = std::max({max_uv, std::abs(uv.at(x, y, 0) - u), std::abs(uv.at(x, y, 1) - v)});
      max_z = std::max(max_z, double(std::abs(xyz.at(x, y, 2))));
    }
  EXPECT_GT(inside, cam.width * cam.height / 4);
  EXPECT_LT(inside, cam.width * cam.height);
  // float32 output: u, v in [0, 1] carry ~6e-8; z = 0 exactly up to rounding of the corners.
  EXPECT_LT(max_uv, 2e-7);
  EXPECT_LT(max_z, 1e-9);
  for (int threads : {2, 3, 7}) {
    const PixelHits other = cast_pixel_rays(sheet, cam, threads);
    EXPECT_EQ(other.face, hits.face) << threads << " threads";
    EXPECT_TRUE(other.weight == hits.weight) << threads << " threads";
  }
}

TEST(Raycast, NearestFaceWinsAndNormalsTurnToTheCamera) {
  // Two sheets, one 1 cm above the other: every pixel seeing both sees the upper one.
  SheetMesh two = flat_grid(0.2, 0.2, 4);
  const SheetMesh upper = flat_grid(0.2, 0.2, 4);
  const int nv = two.num_vertices(), nf = two.num_faces();
  two.positions.conservativeResize(2 * nv, 3);
  two.uv.conservativeResize(2 * nv, 2);
  two.faces.conservativeResize(2 * nf, 3);
  for (int i = 0; i < nv; ++i) {
    two.positions.row(nv + i) = upper.positions.row(i) + Eigen::RowVector3d(0, 0, 0.01);
    two.uv.row(nv + i) = upper.uv.row(i);
  }
  for (int f = 0; f < nf; ++f) two.faces.row(nf + f) = upper.faces.row(f).array() + nv;
  // Normals pointing away from the camera (-z): the pass turns them to +z.
  const Eigen::MatrixX3d normals = Eigen::RowVector3d(0, 0, -1).replicate(2 * nv, 1);
  const Camera cam = oblique_camera({0.1, 0.1, 0.0}, 96, 96);
  const PixelHits hits = cast_pixel_rays(two, cam);
  const ImageF xyz = coords_from_hits(hits, two);
  const ImageF n = normals_from_hits(hits, two, normals, cam);
  int both = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const std::size_t px = std::size_t(y) * cam.width + x;
      if (hits.face[px] < 0) continue;
      EXPECT_FLOAT_EQ(n.at(x, y, 2), 1.0f);
      const Eigen::Vector3d d = cam.ray(x + 0.5, y + 0.5);
      const Eigen::Vector3d p =
          cam.position - (cam.position.z() - 0.01) / d.z() * d;  // on the upper sheet
      const bool on_upper =
          p.x() > 1e-9 && p.y() > 1e-9 && p.x() < 0.2 - 1e-9 && p.y() < 0.2 - 1e-9;
      if (!on_upper) continue;
      ++both;
      EXPECT_GE(hits.face[px], nf) << "pixel " << x << "," << y << " sees the lower sheet";
      EXPECT_NEAR(xyz.at(x, y, 2), 0.01, 1e-8);
    }
  EXPECT_GT(both, 1000);
  EXPECT_THROW(normals_from_hits(hits, two, normals.topRows(3), cam), InputError);
}

TEST(Raycast, VertexNormalsReadBackExactlyAndBadFilesNameTheProblem) {
  test::TempDir dir("normals");
  Eigen::MatrixX3d n(3, 3);
  n << 0.1, 0.2, std::sqrt(0.95), 0, 0, 1, 1.0 / 3.0, -2.0 / 3.0, 2.0 / 3.0;
  write_vertex_normals(dir.str("n.txt"), n);
  EXPECT_TRUE(read_vertex_normals(dir.str("n.txt"), 3) == n);
  try {
    read_vertex_normals(dir.str("n.txt"), 4);
    FAIL() << "a file with 3 normals read as 4";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("holds 3 normals, expected 4"), std::string::npos)
        << e.what();
  }
  std::ofstream(dir.str("bad.txt")) << "# header\n0 0 1\n0 nan 1\n";
  try {
    read_vertex_normals(dir.str("bad.txt"), 2);
    FAIL() << "a non-finite normal was accepted";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_vertex_normals(dir.str("missing.txt"), 1), IoError);
}

TEST(Raycast, GroundTruthNamesParseAndABadOneNamesTheOption) {
  EXPECT_EQ(parse_ground_truth("raycast"), GroundTruth::raycast);
  EXPECT_EQ(parse_ground_truth("povray"), GroundTruth::povray);
  EXPECT_EQ(ground_truth_name(GroundTruth::povray), "povray");
  try {
    parse_ground_truth("blender");
    FAIL() << "an unknown ground truth was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--ground-truth 'blender'"), std::string::npos)
        << e.what();
  }
  // The POV-Ray renders of the exact passes are asked for only with povray ground truth.
  const auto raw = raw_passes_for(all_passes(), true, GroundTruth::raycast);
  EXPECT_EQ(raw, (std::vector<RawPass>{RawPass::albedo, RawPass::shading, RawPass::image}));
  EXPECT_EQ(raw_passes_for({Pass::coords}, false, GroundTruth::povray),
            (std::vector<RawPass>{RawPass::uv, RawPass::coords}));
}

/// The pixels whose 3 x 3 neighbourhood holds both sheet and background in `mask`.
std::vector<bool> silhouette(const ImageF& mask) {
  std::vector<bool> s(std::size_t(mask.width) * mask.height, false);
  for (int y = 0; y < mask.height; ++y)
    for (int x = 0; x < mask.width; ++x) {
      bool on = false, off = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = std::clamp(x + dx, 0, mask.width - 1),
                    yy = std::clamp(y + dy, 0, mask.height - 1);
          (mask.at(xx, yy, 0) > 0.5f ? on : off) = true;
        }
      s[std::size_t(y) * mask.width + x] = on && off;
    }
  return s;
}

TEST(Render, RayCastGroundTruthAgreesWithPovRayRendersOfTheSameScene) {
  test::TempDir dir("raycast");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "fold", "fold.obj");
  o.seed = 3;
  o.width = 192;
  o.height = 270;
  o.quality = Quality::draft;
  o.passes = {Pass::uv, Pass::coords, Pass::normal, Pass::mask};
  o.document_dpi = 30;
  o.ground_truth = GroundTruth::povray;
  render_sample(o, dir.str("povray"), RunOptions{});
  o.ground_truth = GroundTruth::raycast;
  render_sample(o, dir.str("raycast"), RunOptions{}, true);
  // POV-Ray shades a mesh2 triangle whose three normals are equal with its facet normal (the
  // refined surface undulates slightly beside a crease, up to ~1 degree here); the normal pass
  // is the carried normals interpolated (docs/scenegen.md), so those pixels are compared apart.
  const fs::path job = dir.path() / "raycast" / "job";
  const SheetMesh surface = read_sheet_obj((job / "sheet.obj").string());
  Eigen::MatrixX3d normals =
      read_vertex_normals((job / "sheet_normals.txt").string(), surface.num_vertices());
  const SheetMesh rendered = povray_precision(surface, normals);
  const Camera cam = camera_from_json(
      nlohmann::json::parse(std::ifstream(dir.path() / "raycast" / "meta.json"))["camera"]);
  const PixelHits hits = cast_pixel_rays(rendered, cam);
  const auto flat_face = [&](int f) {
    return normals.row(rendered.faces(f, 0)) == normals.row(rendered.faces(f, 1)) &&
           normals.row(rendered.faces(f, 1)) == normals.row(rendered.faces(f, 2));
  };
  const auto exr = [&](const char* sample, const char* file) {
    return read_exr((dir.path() / sample / file).string(), {"R", "G", "B"});
  };
  const ImageF mask_p = read_png((dir.path() / "povray" / "mask.png").string());
  const ImageF mask_r = read_png((dir.path() / "raycast" / "mask.png").string());
  const ImageF uv_p = exr("povray", "uv.exr"), uv_r = exr("raycast", "uv.exr");
  const ImageF xyz_p = exr("povray", "coords.exr"), xyz_r = exr("raycast", "coords.exr");
  const ImageF n_p = exr("povray", "normal.exr"), n_r = exr("raycast", "normal.exr");
  const std::vector<bool> edge = silhouette(mask_p);
  int differ = 0, differ_inside = 0, edge_pixels = 0, sheet = 0;
  int flat = 0;
  double max_uv = 0, max_xyz = 0, max_n = 0, max_n_flat = 0;
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const bool on_edge = edge[std::size_t(y) * o.width + x];
      const bool p = mask_p.at(x, y, 0) > 0.5f, r = mask_r.at(x, y, 0) > 0.5f;
      edge_pixels += on_edge;
      if (p != r) ++(on_edge ? differ : differ_inside);
      if (!p || !r || on_edge) continue;
      ++sheet;
      for (int c = 0; c < 3; ++c) {
        max_uv = std::max(max_uv, double(std::abs(uv_p.at(x, y, c) - uv_r.at(x, y, c))));
        max_xyz = std::max(max_xyz, double(std::abs(xyz_p.at(x, y, c) - xyz_r.at(x, y, c))));
      }
      const bool facet = flat_face(hits.face[std::size_t(y) * o.width + x]);
      flat += facet;
      for (int c = 0; c < 3; ++c) {
        double& m = facet ? max_n_flat : max_n;
        m = std::max(m, double(std::abs(n_p.at(x, y, c) - n_r.at(x, y, c))));
      }
    }
  std::cout << "[raycast] " << o.width << " x " << o.height << ": masks differ on " << differ
            << " of " << edge_pixels << " silhouette pixels and on " << differ_inside
            << " others; off the silhouette (" << sheet << " pixels) max |uv| difference " << max_uv
            << ", max |coords| difference " << max_xyz << " m, max |normal| difference " << max_n
            << " (" << flat << " pixels on faces with three equal normals: " << max_n_flat << ")\n";
  EXPECT_EQ(differ_inside, 0);
  EXPECT_GT(sheet, o.width * o.height / 5);
  // POV-Ray's float32-exact passes (fine renders: 2^-24 of the encoding span) and its slope
  // normals (16 bits of 0.5 + asin(n . axis) / pi: ~5e-5) against float32 casts.
  EXPECT_LT(max_uv, 1e-5);
  EXPECT_LT(max_xyz, 1e-6);
  EXPECT_LT(max_n, 2e-4);
  EXPECT_LT(max_n_flat, 0.05);
}

}  // namespace
}  // namespace papersim::scenegen
