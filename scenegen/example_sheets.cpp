#include "scenegen/example_sheets.hpp"

#include <cmath>
#include <functional>

#include "scenegen/errors.hpp"

namespace papersim::scenegen {
namespace {

using Map = std::function<Eigen::Vector3d(double, double)>;  // centred material (x, y) -> world

SheetMesh grid(const ExampleSheetParams& p, const Map& map) {
  SheetMesh m;
  m.width = p.width;
  m.height = p.height;
  m.size_from_header = true;
  m.positions.resize(p.nx * p.ny, 3);
  m.uv.resize(p.nx * p.ny, 2);
  for (int j = 0; j < p.ny; ++j)
    for (int i = 0; i < p.nx; ++i) {
      const int k = j * p.nx + i;
      const double u = static_cast<double>(i) / (p.nx - 1), v = static_cast<double>(j) / (p.ny - 1);
      m.uv.row(k) << u, v;
      m.positions.row(k) = map((u - 0.5) * p.width, (v - 0.5) * p.height).transpose();
    }
  m.faces.resize(2 * (p.nx - 1) * (p.ny - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < p.ny; ++j)
    for (int i = 0; i + 1 < p.nx; ++i) {
      const int a = j * p.nx + i, b = a + 1, c = a + p.nx, d = c + 1;
      if ((i + j) % 2 == 0) {
        m.faces.row(f++) << a, b, d;
        m.faces.row(f++) << a, d, c;
      } else {
        m.faces.row(f++) << a, b, c;
        m.faces.row(f++) << b, d, c;
      }
    }
  return m;
}

/// Fold: material x beyond the crease rolls over a cylinder of radius r (angle up to alpha) and
/// continues straight: an isometric fold with a rounded crease.
Eigen::Vector3d fold(const ExampleSheetParams& p, double x, double y) {
  const double alpha = p.fold_angle_deg * M_PI / 180.0, r = p.fold_radius;
  const double s = x - p.fold_x;
  if (s <= 0) return {x, y, 0};
  const double arc = r * alpha;
  const double t = std::min(s, arc) / r;
  Eigen::Vector3d q(p.fold_x + r * std::sin(t), y, r * (1 - std::cos(t)));
  if (s > arc) q += (s - arc) * Eigen::Vector3d(std::cos(alpha), 0, std::sin(alpha));
  return q;
}

}  // namespace

SheetMesh make_example_sheet(const std::string& kind, const ExampleSheetParams& p) {
  if (kind == "flat") return grid(p, [](double x, double y) { return Eigen::Vector3d(x, y, 0); });
  if (kind == "cylinder")
    return grid(p, [&](double x, double y) {
      const double R = p.cylinder_radius, t = x / R;
      return Eigen::Vector3d(R * std::sin(t), y, R * (1 - std::cos(t)));
    });
  if (kind == "fold") return grid(p, [&](double x, double y) { return fold(p, x, y); });
  if (kind == "bump")
    return grid(p, [&](double x, double y) {
      const double dx = x - 0.03, dy = y + 0.04;
      return Eigen::Vector3d(
          x, y, p.bump_height * std::exp(-(dx * dx + dy * dy) / (2 * p.bump_sigma * p.bump_sigma)));
    });
  throw InputError("unknown example sheet '" + kind + "' (flat, cylinder, fold, bump)");
}

}  // namespace papersim::scenegen
