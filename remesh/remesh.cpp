#include "remesh/remesh.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "remesh/mesh_editor.hpp"
#include "remesh/sizing.hpp"

namespace papersim::remesh {

namespace {

using OpenMesh::EdgeHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;
using VertexPair = std::pair<int, int>;

/// Collapses are allowed only when every new edge stays below 0.9 under the metric (ArcSim's
/// hysteresis): an edge just made by a collapse is not split again by the next pass.
constexpr double COLLAPSE_SIZE2_MAX = 0.9 * 0.9;
/// A flip is wanted when the two angles opposite the edge, measured in the metric, exceed pi by
/// this much in sin(alpha + beta) (Bossen and Heckbert 1996, ArcSim's edge_flip_threshold), so that
/// nearly cocircular quads do not flip back and forth.
constexpr double FLIP_THRESHOLD = 1e-2;
/// Bound on the sweeps of the global flip phase (each sweep flips every edge that wants it).
constexpr int FLIP_SWEEPS_MAX = 100;
/// Bound on the local flip rounds after a split or a collapse.
constexpr int LOCAL_FLIP_ROUNDS_MAX = 8;
/// A face thinner than this fraction of aspect_min is a sliver: no metric asks for it (the
/// metric's own aspect floor is aspect_min), and the Morley plate's curvature on it grows as one
/// over its height. Midpoint splits make them next to the boundary, where no flip can repair them.
constexpr double SLIVER_FRACTION = 0.5;
/// Bound on the sweeps of the sliver phase.
constexpr int SLIVER_SWEEPS_MAX = 10;

VertexPair key(VertexHandle a, VertexHandle b) { return std::minmax(a.idx(), b.idx()); }

/// l^2 = u^T M u for the material edge vector u, M the mean of the end vertices' metrics.
double edge_size2(const MeshEditor& ed, VertexHandle a, VertexHandle b) {
  const Eigen::Vector2d u = ed.material(b) - ed.material(a);
  return u.dot(0.5 * (ed.metric(a) + ed.metric(b)) * u);
}

/// Signed dihedral angle [rad] of the hinge x0 -> x1 between faces (x0, x1, xa) and (x1, x0, xb),
/// 0 when a face is degenerate in world space.
double hinge_angle(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& xa,
                   const Eigen::Vector3d& xb) {
  const Eigen::Vector3d e = x1 - x0;
  const Eigen::Vector3d n0 = e.cross(xa - x0), n1 = (xb - x0).cross(e);
  if (!(n0.norm() > 1e-12 * e.norm() * (xa - x0).norm()) ||
      !(n1.norm() > 1e-12 * e.norm() * (xb - x0).norm()))
    return 0.0;
  return std::atan2(n0.cross(n1).dot(e.normalized()), n0.dot(n1));
}

/// sin and cos of the angle at `apex` between p - apex and q - apex, measured in metric m.
std::pair<double, double> metric_angle(const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                                       const Eigen::Vector2d& apex, const Eigen::Matrix2d& m) {
  const Eigen::Vector2d u = p - apex, v = q - apex;
  const double norms = std::sqrt(u.dot(m * u) * v.dot(m * v));
  if (!(norms > 0)) return {0.0, 1.0};
  const double wedge = std::abs(u.x() * v.y() - u.y() * v.x());
  return {std::sqrt(std::max(m.determinant(), 0.0)) * wedge / norms, u.dot(m * v) / norms};
}

/// The anisotropic Delaunay condition: flip when the angles opposite the edge sum to more than pi
/// under the mean metric of the four vertices.
bool wants_flip(const MeshEditor& ed, EdgeHandle e) {
  const TriMesh& m = ed.mesh();
  if (m.is_boundary(e)) return false;
  const HalfedgeHandle h0 = m.halfedge_handle(e, 0), h1 = m.halfedge_handle(e, 1);
  const VertexHandle a = m.from_vertex_handle(h0), b = m.to_vertex_handle(h0);
  const VertexHandle c = m.to_vertex_handle(m.next_halfedge_handle(h0));
  const VertexHandle d = m.to_vertex_handle(m.next_halfedge_handle(h1));
  const Eigen::Matrix2d mm = 0.25 * (ed.metric(a) + ed.metric(b) + ed.metric(c) + ed.metric(d));
  const auto [sin_c, cos_c] = metric_angle(ed.material(a), ed.material(b), ed.material(c), mm);
  const auto [sin_d, cos_d] = metric_angle(ed.material(a), ed.material(b), ed.material(d), mm);
  return sin_c * cos_d + cos_c * sin_d < -FLIP_THRESHOLD;
}

/// Refuses a flip across a sharp hinge, or one that would make a sharp hinge: it would cut a
/// crease. Proposal faces are (a, d, c) and (d, b, c).
MeshEditor::EditCheck crease_check(double angle_max) {
  return [angle_max](const EditProposal& p) -> std::string {
    const Eigen::Vector3d a = p.world[0].row(0), d = p.world[0].row(1), c = p.world[0].row(2);
    const Eigen::Vector3d b = p.world[1].row(1);
    if (std::abs(hinge_angle(a, b, c, d)) > angle_max) return "crease";
    if (std::abs(hinge_angle(c, d, b, a)) > angle_max) return "crease";
    return "";
  };
}

/// Refuses a collapse that would make an edge at the survivor longer than 0.9 under the metric
/// ("too long") or a face thinner than aspect_min ("too thin").
MeshEditor::EditCheck collapse_check(const MeshEditor& ed, VertexHandle survivor,
                                     double aspect_min) {
  return [&ed, survivor, aspect_min](const EditProposal& p) -> std::string {
    for (const auto& face : p.vertices)
      for (int v : face)
        if (v != survivor.idx() && edge_size2(ed, survivor, VertexHandle(v)) > COLLAPSE_SIZE2_MAX)
          return "too long";
    for (const auto& x : p.material)
      if (aspect_ratio(x.row(0).transpose(), x.row(1).transpose(), x.row(2).transpose()) <
          aspect_min)
        return "too thin";
    return "";
  };
}

/// Material aspect ratio of face f of the working mesh.
double face_aspect(const MeshEditor& ed, OpenMesh::FaceHandle f) {
  Eigen::Vector2d x[3];
  int k = 0;
  for (auto v : ed.mesh().fv_range(f)) x[k++] = ed.material(v);
  return aspect_ratio(x[0], x[1], x[2]);
}

/// Smallest aspect ratio of the faces edit p removes, and of the faces it creates.
std::pair<double, double> thinnest_before_after(const MeshEditor& ed, const EditProposal& p) {
  double before = 1.0, after = 1.0;
  for (int f : p.removed_faces) before = std::min(before, face_aspect(ed, OpenMesh::FaceHandle(f)));
  for (const auto& x : p.material)
    after = std::min(
        after, aspect_ratio(x.row(0).transpose(), x.row(1).transpose(), x.row(2).transpose()));
  return {before, after};
}

/// Accepts an edit only when its thinnest new face is thicker than the thinnest face it removes
/// ("no better"): every sliver repair strictly raises the local minimum aspect ratio.
MeshEditor::EditCheck improves_check(const MeshEditor& ed) {
  return [&ed](const EditProposal& p) -> std::string {
    const auto [before, after] = thinnest_before_after(ed, p);
    return after > before ? std::string() : std::string("no better");
  };
}

/// Accepts a split only when its thinnest new face is no thinner than `threshold` or than the
/// thinnest face it replaces ("thin split", RemeshParams::refuse_thin_splits).
MeshEditor::EditCheck thick_split_check(const MeshEditor& ed, double threshold) {
  return [&ed, threshold](const EditProposal& p) -> std::string {
    const auto [before, after] = thinnest_before_after(ed, p);
    return after < std::min(threshold, before) ? std::string("thin split") : std::string();
  };
}

/// Repairs sliver f by a collapse: the vertex opposite its longest edge into the nearer end of
/// that edge, else into the farther end, else either end into the opposite vertex; the first
/// collapse that makes the neighbourhood less thin wins. No flip: the Delaunay flips have had their
/// say, and a sliver next to the boundary has no edge to flip.
bool repair_sliver(MeshEditor& ed, OpenMesh::FaceHandle f) {
  const TriMesh& m = ed.mesh();
  HalfedgeHandle longest;
  double l2 = -1;
  for (auto h : m.fh_range(f)) {
    const double l =
        (ed.material(m.to_vertex_handle(h)) - ed.material(m.from_vertex_handle(h))).squaredNorm();
    if (l > l2) l2 = l, longest = h;
  }
  VertexHandle a = m.from_vertex_handle(longest), b = m.to_vertex_handle(longest);
  const VertexHandle p = m.to_vertex_handle(m.next_halfedge_handle(longest));
  if ((ed.material(b) - ed.material(p)).squaredNorm() <
      (ed.material(a) - ed.material(p)).squaredNorm())
    std::swap(a, b);
  for (auto [removed, survivor] :
       {std::pair{p, a}, std::pair{p, b}, std::pair{a, p}, std::pair{b, p}}) {
    const HalfedgeHandle h = m.find_halfedge(removed, survivor);
    if (h.is_valid() && ed.collapse(h, improves_check(ed))) return true;
  }
  return false;
}

/// Repairs every face thinner than SLIVER_FRACTION * aspect_min, sweep after sweep, while a
/// repair succeeds. The repairs ignore the metric's lengths: an edge they make too long is split by
/// the next pass.
void sliver_phase(MeshEditor& ed, const RemeshParams& params) {
  const double threshold = SLIVER_FRACTION * params.aspect_min;
  for (int sweep = 0; sweep < SLIVER_SWEEPS_MAX; ++sweep) {
    std::vector<OpenMesh::FaceHandle> slivers;
    for (auto f : ed.mesh().faces())
      if (face_aspect(ed, f) < threshold) slivers.push_back(f);
    bool repaired = false;
    for (auto f : slivers)
      if (!ed.mesh().status(f).deleted() && face_aspect(ed, f) < threshold && repair_sliver(ed, f))
        repaired = true;
    if (!repaired) return;
  }
}

/// Flips the edges of the faces around v to the anisotropic Delaunay condition.
void flip_around(MeshEditor& ed, VertexHandle v, const RemeshParams& params) {
  for (int round = 0; round < LOCAL_FLIP_ROUNDS_MAX; ++round) {
    std::vector<EdgeHandle> edges;
    for (auto f : ed.mesh().vf_range(v))
      for (auto e : ed.mesh().fe_range(f)) edges.push_back(e);
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    bool flipped = false;
    for (EdgeHandle e : edges)
      if (wants_flip(ed, e) && ed.flip(e, crease_check(params.flip_angle_max))) flipped = true;
    if (!flipped) return;
  }
}

/// Splits every edge longer than 1 under the metric, longest first, until none is left (or every
/// one left was refused).
void split_phase(MeshEditor& ed, const RemeshParams& params) {
  std::set<VertexPair> refused;
  const MeshEditor::EditCheck thick =
      params.refuse_thin_splits ? thick_split_check(ed, SLIVER_FRACTION * params.aspect_min)
                                : MeshEditor::EditCheck();
  for (;;) {
    std::vector<std::tuple<double, int, int>> bad;
    for (auto e : ed.mesh().edges()) {
      const auto h = ed.mesh().halfedge_handle(e, 0);
      const VertexHandle a = ed.mesh().from_vertex_handle(h), b = ed.mesh().to_vertex_handle(h);
      const double s2 = edge_size2(ed, a, b);
      if (s2 > 1.0 && !refused.count(key(a, b))) bad.emplace_back(s2, a.idx(), b.idx());
    }
    if (bad.empty()) return;
    std::sort(bad.begin(), bad.end(), std::greater<>());
    bool progress = false;
    for (const auto& [s2, ia, ib] : bad) {
      const VertexHandle a(ia), b(ib);
      const HalfedgeHandle h = ed.mesh().find_halfedge(a, b);
      if (!h.is_valid() || edge_size2(ed, a, b) <= 1.0) continue;
      const VertexHandle v = ed.split(ed.mesh().edge_handle(h), thick);
      if (!v.is_valid()) {
        refused.insert(key(a, b));
        continue;
      }
      progress = true;
      flip_around(ed, v, params);
    }
    if (!progress) return;
  }
}

/// Flips every interior edge that violates the anisotropic Delaunay condition, sweep after sweep.
void flip_phase(MeshEditor& ed, const RemeshParams& params) {
  std::set<VertexPair> refused;
  for (int sweep = 0; sweep < FLIP_SWEEPS_MAX; ++sweep) {
    bool flipped = false;
    for (auto e : ed.mesh().edges()) {
      if (!wants_flip(ed, e)) continue;
      const auto h = ed.mesh().halfedge_handle(e, 0);
      const VertexPair k = key(ed.mesh().from_vertex_handle(h), ed.mesh().to_vertex_handle(h));
      if (refused.count(k)) continue;
      if (ed.flip(e, crease_check(params.flip_angle_max)))
        flipped = true;
      else
        refused.insert(k);
    }
    if (!flipped) return;
  }
}

/// Tries to remove `removed` by collapsing it into `survivor`.
bool try_collapse(MeshEditor& ed, VertexHandle removed, VertexHandle survivor,
                  const RemeshParams& params) {
  const HalfedgeHandle h = ed.mesh().find_halfedge(removed, survivor);
  return h.is_valid() && ed.collapse(h, collapse_check(ed, survivor, params.aspect_min));
}

/// Collapses edges, shortest first under the metric, wherever the result is acceptable; an edge is
/// tried again only after an edit next to it.
void collapse_phase(MeshEditor& ed, const RemeshParams& params) {
  const TriMesh& m = ed.mesh();
  std::vector<char> active(m.n_vertices(), 1);
  for (;;) {
    std::vector<std::tuple<double, int, int>> candidates;
    for (auto e : m.edges()) {
      const auto h = m.halfedge_handle(e, 0);
      const VertexHandle a = m.from_vertex_handle(h), b = m.to_vertex_handle(h);
      if (active[a.idx()] || active[b.idx()])
        candidates.emplace_back(edge_size2(ed, a, b), a.idx(), b.idx());
    }
    std::sort(candidates.begin(), candidates.end());
    std::fill(active.begin(), active.end(), 0);
    bool progress = false;
    for (const auto& [s2, ia, ib] : candidates) {
      const VertexHandle a(ia), b(ib);
      if (m.status(a).deleted() || m.status(b).deleted()) continue;
      VertexHandle survivor = b;
      if (!try_collapse(ed, a, b, params)) {
        if (!try_collapse(ed, b, a, params)) continue;
        survivor = a;
      }
      progress = true;
      active[survivor.idx()] = 1;
      for (auto n : m.vv_range(survivor)) active[n.idx()] = 1;
      flip_around(ed, survivor, params);
    }
    if (!progress) return;
  }
}

}  // namespace

RemeshStats remesh(SheetMesh& mesh, RemeshState& state, const RemeshParams& params,
                   const EditVeto& veto) {
  check_params(params);
  check_state(mesh, state);
  // Work on copies so that a failure (an exception from the veto) leaves the inputs untouched.
  SheetMesh work(mesh);
  RemeshState work_state = state;
  const std::vector<Eigen::Matrix2d> metrics =
      vertex_metrics(work, sizing(work, work_state, params));
  work_state.membrane_strain.resize(0, 3);  // per face: stale once the faces change
  RemeshStats stats;
  {
    MeshEditor ed(work, work_state, veto);
    for (auto v : work.mesh().vertices()) ed.set_metric(v, metrics[v.idx()]);
    split_phase(ed, params);
    flip_phase(ed, params);
    collapse_phase(ed, params);
    flip_phase(ed, params);
    sliver_phase(ed, params);
    ed.finish();
    stats = ed.stats();
  }
  mesh = work;
  state = std::move(work_state);
  return stats;
}

}  // namespace papersim::remesh
