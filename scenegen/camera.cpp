#include "scenegen/camera.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "scenegen/geometry.hpp"

namespace papersim::scenegen {
namespace {

bool in_frame(const SheetMesh& mesh, const Camera& cam, double margin) {
  const double x0 = margin * cam.width, x1 = (1.0 - margin) * cam.width;
  const double y0 = margin * cam.height, y1 = (1.0 - margin) * cam.height;
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    const Eigen::Vector3d p = mesh.positions.row(i);
    if (cam.depth(p) <= 1e-6) return false;
    const Eigen::Vector2d q = cam.project(p);
    if (q.x() < x0 || q.x() > x1 || q.y() < y0 || q.y() > y1) return false;
  }
  return true;
}

double backfacing_fraction(const SheetMesh& mesh, const Eigen::MatrixX3d& normals,
                           const Camera& cam, double angle_deg) {
  const double c = std::cos(angle_deg * DEG);
  int count = 0;
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    const Eigen::Vector3d to_cam =
        (cam.position - Eigen::Vector3d(mesh.positions.row(i))).normalized();
    if (Eigen::Vector3d(normals.row(i)).dot(to_cam) < c) ++count;
  }
  return static_cast<double>(count) / std::max(1, mesh.num_vertices());
}

/// Points (vertices, then face centres) hidden from the camera by another part of the sheet.
int occluded_points(const SheetMesh& mesh, const MeshBvh& bvh, const Camera& cam) {
  constexpr double T_END = 1.0 - 1e-4;  // stop short of the point itself (60 um at 0.6 m)
  int count = 0;
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(mesh.positions.row(i)) - cam.position;
    if (bvh.first_hit(cam.position, d, 0.0, T_END, i)) ++count;
  }
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d c =
        (mesh.positions.row(mesh.faces(f, 0)) + mesh.positions.row(mesh.faces(f, 1)) +
         mesh.positions.row(mesh.faces(f, 2)))
            .transpose() /
        3.0;
    const auto hit = bvh.first_hit(cam.position, c - cam.position, 0.0, T_END);
    if (hit && hit->face != f) ++count;
  }
  return count;
}

}  // namespace

double Camera::vertical_fov_deg() const { return 2.0 * std::atan(0.5 * height / focal_px) / DEG; }

std::vector<Eigen::Vector2d> candidate_directions() {
  const double inclinations[] = {5.0, 12.0, 20.0, 28.0};
  const int azimuth_counts[] = {1, 5, 9, 11};
  std::vector<Eigen::Vector2d> out;
  for (int r = 0; r < 4; ++r) {
    const int n = azimuth_counts[r];
    for (int k = 0; k < n; ++k)
      out.emplace_back(inclinations[r], n == 1 ? 0.0 : -120.0 + 240.0 * k / (n - 1));
  }
  return out;
}

Camera make_camera(const Stage& stage, const Eigen::Vector3d& target, double inclination_deg,
                   double azimuth_deg, double roll_deg, int width, int height,
                   const CameraParams& params) {
  const double th = inclination_deg * DEG, ph = azimuth_deg * DEG;
  const Eigen::Vector3d offset_stage(std::sin(th) * std::sin(ph), -std::sin(th) * std::cos(ph),
                                     std::cos(th));
  Camera cam;
  cam.width = width;
  cam.height = height;
  cam.position = target + params.distance * stage.dir_to_world(offset_stage);
  cam.forward = (target - cam.position).normalized();
  // Page upright: image up is the stage's +y seen from the camera, then rolled.
  Eigen::Vector3d up = stage.ey - stage.ey.dot(cam.forward) * cam.forward;
  if (up.norm() < 1e-9) up = stage.up - stage.up.dot(cam.forward) * cam.forward;
  up.normalize();
  const Eigen::AngleAxisd roll(roll_deg * DEG, cam.forward);
  cam.up = (roll * up).normalized();
  cam.right = cam.forward.cross(cam.up).normalized();
  cam.focal_px = params.focal_length / params.sensor_size * std::max(width, height);
  return cam;
}

CameraChoice choose_camera(const SheetMesh& mesh, const Stage& stage, int width, int height,
                           const CameraParams& params, Rng& rng) {
  CameraChoice choice;
  choice.roll_deg = rng.uniform(-params.max_roll_deg, params.max_roll_deg);
  const Eigen::MatrixX3d normals = vertex_normals(mesh);
  const MeshBvh bvh(mesh);
  std::vector<int> valid;
  const auto dirs = candidate_directions();
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    CameraCandidate c;
    c.inclination_deg = dirs[k].x();
    c.azimuth_deg = dirs[k].y();
    const Camera cam = make_camera(stage, stage.centre_of_mass, c.inclination_deg, c.azimuth_deg,
                                   choice.roll_deg, width, height, params);
    c.in_frame = in_frame(mesh, cam, params.margin);
    c.backfacing_fraction = backfacing_fraction(mesh, normals, cam, params.backfacing_angle_deg);
    c.occluded_points = params.check_occlusion ? occluded_points(mesh, bvh, cam) : 0;
    c.valid = c.in_frame && c.backfacing_fraction <= params.max_backfacing_fraction &&
              c.occluded_points == 0;
    if (c.valid) valid.push_back(static_cast<int>(k));
    choice.candidates.push_back(c);
  }
  if (valid.empty()) return choice;
  choice.valid = true;
  choice.index =
      valid[static_cast<std::size_t>(rng.randint(0, static_cast<int>(valid.size()) - 1))];
  const auto& c = choice.candidates[static_cast<std::size_t>(choice.index)];
  choice.camera = make_camera(stage, stage.centre_of_mass, c.inclination_deg, c.azimuth_deg,
                              choice.roll_deg, width, height, params);
  return choice;
}

}  // namespace papersim::scenegen
