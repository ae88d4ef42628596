#include "scenegen/raycast.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include "common/atomic_file.hpp"
#include "scenegen/errors.hpp"

namespace papersim::scenegen {
namespace {

/// A face ready for the pixel loop. The ray origin (the camera) is the same for every pixel, so
/// Moller-Trumbore's s = o - a and q = s x e1 are per face.
struct FaceSetup {
  Eigen::Vector3d e1, e2, s, q;
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  ///< pixel range (inclusive) of the projected bounds
};

/// Pixels whose centre may lie in the face's image: the projected corners' bounding box with
/// one pixel of slack; the whole image when a corner is not in front of the camera.
void pixel_range(FaceSetup& f, const Eigen::Vector3d (&p)[3], const Camera& cam) {
  double lo_x = std::numeric_limits<double>::infinity(), hi_x = -lo_x, lo_y = lo_x, hi_y = -lo_x;
  for (const auto& v : p) {
    if (!(cam.depth(v) > 1e-9)) {
      f.x0 = 0, f.x1 = cam.width - 1, f.y0 = 0, f.y1 = cam.height - 1;
      return;
    }
    const Eigen::Vector2d q = cam.project(v);
    lo_x = std::min(lo_x, q.x()), hi_x = std::max(hi_x, q.x());
    lo_y = std::min(lo_y, q.y()), hi_y = std::max(hi_y, q.y());
  }
  // Centre i + 0.5 in [lo - 1, hi + 1].
  const auto clamp_to = [](double v, int n) {
    return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(n)));
  };
  f.x0 = std::max(0, clamp_to(std::ceil(lo_x - 1.5), cam.width));
  f.x1 = std::min(cam.width - 1, clamp_to(std::floor(hi_x + 0.5), cam.width));
  f.y0 = std::max(0, clamp_to(std::ceil(lo_y - 1.5), cam.height));
  f.y1 = std::min(cam.height - 1, clamp_to(std::floor(hi_y + 0.5), cam.height));
}

std::vector<FaceSetup> setup_faces(const SheetMesh& mesh, const Camera& cam) {
  std::vector<FaceSetup> faces(static_cast<std::size_t>(mesh.num_faces()));
  for (int i = 0; i < mesh.num_faces(); ++i) {
    const Eigen::Vector3d p[3] = {mesh.positions.row(mesh.faces(i, 0)),
                                  mesh.positions.row(mesh.faces(i, 1)),
                                  mesh.positions.row(mesh.faces(i, 2))};
    FaceSetup& f = faces[static_cast<std::size_t>(i)];
    f.e1 = p[1] - p[0];
    f.e2 = p[2] - p[0];
    f.s = cam.position - p[0];
    f.q = f.s.cross(f.e1);
    pixel_range(f, p, cam);
  }
  return faces;
}

/// The z-buffer pass over rows [row_begin, row_end): every face in order, every pixel of its
/// range; a hit replaces the pixel's one when strictly nearer.
void cast_rows(const std::vector<FaceSetup>& faces, const Camera& cam, int row_begin, int row_end,
               PixelHits& hits, std::vector<double>& depth) {
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const FaceSetup& f = faces[i];
    const int y0 = std::max(f.y0, row_begin), y1 = std::min(f.y1, row_end - 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = f.x0; x <= f.x1; ++x) {
        const Eigen::Vector3d d = cam.ray(x + 0.5, y + 0.5);
        const Eigen::Vector3d p = d.cross(f.e2);
        const double det = f.e1.dot(p);
        if (std::abs(det) < 1e-300) continue;
        const double inv = 1.0 / det;
        const double b1 = f.s.dot(p) * inv;
        if (b1 < 0.0 || b1 > 1.0) continue;
        const double b2 = d.dot(f.q) * inv;
        if (b2 < 0.0 || b1 + b2 > 1.0) continue;
        const double t = f.e2.dot(f.q) * inv;
        const std::size_t px = static_cast<std::size_t>(y) * cam.width + x;
        if (!(t > 0.0) || !(t < depth[px])) continue;
        depth[px] = t;
        hits.face[px] = static_cast<int>(i);
        hits.weight[px] = {b1, b2};
      }
  }
}

void check_hits(const PixelHits& hits, const SheetMesh& mesh) {
  for (int f : hits.face)
    if (f >= mesh.num_faces())
      throw InputError("pixel hits refer to face " + std::to_string(f) + " of a mesh with " +
                       std::to_string(mesh.num_faces()) + " faces");
}

/// Interpolate per-vertex rows of `values` (#V by N) at every hit into channels [0, N).
template <class Matrix>
ImageF interpolate(const PixelHits& hits, const SheetMesh& mesh, const Matrix& values,
                   int channels) {
  check_hits(hits, mesh);
  ImageF out(hits.width, hits.height, channels);
  const int n = static_cast<int>(values.cols());
  for (std::size_t px = 0; px < hits.face.size(); ++px) {
    const int f = hits.face[px];
    if (f < 0) continue;
    const Eigen::Vector2d w = hits.weight[px];
    for (int c = 0; c < n; ++c) {
      const double v = (1.0 - w.x() - w.y()) * values(mesh.faces(f, 0), c) +
                       w.x() * values(mesh.faces(f, 1), c) + w.y() * values(mesh.faces(f, 2), c);
      out.data[px * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)] =
          static_cast<float>(v);
    }
  }
  return out;
}

}  // namespace

SheetMesh povray_precision(const SheetMesh& mesh, Eigen::MatrixX3d& normals) {
  SheetMesh out = mesh;
  out.positions = mesh.positions.cast<float>().cast<double>();
  normals = normals.cast<float>().cast<double>().eval();
  return out;
}

PixelHits cast_pixel_rays(const SheetMesh& mesh, const Camera& camera, int threads) {
  PixelHits hits;
  hits.width = camera.width;
  hits.height = camera.height;
  const std::size_t n =
      static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height);
  hits.face.assign(n, -1);
  hits.weight.assign(n, Eigen::Vector2d::Zero());
  std::vector<double> depth(n, std::numeric_limits<double>::infinity());
  const std::vector<FaceSetup> faces = setup_faces(mesh, camera);
  int t =
      threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  t = std::clamp(t, 1, camera.height);
  // Each thread owns a band of rows: no two write the same pixel, and a pixel's result is the
  // same face loop in the same order whatever the band.
  std::vector<std::thread> pool;
  for (int k = 1; k < t; ++k)
    pool.emplace_back([&, k] {
      cast_rows(faces, camera, k * camera.height / t, (k + 1) * camera.height / t, hits, depth);
    });
  cast_rows(faces, camera, 0, camera.height / t, hits, depth);
  for (auto& th : pool) th.join();
  return hits;
}

ImageF uv_from_hits(const PixelHits& hits, const SheetMesh& mesh) {
  ImageF uv = interpolate(hits, mesh, mesh.uv, 3);
  for (std::size_t px = 0; px < hits.face.size(); ++px)
    if (hits.face[px] >= 0) uv.data[px * 3 + 2] = 1.0f;
  return uv;
}

ImageF coords_from_hits(const PixelHits& hits, const SheetMesh& mesh) {
  return interpolate(hits, mesh, mesh.positions, 3);
}

ImageF normals_from_hits(const PixelHits& hits, const SheetMesh& mesh,
                         const Eigen::MatrixX3d& normals, const Camera& camera) {
  if (normals.rows() != mesh.num_vertices())
    throw InputError("normals_from_hits: " + std::to_string(normals.rows()) + " normals for " +
                     std::to_string(mesh.num_vertices()) + " vertices");
  check_hits(hits, mesh);
  ImageF out(hits.width, hits.height, 3);
  for (int y = 0; y < hits.height; ++y)
    for (int x = 0; x < hits.width; ++x) {
      const std::size_t px = static_cast<std::size_t>(y) * hits.width + x;
      const int f = hits.face[px];
      if (f < 0) continue;
      const Eigen::Vector2d w = hits.weight[px];
      Eigen::Vector3d n = (1.0 - w.x() - w.y()) * Eigen::Vector3d(normals.row(mesh.faces(f, 0))) +
                          w.x() * Eigen::Vector3d(normals.row(mesh.faces(f, 1))) +
                          w.y() * Eigen::Vector3d(normals.row(mesh.faces(f, 2)));
      const double len = n.norm();
      if (!(len > 0.0)) continue;
      n /= len;
      if (n.dot(camera.ray(x + 0.5, y + 0.5)) > 0.0) n = -n;
      for (int c = 0; c < 3; ++c)
        out.data[px * 3 + static_cast<std::size_t>(c)] = static_cast<float>(n[c]);
    }
  return out;
}

void write_vertex_normals(const std::string& path, const Eigen::MatrixX3d& normals) {
  common::write_file_atomically(path, [&](std::ostream& out) {
    out.precision(17);
    out << "# papersim scenegen: unit shading normal of each vertex of sheet.obj\n";
    for (int i = 0; i < normals.rows(); ++i)
      out << normals(i, 0) << ' ' << normals(i, 1) << ' ' << normals(i, 2) << '\n';
  });
}

Eigen::MatrixX3d read_vertex_normals(const std::string& path, int count) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open vertex normals '" + path + "'");
  Eigen::MatrixX3d n(count, 3);
  std::string line;
  int i = 0, line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    if (i == count)
      throw IoError("'" + path + "' holds more than " + std::to_string(count) + " normals");
    std::istringstream s(line);
    if (!(s >> n(i, 0) >> n(i, 1) >> n(i, 2)) || !n.row(i).allFinite())
      throw IoError("'" + path + "' line " + std::to_string(line_no) + " is not a finite normal");
    ++i;
  }
  if (in.bad() || i != count)
    throw IoError("'" + path + "' holds " + std::to_string(i) + " normals, expected " +
                  std::to_string(count));
  return n;
}

}  // namespace papersim::scenegen
