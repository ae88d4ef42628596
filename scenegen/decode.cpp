#include "scenegen/decode.hpp"

#include <algorithm>
#include <cmath>

#include "scenegen/errors.hpp"
#include "scenegen/geometry.hpp"

namespace papersim::scenegen {
namespace {

std::vector<std::uint16_t> load(const std::string& path, int& w, int& h, int& c) {
  auto raw = read_png16(path, w, h, c);
  if (c < 3) throw IoError("raw render '" + path + "' is not RGB");
  return raw;
}

}  // namespace

double combine_fine(double coarse, double fine) {
  const double k = std::round(coarse * FINE_FACTOR - fine);
  return (k + fine) / FINE_FACTOR;
}

ImageF decode_uv(const std::string& coarse_path, const std::string& fine_path) {
  int w, h, c;
  const auto raw = load(coarse_path, w, h, c);
  std::vector<std::uint16_t> fine;
  if (!fine_path.empty()) {
    int w2, h2, c2;
    fine = load(fine_path, w2, h2, c2);
    if (w2 != w || h2 != h) throw IoError("raw UV renders differ in size");
  }
  ImageF uv(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = (std::size_t(y) * w + x) * c;
      if (raw[i + 2] < 32768) continue;  // mask channel is exactly 0 or 1
      for (int k = 0; k < 2; ++k) {
        double e = raw[i + k] / 65535.0;
        if (!fine.empty()) e = combine_fine(e, fine[i + k] / 65535.0);
        uv.at(x, y, k) = static_cast<float>(e / UV_ENCODING);
      }
      uv.at(x, y, 2) = 1.0f;
    }
  return uv;
}

ImageF decode_coords(const std::string& coarse_path, const std::string& fine_path,
                     const Eigen::Vector3d& coords_min, double coords_span, const ImageF& mask) {
  int w, h, c;
  const auto raw = load(coarse_path, w, h, c);
  std::vector<std::uint16_t> fine;
  if (!fine_path.empty()) {
    int w2, h2, c2;
    fine = load(fine_path, w2, h2, c2);
  }
  ImageF xyz(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (mask.at(x, y, 0) < 0.5f) continue;
      const std::size_t i = (std::size_t(y) * w + x) * c;
      for (int k = 0; k < 3; ++k) {
        double e = raw[i + k] / 65535.0;
        if (!fine.empty()) e = combine_fine(e, fine[i + k] / 65535.0);
        xyz.at(x, y, k) = static_cast<float>(coords_min[k] + e * coords_span);
      }
    }
  return xyz;
}

ImageF decode_normal(const std::string& path, const ImageF& mask) {
  int w, h, c;
  const auto raw = load(path, w, h, c);
  ImageF n(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (mask.at(x, y, 0) < 0.5f) continue;
      const std::size_t i = (std::size_t(y) * w + x) * c;
      Eigen::Vector3d v;
      for (int k = 0; k < 3; ++k) v[k] = std::sin(M_PI * (raw[i + k] / 65535.0 - 0.5));
      // Not renormalised: the length measures the exactness of the pass (16-bit quantisation).
      for (int k = 0; k < 3; ++k) n.at(x, y, k) = static_cast<float>(v[k]);
    }
  return n;
}

void apply_vignetting(ImageF& linear, const Camera& camera) {
  for (int y = 0; y < linear.height; ++y)
    for (int x = 0; x < linear.width; ++x) {
      const double dx = (x + 0.5 - 0.5 * camera.width) / camera.focal_px;
      const double dy = (y + 0.5 - 0.5 * camera.height) / camera.focal_px;
      const double cos2 = 1.0 / (1.0 + dx * dx + dy * dy);
      for (int c = 0; c < linear.channels; ++c)
        linear.at(x, y, c) *= static_cast<float>(cos2 * cos2);
    }
}

ImageF decode_linear(const std::string& path) {
  int w, h, c;
  const auto raw = load(path, w, h, c);
  ImageF img(w, h, 3);
  for (std::size_t p = 0; p < std::size_t(w) * h; ++p)
    for (int k = 0; k < 3; ++k) img.data[p * 3 + k] = raw[p * c + k] / 65535.0f;
  return img;
}

ImageF backward_map(const SheetMesh& mesh, const Camera& camera, const ImageF& uv_pass,
                    const BackwardParams& params) {
  const int gw = params.grid_width > 0 ? params.grid_width : camera.width;
  const int gh = params.grid_height > 0 ? params.grid_height : camera.height;
  if (gw < 2 || gh < 2) throw InputError("backward grid must be at least 2 x 2");
  const UvLocator locator(mesh);
  const Eigen::MatrixX3d normals = vertex_normals(mesh);
  ImageF map(gw, gh, 3);
  for (int r = 0; r < gh; ++r)
    for (int c = 0; c < gw; ++c) {
      const Eigen::Vector2d uv(static_cast<double>(c) / (gw - 1),
                               1.0 - static_cast<double>(r) / (gh - 1));
      const auto hit = locator.locate(uv);
      if (!hit) continue;
      Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        p += hit->barycentric[k] * Eigen::Vector3d(mesh.positions.row(mesh.faces(hit->face, k)));
        n += hit->barycentric[k] * Eigen::Vector3d(normals.row(mesh.faces(hit->face, k)));
      }
      const double depth = camera.depth(p);
      if (depth <= 0) continue;
      const Eigen::Vector2d q = camera.project(p);
      map.at(c, r, 0) = static_cast<float>(q.x());
      map.at(c, r, 1) = static_cast<float>(q.y());
      const int px = static_cast<int>(std::floor(q.x())), py = static_cast<int>(std::floor(q.y()));
      if (px < 0 || py < 0 || px >= uv_pass.width || py >= uv_pass.height) continue;
      if (uv_pass.at(px, py, 2) < 0.5f) continue;
      // Size of one pixel on the sheet along its most foreshortened direction [m].
      const double cosine =
          std::max(0.05, std::abs(n.normalized().dot((camera.position - p).normalized())));
      const double footprint = depth / (camera.focal_px * cosine);
      const Eigen::Vector2d seen(uv_pass.at(px, py, 0), uv_pass.at(px, py, 1));
      const double dist = mesh.material_point(seen - uv).norm();
      if (dist <= params.tolerance_pixels * footprint + 1e-6) map.at(c, r, 2) = 1.0f;
    }
  return map;
}

bool sample_masked(const ImageF& image, const ImageF& mask, double x, double y, float* out) {
  const double fx = x - 0.5, fy = y - 0.5;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const double ax = fx - x0, ay = fy - y0;
  double wsum = 0.0;
  std::vector<double> acc(image.channels, 0.0);
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int xi = x0 + dx, yi = y0 + dy;
      if (xi < 0 || yi < 0 || xi >= image.width || yi >= image.height) continue;
      if (mask.at(xi, yi, 0) < 0.5f) continue;
      const double w = (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay) + 1e-12;
      for (int k = 0; k < image.channels; ++k) acc[k] += w * image.at(xi, yi, k);
      wsum += w;
    }
  if (wsum <= 0.0) return false;
  for (int k = 0; k < image.channels; ++k) out[k] = static_cast<float>(acc[k] / wsum);
  return true;
}

ImageF unwarp(const ImageF& image, const ImageF& mask, const ImageF& backward) {
  ImageF flat(backward.width, backward.height, image.channels);
  for (int r = 0; r < backward.height; ++r)
    for (int c = 0; c < backward.width; ++c)
      if (backward.at(c, r, 2) > 0.5f)
        sample_masked(image, mask, backward.at(c, r, 0), backward.at(c, r, 1),
                      &flat.data[(std::size_t(r) * flat.width + c) * flat.channels]);
  return flat;
}

}  // namespace papersim::scenegen
