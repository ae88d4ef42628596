#include "scenegen/edge_lift.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "scenegen/errors.hpp"
#include "scenegen/geometry.hpp"

namespace papersim::scenegen {
namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

/// Boundary edges of a mesh (edges of one face) as segments in material coordinates [m],
/// bucketed in square cells of side `cell` for the distance queries.
class BoundaryGrid {
 public:
  BoundaryGrid(const SheetMesh& m, double cell) : m_cell(cell) {
    std::unordered_map<std::uint64_t, int> count;
    auto key = [](int a, int b) {
      if (a > b) std::swap(a, b);
      return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
    };
    for (int f = 0; f < m.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) ++count[key(m.faces(f, k), m.faces(f, (k + 1) % 3))];
    for (const auto& [k, n] : count) {
      if (n != 1) continue;
      const Vec2 a = m.material_point(m.uv.row(static_cast<Eigen::Index>(k >> 32)).transpose());
      const Vec2 b =
          m.material_point(m.uv.row(static_cast<Eigen::Index>(k & 0xffffffffULL)).transpose());
      const int s = static_cast<int>(m_segments.size());
      m_segments.emplace_back(a, b);
      const Vec2 lo = a.cwiseMin(b), hi = a.cwiseMax(b);
      for (long i = cell_of(lo.x()); i <= cell_of(hi.x()); ++i)
        for (long j = cell_of(lo.y()); j <= cell_of(hi.y()); ++j) m_cells[pack(i, j)].push_back(s);
    }
  }
  /// Distance [m] from material point `p` to the boundary, or `cap` when it is farther than
  /// one cell (the cells around p are the only ones searched).
  double distance(const Vec2& p, double cap) const {
    double best = cap;
    const long ci = cell_of(p.x()), cj = cell_of(p.y());
    for (long i = ci - 1; i <= ci + 1; ++i)
      for (long j = cj - 1; j <= cj + 1; ++j) {
        const auto it = m_cells.find(pack(i, j));
        if (it == m_cells.end()) continue;
        for (int s : it->second)
          best = std::min(best, segment_distance(p, m_segments[static_cast<std::size_t>(s)]));
      }
    return best;
  }

 private:
  long cell_of(double x) const { return static_cast<long>(std::floor(x / m_cell)); }
  static std::uint64_t pack(long i, long j) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32) |
           static_cast<std::uint32_t>(j);
  }
  static double segment_distance(const Vec2& p, const std::pair<Vec2, Vec2>& s) {
    const Vec2 d = s.second - s.first;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - s.first).dot(d) / len2, 0.0, 1.0) : 0.0;
    return (p - s.first - t * d).norm();
  }
  double m_cell;
  std::vector<std::pair<Vec2, Vec2>> m_segments;
  std::unordered_map<std::uint64_t, std::vector<int>> m_cells;
};

/// 1 at or below `lo`, 0 at or above `hi`, smoothstep between.
double rest_weight(double h, double lo, double hi) {
  const double s = std::clamp((h - lo) / (hi - lo), 0.0, 1.0);
  return 1.0 - s * s * (3.0 - 2.0 * s);
}

}  // namespace

EdgeLift draw_edge_lift(Rng& rng) {
  EdgeLift lift;
  lift.amplitude = rng.uniform(EDGE_LIFT_AMPLITUDE_MIN, EDGE_LIFT_AMPLITUDE_MAX);
  lift.width = rng.uniform(EDGE_LIFT_WIDTH_MIN, EDGE_LIFT_WIDTH_MAX);
  return lift;
}

SheetMesh lift_edges(SheetMesh surface, const Eigen::Vector3d& origin, const Eigen::Vector3d& up,
                     const EdgeLift& lift) {
  if (!(lift.amplitude >= 0.0) || !(lift.width > 0.0) || !(lift.rest_high > lift.rest_low))
    throw InputError("edge lift: amplitude must be >= 0, width > 0 and rest_high > rest_low");
  if (lift.amplitude == 0.0) return surface;
  const BoundaryGrid boundary(surface, lift.width);
  std::vector<double> raise(static_cast<std::size_t>(surface.num_vertices()), 0.0);
  for (int i = 0; i < surface.num_vertices(); ++i) {
    const double h = (Vec3(surface.positions.row(i)) - origin).dot(up);
    const double rest = rest_weight(h, lift.rest_low, lift.rest_high);
    if (rest == 0.0) continue;
    const double d =
        boundary.distance(surface.material_point(surface.uv.row(i).transpose()), lift.width);
    const double s = 1.0 - d / lift.width;
    raise[static_cast<std::size_t>(i)] = lift.amplitude * s * s * rest;
  }
  // At most half the free space above each lifted point, measured on the surface before the
  // lift: a layer above only moves up, so at least half of every vertical gap stays.
  const MeshBvh bvh(surface);
  for (int i = 0; i < surface.num_vertices(); ++i) {
    double& r = raise[static_cast<std::size_t>(i)];
    if (r == 0.0) continue;
    const auto hit = bvh.first_hit(surface.positions.row(i).transpose(), up, 0.0, 2.0 * r, i);
    if (hit) r = std::min(r, 0.5 * hit->t);
  }
  for (int i = 0; i < surface.num_vertices(); ++i)
    surface.positions.row(i) += raise[static_cast<std::size_t>(i)] * up.transpose();
  return surface;
}

Eigen::MatrixX3d moved_normals(const Eigen::MatrixX3d& normals, const SheetMesh& before,
                               const SheetMesh& after) {
  std::vector<char> moved(static_cast<std::size_t>(after.num_vertices()), 0);
  for (int f = 0; f < after.num_faces(); ++f) {
    bool any = false;
    for (int k = 0; k < 3; ++k)
      any =
          any || before.positions.row(after.faces(f, k)) != after.positions.row(after.faces(f, k));
    if (any)
      for (int k = 0; k < 3; ++k) moved[static_cast<std::size_t>(after.faces(f, k))] = 1;
  }
  const Eigen::MatrixX3d nb = vertex_normals(before), na = vertex_normals(after);
  Eigen::MatrixX3d out = normals;
  for (int i = 0; i < after.num_vertices(); ++i)
    if (moved[static_cast<std::size_t>(i)])
      out.row(i) = (normals.row(i) + na.row(i) - nb.row(i)).normalized();
  return out;
}

RenderedSurface rendered_surface(const SheetMesh& mesh, const Eigen::Vector3d& origin,
                                 const Eigen::Vector3d& up, const SurfaceParams& params,
                                 const EdgeLift& lift) {
  const SheetMesh on_table = lift_above_plane(refine_surface(mesh, params), origin, up);
  RenderedSurface out{lift_edges(on_table, origin, up, lift), carried_normals(mesh, on_table)};
  if (lift.amplitude > 0.0) out.normals = moved_normals(out.normals, on_table, out.surface);
  return out;
}

}  // namespace papersim::scenegen
