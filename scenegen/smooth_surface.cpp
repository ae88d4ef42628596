#include "scenegen/smooth_surface.hpp"

#include <cmath>
#include <string>
#include <unordered_map>
#include <vector>

#include "scenegen/errors.hpp"
#include "scenegen/geometry.hpp"

namespace papersim::scenegen {
namespace {

using Vec3 = Eigen::Vector3d;

/// Connectivity of a triangle mesh for one butterfly step.
struct Topology {
  /// Per edge (key a < b): the opposite vertices of its one or two faces.
  std::unordered_map<std::uint64_t, std::vector<int>> opposite;
  /// Per vertex: neighbours in ring order (next[v][a] = b when face (v, a, b) exists).
  std::vector<std::unordered_map<int, int>> next;
  std::vector<char> boundary;  ///< vertex on the boundary (open ring)

  static std::uint64_t key(int a, int b) {
    if (a > b) std::swap(a, b);
    return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
  }
  explicit Topology(const SheetMesh& m)
      : next(static_cast<std::size_t>(m.num_vertices())),
        boundary(static_cast<std::size_t>(m.num_vertices()), 0) {
    for (int f = 0; f < m.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = m.faces(f, k), b = m.faces(f, (k + 1) % 3), c = m.faces(f, (k + 2) % 3);
        opposite[key(a, b)].push_back(c);
        next[static_cast<std::size_t>(a)][b] = c;
      }
    for (const auto& [k, opp] : opposite)
      if (opp.size() == 1) boundary[k >> 32] = boundary[k & 0xffffffffULL] = 1;
  }
  /// Opposite vertex of edge (a, b) other than `not_this`, or -1.
  int across(int a, int b, int not_this) const {
    const auto it = opposite.find(key(a, b));
    if (it == opposite.end()) return -1;
    for (int o : it->second)
      if (o != not_this) return o;
    return -1;
  }
  /// Ring of an interior vertex starting at neighbour `first` (empty when open or broken).
  std::vector<int> ring(int v, int first) const {
    std::vector<int> r{first};
    const auto& nx = next[static_cast<std::size_t>(v)];
    for (int cur = first;;) {
      const auto it = nx.find(cur);
      if (it == nx.end()) return {};
      cur = it->second;
      if (cur == first) return r;
      r.push_back(cur);
      if (r.size() > nx.size()) return {};
    }
  }
  /// The other boundary neighbour of boundary vertex v (not w), or -1.
  int boundary_neighbour(int v, int w) const {
    for (const auto& [a, b] : next[static_cast<std::size_t>(v)]) {
      (void)b;
      if (a != w && opposite.at(key(v, a)).size() == 1) return a;
    }
    for (const auto& [a, b] : next[static_cast<std::size_t>(v)]) {
      (void)a;
      if (b != w && opposite.at(key(v, b)).size() == 1) return b;
    }
    return -1;
  }
};

/// Zorin, Schroeder and Sweldens 1996 ("Interpolating subdivision for meshes with arbitrary
/// topology"), the rule for an edge at an extraordinary vertex v of valence k, ring[0] the
/// edge's other end: 3/4 v + sum_j s_j ring[j].
Vec3 extraordinary_rule(const SheetMesh& m, int v, const std::vector<int>& ring) {
  const int k = static_cast<int>(ring.size());
  Vec3 p = 0.75 * Vec3(m.positions.row(v));
  for (int j = 0; j < k; ++j) {
    double s;
    if (k == 3)
      s = j == 0 ? 5.0 / 12.0 : -1.0 / 12.0;
    else if (k == 4)
      s = j == 0 ? 3.0 / 8.0 : (j == 2 ? -1.0 / 8.0 : 0.0);
    else
      s = (0.25 + std::cos(2 * M_PI * j / k) + 0.5 * std::cos(4 * M_PI * j / k)) / k;
    p += s * Vec3(m.positions.row(ring[static_cast<std::size_t>(j)]));
  }
  return p;
}

/// Four-point rule on the boundary (-1, 9, 9, -1) / 16; at a corner of the UV outline the
/// missing neighbour is reflected, so straight sides stay straight.
Vec3 boundary_rule(const SheetMesh& m, const Topology& t, int a, int b) {
  const auto outer = [&](int v, int w) {
    const int o = t.boundary_neighbour(v, w);
    const Vec3 pv = m.positions.row(v), pw = m.positions.row(w);
    if (o < 0) return Vec3(2 * pv - pw);
    const Eigen::Vector2d d1 = m.uv.row(v) - m.uv.row(o), d2 = m.uv.row(w) - m.uv.row(v);
    const double cross = d1.x() * d2.y() - d1.y() * d2.x();
    if (std::abs(cross) > 1e-3 * d1.norm() * d2.norm()) return Vec3(2 * pv - pw);  // corner
    return Vec3(m.positions.row(o));
  };
  return (9.0 * (Vec3(m.positions.row(a)) + Vec3(m.positions.row(b))) - outer(a, b) - outer(b, a)) /
         16.0;
}

/// New point on interior edge (a, b) with opposite vertices c, d (modified butterfly).
Vec3 interior_rule(const SheetMesh& m, const Topology& t, int a, int b, int c, int d) {
  const auto P = [&](int v) { return Vec3(m.positions.row(v)); };
  std::vector<int> ra, rb;
  if (!t.boundary[static_cast<std::size_t>(a)]) ra = t.ring(a, b);
  if (!t.boundary[static_cast<std::size_t>(b)]) rb = t.ring(b, a);
  const bool reg_a = ra.size() == 6, reg_b = rb.size() == 6;
  const int w1 = t.across(a, c, b), w2 = t.across(b, c, a), w3 = t.across(a, d, b),
            w4 = t.across(b, d, a);
  const bool wings = w1 >= 0 && w2 >= 0 && w3 >= 0 && w4 >= 0;
  if ((reg_a || t.boundary[static_cast<std::size_t>(a)]) &&
      (reg_b || t.boundary[static_cast<std::size_t>(b)]) && wings)
    return 0.5 * (P(a) + P(b)) + 0.125 * (P(c) + P(d)) - 0.0625 * (P(w1) + P(w2) + P(w3) + P(w4));
  const bool ext_a = !ra.empty() && !reg_a, ext_b = !rb.empty() && !reg_b;
  if (ext_a && ext_b) return 0.5 * (extraordinary_rule(m, a, ra) + extraordinary_rule(m, b, rb));
  if (!ra.empty() && (ext_a || rb.empty())) return extraordinary_rule(m, a, ra);
  if (!rb.empty()) return extraordinary_rule(m, b, rb);
  return 0.375 * (P(a) + P(b)) + 0.125 * (P(c) + P(d));  // both ends on the boundary, no wings
}

/// One step of the modified butterfly scheme: every triangle split in four, old vertices kept
/// (same indices), new UV = edge midpoint.
SheetMesh butterfly_step(const SheetMesh& m) {
  const Topology t(m);
  const Eigen::MatrixX3d normals = vertex_normals(m);
  std::vector<Vec3> pos;
  std::vector<Eigen::Vector2d> uv;
  for (int v = 0; v < m.num_vertices(); ++v) {
    pos.emplace_back(m.positions.row(v));
    uv.emplace_back(m.uv.row(v));
  }
  std::unordered_map<std::uint64_t, int> mid;
  const auto midpoint = [&](int a, int b) {
    const auto [it, fresh] = mid.emplace(Topology::key(a, b), static_cast<int>(pos.size()));
    if (!fresh) return it->second;
    const std::vector<int>& opp = t.opposite.at(Topology::key(a, b));
    const Vec3 p =
        opp.size() == 2 ? interior_rule(m, t, a, b, opp[0], opp[1]) : boundary_rule(m, t, a, b);
    // Only the move along the surface normal is kept: the rules at vertices of valence other
    // than 6 assume evenly spread neighbours and would also slide the point along the sheet,
    // drawing the document away from its material place (3 mm on a flat 30 mm grid).
    const Vec3 mid = 0.5 * (Vec3(m.positions.row(a)) + Vec3(m.positions.row(b)));
    const Vec3 n = (Vec3(normals.row(a)) + Vec3(normals.row(b))).normalized();
    pos.push_back(mid + n * n.dot(p - mid));
    uv.emplace_back(0.5 * (m.uv.row(a) + m.uv.row(b)));
    return it->second;
  };
  SheetMesh out;
  out.faces.resize(4 * m.num_faces(), 3);
  for (int f = 0; f < m.num_faces(); ++f) {
    const int a = m.faces(f, 0), b = m.faces(f, 1), c = m.faces(f, 2);
    const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.faces.row(4 * f) << a, ab, ca;
    out.faces.row(4 * f + 1) << ab, b, bc;
    out.faces.row(4 * f + 2) << ca, bc, c;
    out.faces.row(4 * f + 3) << ab, bc, ca;
  }
  out.positions.resize(static_cast<Eigen::Index>(pos.size()), 3);
  out.uv.resize(static_cast<Eigen::Index>(pos.size()), 2);
  for (std::size_t i = 0; i < pos.size(); ++i) {
    out.positions.row(static_cast<Eigen::Index>(i)) = pos[i].transpose();
    out.uv.row(static_cast<Eigen::Index>(i)) = uv[i].transpose();
  }
  out.width = m.width;
  out.height = m.height;
  out.size_from_header = m.size_from_header;
  return out;
}

}  // namespace

SheetMesh refine_surface(const SheetMesh& mesh, const SurfaceParams& params) {
  if (params.level < 0 || params.level > MAX_SURFACE_LEVEL)
    throw InputError("subdivision level " + std::to_string(params.level) + " is outside [0, " +
                     std::to_string(MAX_SURFACE_LEVEL) + "]");
  SheetMesh out = mesh;
  for (int i = 0; i < params.level; ++i) out = butterfly_step(out);
  return out;
}

SheetMesh lift_above_plane(SheetMesh surface, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& up) {
  for (int i = 0; i < surface.num_vertices(); ++i) {
    const Eigen::Vector3d p = surface.positions.row(i).transpose();
    const double h = (p - origin).dot(up);
    if (h < 0.0) surface.positions.row(i) = (p - h * up).transpose();
  }
  return surface;
}

Eigen::MatrixX3d carried_normals(const SheetMesh& mesh, const SheetMesh& refined) {
  const Eigen::MatrixX3d vn = vertex_normals(mesh);
  Eigen::MatrixX3d out(refined.num_vertices(), 3);
  out.topRows(mesh.num_vertices()) = vn;  // refine_surface keeps the original vertices first
  const UvLocator loc(mesh);
  for (int i = mesh.num_vertices(); i < refined.num_vertices(); ++i) {
    const auto hit = loc.locate(refined.uv.row(i).transpose(), 1e-9);
    if (!hit)
      throw InputError("refined vertex " + std::to_string(i) +
                       " lies outside the sheet's UV domain");
    Vec3 n = Vec3::Zero();
    for (int k = 0; k < 3; ++k) n += hit->barycentric[k] * Vec3(vn.row(mesh.faces(hit->face, k)));
    out.row(i) = n.normalized().transpose();
  }
  return out;
}

SheetMesh flip_sheet(const SheetMesh& mesh) {
  SheetMesh out = mesh;
  out.positions.col(0) = -mesh.positions.col(0);
  out.uv.col(0) = (1.0 - mesh.uv.col(0).array()).matrix();
  out.faces.col(1) = mesh.faces.col(2);
  out.faces.col(2) = mesh.faces.col(1);
  return out;
}

}  // namespace papersim::scenegen
