// Shadow-terminator artefact: a folded sheet lit at a grazing angle. On a coarse triangle mesh
// with interpolated normals the flat triangles shadow each other, and the shading pass shows
// steps along the projected mesh edges. The test compares the mean gradient magnitude of the
// shading pass on pixels crossed by a projected edge of the simulated mesh with that on pixels
// beside them (1.5 to 3 pixels from every edge), inside the crease.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>

#include "scenegen/example_sheets.hpp"
#include "scenegen/geometry.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/job.hpp"
#include "scenegen/resting_pose.hpp"
#include "test_support.hpp"

namespace papersim::scenegen {
namespace {

/// Mean gradient magnitudes of the shading pass on edge pixels and on pixels beside them.
struct EdgeGradient {
  double on_edges = 0, beside = 0;
  long edge_pixels = 0, beside_pixels = 0;
  double ratio() const { return on_edges / beside; }
};

/// Distance [px] from pixel (x, y) to the nearest edge of the mesh face its UV lies in: the
/// barycentric weight over the norm of its pixel-space gradient (chain rule through the UV
/// pass's Jacobian, by central differences). Negative when it cannot be measured.
/// @param face  set to the face
double edge_distance_px(const SheetMesh& mesh, const UvLocator& loc, const ImageF& uv, int x, int y,
                        int& face) {
  for (int d : {-1, 1})
    if (uv.at(x + d, y, 2) < 0.5f || uv.at(x, y + d, 2) < 0.5f) return -1;
  Eigen::Matrix2d jac;  // d(u, v) / d(x, y)
  for (int k = 0; k < 2; ++k) {
    jac(k, 0) = 0.5 * (uv.at(x + 1, y, k) - uv.at(x - 1, y, k));
    jac(k, 1) = 0.5 * (uv.at(x, y + 1, k) - uv.at(x, y - 1, k));
  }
  const auto hit = loc.locate({uv.at(x, y, 0), uv.at(x, y, 1)}, 1e-6);
  if (!hit) return -1;
  face = hit->face;
  Eigen::Vector2d t[3];
  for (int k = 0; k < 3; ++k) t[k] = mesh.uv.row(mesh.faces(hit->face, k));
  const double area2 =
      (t[1] - t[0]).x() * (t[2] - t[0]).y() - (t[1] - t[0]).y() * (t[2] - t[0]).x();
  double best = 1e9;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d e = t[(k + 2) % 3] - t[(k + 1) % 3];     // edge opposite corner k
    const Eigen::Vector2d grad_uv(-e.y() / area2, e.x() / area2);  // gradient of weight k in UV
    const double g = (jac.transpose() * grad_uv).norm();
    if (g > 0) best = std::min(best, std::max(0.0, hit->barycentric[k]) / g);
  }
  return best;
}

/// Luminance gradient magnitude of the shading pass (sRGB decoded), central differences.
double gradient(const ImageF& shading, int x, int y) {
  const auto lum = [&](int i, int j) {
    double s = 0;
    for (int c = 0; c < 3; ++c) s += srgb_to_linear(shading.at(i, j, c)) / 3.0;
    return s;
  };
  return 0.5 * std::hypot(lum(x + 1, y) - lum(x - 1, y), lum(x, y + 1) - lum(x, y - 1));
}

/// Edge statistics over mask pixels whose material coordinate across the fold [m] lies in
/// [s_lo, s_hi]. Compared face by face (each face's edge pixels with its own interior), then
/// averaged over the faces that have both, so foreshortening (more edge pixels where faces are
/// small in the image) does not weigh one lighting more than another.
EdgeGradient edge_gradient(const SheetMesh& mesh, const ImageF& uv, const ImageF& shading,
                           double s_lo, double s_hi) {
  const UvLocator loc(mesh);
  struct Sums {
    double edge = 0, beside = 0;
    long n_edge = 0, n_beside = 0;
  };
  std::vector<Sums> faces(static_cast<std::size_t>(mesh.num_faces()));
  for (int y = 2; y + 2 < uv.height; ++y)
    for (int x = 2; x + 2 < uv.width; ++x) {
      if (uv.at(x, y, 2) < 0.5f) continue;
      const double s = (uv.at(x, y, 0) - 0.5) * mesh.width * std::cos(M_PI / 6) +
                       (uv.at(x, y, 1) - 0.5) * mesh.height * std::sin(M_PI / 6);
      if (s < s_lo || s > s_hi) continue;
      int face = -1;
      const double d = edge_distance_px(mesh, loc, uv, x, y, face);
      if (d < 0) continue;
      Sums& f = faces[static_cast<std::size_t>(face)];
      if (d < 0.5) {
        f.edge += gradient(shading, x, y);
        ++f.n_edge;
      } else if (d > 1.5 && d < 3.0) {
        f.beside += gradient(shading, x, y);
        ++f.n_beside;
      }
    }
  EdgeGradient r;
  for (const Sums& f : faces) {
    if (f.n_edge == 0 || f.n_beside == 0) continue;
    r.on_edges += f.edge / f.n_edge;
    r.beside += f.beside / f.n_beside;
    r.edge_pixels += f.n_edge;
    r.beside_pixels += f.n_beside;
  }
  return r;
}

/// A4 sheet, 36 x 50 vertices (6 mm edges), folded by `angle` along a line at 30 degrees to
/// the mesh rows through the centre, the crease a cylinder of radius r; printed side outside
/// the convex ridge (z down before the resting pose turns it over).
SheetMesh diagonal_ridge(const ExampleSheetParams& p) {
  SheetMesh m = make_example_sheet("flat", p);
  const double alpha = p.fold_angle_deg * M_PI / 180.0, r = p.fold_radius;
  const Eigen::Vector2d across(std::cos(M_PI / 6), std::sin(M_PI / 6));
  for (int i = 0; i < m.num_vertices(); ++i) {
    const Eigen::Vector2d q = m.positions.row(i).head<2>().transpose();
    const double s = q.dot(across), arc = r * alpha, t = std::min(std::max(s, 0.0), arc) / r;
    Eigen::Vector2d along = q - s * across;
    double a = s <= 0 ? s : r * std::sin(t), z = s <= 0 ? 0 : -r * (1 - std::cos(t));
    if (s > arc) {
      a += (s - arc) * std::cos(alpha);
      z -= (s - arc) * std::sin(alpha);
    }
    m.positions.row(i) << (along + a * across).transpose(), z;
  }
  return m;
}

/// The folded sheet of the test: a 60 degree ridge with a 2 cm crease (about three mesh rows
/// across it) at 30 degrees to the mesh rows, 6 mm edges, one point light grazing the crease.
EdgeGradient render_fold(int level, double shadow_offset, test::TempDir& dir,
                         ExampleSheetParams& p) {
  p.fold_angle_deg = 60.0;
  p.fold_radius = 0.02;
  p.fold_x = 0.0;
  SampleOptions o;
  const SheetMesh ridge = diagonal_ridge(p);
  o.mesh_path = dir.str("ridge.obj");
  {
    std::ofstream out(o.mesh_path);
    write_sheet_obj(out, ridge);
  }
  o.document = test::write_smooth_document(dir, 64, 90);
  o.seed = 3;
  o.width = 384;
  o.height = 540;
  o.quality = Quality::draft;
  o.passes = {Pass::shading, Pass::uv};
  o.fine_passes = false;
  o.surface.level = level;
  o.shadow_offset = shadow_offset;
  Light l;
  l.name = "grazing";
  const Stage stage = find_resting_pose(read_sheet_obj(o.mesh_path));
  const double az = M_PI / 2, el = 10.0 * M_PI / 180;  // along the stage's y axis, 10 deg high
  l.position = stage.centre_of_mass +
               2.0 * (std::cos(el) * (std::cos(az) * stage.ex + std::sin(az) * stage.ey) +
                      std::sin(el) * stage.up);
  l.size = 0.0;
  l.fade_distance = 2.0;
  l.intensity = 1.0;
  o.lights = {l};
  const std::string out =
      dir.str("sample" + std::to_string(level) + "_" + std::to_string(shadow_offset));
  render_sample(o, out, RunOptions{});
  const ImageF uv = read_exr(out + "/uv.exr", {"R", "G", "B"});
  const ImageF shading = read_png(out + "/shading.png");
  const SheetMesh mesh = read_sheet_obj(o.mesh_path);
  const double arc = p.fold_radius * p.fold_angle_deg * M_PI / 180;
  return edge_gradient(mesh, uv, shading, p.fold_x - 0.02,
                       p.fold_x + arc + 0.02);  // crease +- 2 cm
}

void print(const char* what, const EdgeGradient& g) {
  std::cout << "[artefact] " << what << ": face-averaged |grad shading| on edge pixels "
            << g.on_edges << ", beside " << g.beside << " (" << g.edge_pixels << " / "
            << g.beside_pixels << " pixels), ratio " << g.ratio() << "\n";
}

TEST(Artefact, ShadingHasNoStepsAlongMeshEdgesOnAFoldLitAtAGrazingAngle) {
  test::TempDir dir("artefact");
  ExampleSheetParams p;
  // The renderer before the smooth surface and the shadow caster: the check sees the steps.
  const EdgeGradient raw = render_fold(0, 0.0, dir, p);
  print("raw mesh, sheet casting its own shadows", raw);
  EXPECT_GT(raw.ratio(), 1.10);
  const SampleOptions defaults;
  const EdgeGradient g = render_fold(defaults.surface.level, defaults.shadow_offset, dir, p);
  print("default surface and shadow caster", g);
  ASSERT_GT(g.edge_pixels, 500);
  ASSERT_GT(g.beside_pixels, 500);
  EXPECT_LT(std::abs(g.ratio() - 1.0), 0.10);
}

}  // namespace
}  // namespace papersim::scenegen
