#include "remesh/mesh_editor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "common/assert.hpp"
#include "remesh/sizing.hpp"

namespace papersim::remesh {

using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;
using Triangle2 = Eigen::Matrix<double, 3, 2>;

double signed_area2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Eigen::Vector2d e1 = b - a, e2 = c - a;
  return e1.x() * e2.y() - e1.y() * e2.x();
}

bool is_proper_triangle(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                        const Eigen::Vector2d& c) {
  const double longest2 =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  return signed_area2(a, b, c) > 1e-10 * longest2;
}

namespace {

double polygon_area(const std::vector<Eigen::Vector2d>& p) {
  double a2 = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& q = p[i];
    const Eigen::Vector2d& r = p[(i + 1) % p.size()];
    a2 += q.x() * r.y() - q.y() * r.x();
  }
  return 0.5 * a2;
}

/// Keeps the part of `poly` on the left of the directed line p0 -> p1.
std::vector<Eigen::Vector2d> clip_half_plane(const std::vector<Eigen::Vector2d>& poly,
                                             const Eigen::Vector2d& p0, const Eigen::Vector2d& p1) {
  std::vector<Eigen::Vector2d> out;
  const Eigen::Vector2d d = p1 - p0;
  auto side = [&](const Eigen::Vector2d& p) {
    return d.x() * (p.y() - p0.y()) - d.y() * (p.x() - p0.x());
  };
  for (size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[(i + 1) % poly.size()];
    const double sa = side(a), sb = side(b);
    if (sa >= 0) out.push_back(a);
    if ((sa >= 0) != (sb >= 0)) out.push_back(a + (sa / (sa - sb)) * (b - a));
  }
  return out;
}

double triangle_area(const Triangle2& t) {
  return 0.5 * signed_area2(t.row(0).transpose(), t.row(1).transpose(), t.row(2).transpose());
}

/// "inverted" when a new face is clockwise or has a negligible area, "degenerate" when it is
/// thinner than EDIT_ASPECT_MIN (e.g. a split whose opposite vertex is nearly on the split line,
/// or a flip or collapse making a face through three nearly collinear vertices).
std::string quality_reason(const EditProposal& p) {
  for (const Triangle2& t : p.material) {
    const Eigen::Vector2d a = t.row(0).transpose(), b = t.row(1).transpose(),
                          c = t.row(2).transpose();
    if (!is_proper_triangle(a, b, c)) return "inverted";
    if (aspect_ratio(a, b, c) < EDIT_ASPECT_MIN) return "degenerate";
  }
  return "";
}

Eigen::Vector3d to_eigen(const OpenMesh::Vec3d& v) { return {v[0], v[1], v[2]}; }
OpenMesh::Vec3d to_om(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

double triangle_overlap(const Triangle2& a, const Triangle2& b) {
  std::vector<Eigen::Vector2d> poly = {a.row(0).transpose(), a.row(1).transpose(),
                                       a.row(2).transpose()};
  for (int k = 0; k < 3 && !poly.empty(); ++k)
    poly = clip_half_plane(poly, b.row(k).transpose(), b.row((k + 1) % 3).transpose());
  return poly.size() < 3 ? 0.0 : std::max(0.0, polygon_area(poly));
}

MeshEditor::MeshEditor(SheetMesh& mesh, RemeshState& state, EditVeto veto)
    : m_sheet(mesh), m_state(state), m_veto(std::move(veto)) {
  check_state(mesh, state);
  TriMesh& m = m_sheet.mesh();
  m_had_vertex_status = m.has_vertex_status();
  m_had_edge_status = m.has_edge_status();
  m_had_face_status = m.has_face_status();
  if (!m_had_vertex_status) m.request_vertex_status();
  if (!m_had_edge_status) m.request_edge_status();
  if (!m_had_face_status) m.request_face_status();
  m.add_property(m_position, "remesh:position");
  m.add_property(m_velocity, "remesh:velocity");
  m.add_property(m_metric, "remesh:metric");
  m.add_property(m_distance, "remesh:obstacle_distance");
  m_has_distance = state.obstacle_distance.size() > 0;
  for (auto v : m.vertices()) {
    m.property(m_position, v) = to_om(state.positions.row(v.idx()).transpose());
    m.property(m_velocity, v) = to_om(state.velocities.row(v.idx()).transpose());
    m.property(m_metric, v) = OpenMesh::Vec3d(0, 0, 0);
    m.property(m_distance, v) = m_has_distance ? state.obstacle_distance(v.idx()) : 0.0;
  }
}

MeshEditor::~MeshEditor() {
  try {
    finish();
  } catch (...) {
    // Only allocation can fail here; a destructor must not throw.
  }
}

Eigen::Vector3d MeshEditor::position(VertexHandle v) const {
  return to_eigen(mesh().property(m_position, v));
}

Eigen::Vector2d MeshEditor::material(VertexHandle v) const {
  const auto& p = mesh().point(v);
  return {p[0], p[1]};
}

double MeshEditor::face_area(FaceHandle f) const {
  Triangle2 x;
  int k = 0;
  for (auto v : mesh().fv_range(f)) x.row(k++) = material(v).transpose();
  return triangle_area(x);
}

Eigen::Matrix2d MeshEditor::metric(VertexHandle v) const {
  const OpenMesh::Vec3d& m = mesh().property(m_metric, v);
  Eigen::Matrix2d out;
  out << m[0], m[2], m[2], m[1];
  return out;
}

void MeshEditor::set_metric(VertexHandle v, const Eigen::Matrix2d& m) {
  m_sheet.mesh().property(m_metric, v) =
      OpenMesh::Vec3d(m(0, 0), m(1, 1), 0.5 * (m(0, 1) + m(1, 0)));
}

void MeshEditor::refuse(const std::string& reason) { ++m_stats.refusals[reason]; }

bool MeshEditor::accept(const EditProposal& proposal, const std::string& own_reason,
                        const EditCheck& check) {
  if (m_finished) throw std::logic_error("MeshEditor: edit after finish()");
  if (!own_reason.empty()) {
    refuse(own_reason);
    return false;
  }
  if (check) {
    const std::string reason = check(proposal);
    if (!reason.empty()) {
      refuse(reason);
      return false;
    }
  }
  if (m_veto) {
    const std::string reason = m_veto(proposal);
    if (!reason.empty()) {
      refuse("veto: " + reason);
      return false;
    }
  }
  return true;
}

void MeshEditor::fill_geometry(EditProposal& p, const Eigen::Vector3d& inserted_world,
                               const Eigen::Vector2d& inserted_material) const {
  p.editor = this;
  p.world.clear();
  p.material.clear();
  for (const auto& face : p.vertices) {
    Eigen::Matrix3d w;
    Triangle2 x;
    for (int k = 0; k < 3; ++k) {
      const bool is_new = face[k] < 0;  // the vertex a split inserts
      const Eigen::Vector3d world = is_new ? inserted_world : position(VertexHandle(face[k]));
      const Eigen::Vector2d mat = is_new ? inserted_material : material(VertexHandle(face[k]));
      w.row(k) = world.transpose();
      x.row(k) = mat.transpose();
    }
    p.world.push_back(w);
    p.material.push_back(x);
  }
}

EditProposal MeshEditor::propose_split(EdgeHandle e) const {
  const TriMesh& m = mesh();
  EditProposal p;
  p.kind = EditKind::split;
  for (int s = 0; s < 2; ++s) {
    const HalfedgeHandle h = m.halfedge_handle(e, s);
    if (m.is_boundary(h)) continue;
    const int a = m.from_vertex_handle(h).idx(), b = m.to_vertex_handle(h).idx();
    const int c = m.to_vertex_handle(m.next_halfedge_handle(h)).idx();
    p.vertices.push_back({a, -1, c});
    p.vertices.push_back({-1, b, c});
    p.removed_faces.push_back(m.face_handle(h).idx());
  }
  const VertexHandle a = m.from_vertex_handle(m.halfedge_handle(e, 0));
  const VertexHandle b = m.to_vertex_handle(m.halfedge_handle(e, 0));
  fill_geometry(p, 0.5 * (position(a) + position(b)), 0.5 * (material(a) + material(b)));
  return p;
}

EditProposal MeshEditor::propose_flip(EdgeHandle e) const {
  const TriMesh& m = mesh();
  EditProposal p;
  p.kind = EditKind::flip;
  const HalfedgeHandle h0 = m.halfedge_handle(e, 0), h1 = m.halfedge_handle(e, 1);
  if (!m.is_boundary(h0) && !m.is_boundary(h1)) {
    // Faces (a, b, c) and (b, a, d): the quad a, d, b, c is counter-clockwise.
    const int a = m.from_vertex_handle(h0).idx(), b = m.to_vertex_handle(h0).idx();
    const int c = m.to_vertex_handle(m.next_halfedge_handle(h0)).idx();
    const int d = m.to_vertex_handle(m.next_halfedge_handle(h1)).idx();
    p.vertices.push_back({a, d, c});
    p.vertices.push_back({d, b, c});
    p.removed_faces = {m.face_handle(h0).idx(), m.face_handle(h1).idx()};
  }
  fill_geometry(p, Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero());
  return p;
}

EditProposal MeshEditor::propose_collapse(HalfedgeHandle h) const {
  const TriMesh& m = mesh();
  EditProposal p;
  p.kind = EditKind::collapse;
  const VertexHandle u = m.from_vertex_handle(h), w = m.to_vertex_handle(h);
  for (auto f : m.vf_range(u)) {
    p.removed_faces.push_back(f.idx());
    std::array<int, 3> corners{};
    bool has_w = false;
    int k = 0;
    for (auto v : m.fv_range(f)) {
      has_w = has_w || v == w;
      corners[k++] = v == u ? w.idx() : v.idx();
    }
    if (!has_w) p.vertices.push_back(corners);
  }
  fill_geometry(p, Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero());
  return p;
}

VertexHandle MeshEditor::add_midpoint(VertexHandle a, VertexHandle b) {
  TriMesh& m = m_sheet.mesh();
  // The midpoint of two points on an axis-aligned boundary line is exactly on that line.
  const VertexHandle v = m.add_vertex((m.point(a) + m.point(b)) * 0.5);
  m.property(m_position, v) = (m.property(m_position, a) + m.property(m_position, b)) * 0.5;
  m.property(m_velocity, v) = (m.property(m_velocity, a) + m.property(m_velocity, b)) * 0.5;
  m.property(m_metric, v) = (m.property(m_metric, a) + m.property(m_metric, b)) * 0.5;
  m.property(m_distance, v) = 0.5 * (m.property(m_distance, a) + m.property(m_distance, b));
  return v;
}

std::vector<MeshEditor::ParentFace> MeshEditor::faces_of_edge(EdgeHandle e) const {
  const TriMesh& m = mesh();
  std::vector<ParentFace> parents;
  for (int s = 0; s < 2; ++s) {
    const HalfedgeHandle h = m.halfedge_handle(e, s);
    if (m.is_boundary(h)) continue;
    const FaceHandle f = m.face_handle(h);
    parents.push_back({m.to_vertex_handle(m.next_halfedge_handle(h)),
                       m.property(m_sheet.plastic_curvature_handle(), f),
                       m.property(m_sheet.damage_handle(), f), face_area(f)});
  }
  return parents;
}

void MeshEditor::pass_to_children(VertexHandle v, std::vector<ParentFace>& parents) {
  TriMesh& m = m_sheet.mesh();
  // A child is recognised by its parent's vertex opposite the split edge.
  std::vector<std::pair<FaceHandle, ParentFace*>> children;
  for (auto f : m.vf_range(v)) {
    ParentFace* parent = nullptr;
    for (auto c : m.fv_range(f))
      for (ParentFace& p : parents)
        if (c == p.opposite) parent = &p;
    PAPERSIM_ASSERT(parent != nullptr, "split: a child face without its parent");
    parent->children_area += face_area(f);
    children.emplace_back(f, parent);
  }
  // Each child inherits its parent's value, scaled so that the area integral is exact.
  for (auto& [f, parent] : children) {
    const double scale = parent->area / parent->children_area;
    m.property(m_sheet.plastic_curvature_handle(), f) = parent->plastic * scale;
    m.property(m_sheet.damage_handle(), f) = parent->damage * scale;
  }
}

VertexHandle MeshEditor::split(EdgeHandle e, const EditCheck& check) {
  TriMesh& m = m_sheet.mesh();
  PAPERSIM_ASSERT(!m_finished, "MeshEditor::split: after finish()");
  PAPERSIM_ASSERT(e.is_valid() && e.idx() < static_cast<int>(m.n_edges()) && !m.status(e).deleted(),
                  "MeshEditor::split: not an edge of the mesh");
  const EditProposal p = propose_split(e);
  if (!accept(p, quality_reason(p), check)) return VertexHandle();
  std::vector<ParentFace> parents = faces_of_edge(e);
  const VertexHandle v = add_midpoint(m.from_vertex_handle(m.halfedge_handle(e, 0)),
                                      m.to_vertex_handle(m.halfedge_handle(e, 0)));
  m.split(e, v);
  pass_to_children(v, parents);
  ++m_stats.splits;
  return v;
}

bool MeshEditor::flip(EdgeHandle e, const EditCheck& check) {
  TriMesh& m = m_sheet.mesh();
  PAPERSIM_ASSERT(!m_finished, "MeshEditor::flip: after finish()");
  PAPERSIM_ASSERT(e.is_valid() && e.idx() < static_cast<int>(m.n_edges()) && !m.status(e).deleted(),
                  "MeshEditor::flip: not an edge of the mesh");
  std::string own;
  if (m.is_boundary(e))
    own = "boundary";
  else if (!m.is_flip_ok(e))
    own = "topology";
  const EditProposal p = propose_flip(e);
  if (own.empty()) own = quality_reason(p);
  if (!accept(p, own, check)) return false;
  const FaceHandle f0 = m.face_handle(m.halfedge_handle(e, 0));
  const FaceHandle f1 = m.face_handle(m.halfedge_handle(e, 1));
  const double a0 = face_area(f0), a1 = face_area(f1);
  const auto& kh = m_sheet.plastic_curvature_handle();
  const auto& dh = m_sheet.damage_handle();
  const OpenMesh::Vec3d k_int = m.property(kh, f0) * a0 + m.property(kh, f1) * a1;
  const double d_int = m.property(dh, f0) * a0 + m.property(dh, f1) * a1;
  m.flip(e);
  const double a_new = face_area(f0) + face_area(f1);
  for (FaceHandle f : {f0, f1}) {
    m.property(kh, f) = k_int / a_new;
    m.property(dh, f) = d_int / a_new;
  }
  ++m_stats.flips;
  return true;
}

std::string MeshEditor::collapse_boundary_reason(HalfedgeHandle h) const {
  const TriMesh& m = mesh();
  const VertexHandle u = m.from_vertex_handle(h);
  if (!m.is_boundary(u)) return "";
  // A boundary vertex may only slide along a boundary edge, and only where the boundary is
  // straight (a corner of the sheet stays).
  if (!m.is_boundary(m.edge_handle(h))) return "boundary";
  HalfedgeHandle out;
  for (auto oh : m.voh_range(u))
    if (m.is_boundary(oh)) out = oh;
  if (!out.is_valid()) return "boundary";
  const VertexHandle next = m.to_vertex_handle(out);
  const VertexHandle prev = m.from_vertex_handle(m.prev_halfedge_handle(out));
  const Eigen::Vector2d a = material(u) - material(prev), b = material(next) - material(u);
  const double cross = a.x() * b.y() - a.y() * b.x();
  if (std::abs(cross) > 1e-12 * a.norm() * b.norm() || a.dot(b) <= 0) return "boundary";
  return "";
}

bool MeshEditor::collapse(HalfedgeHandle h, const EditCheck& check) {
  TriMesh& m = m_sheet.mesh();
  PAPERSIM_ASSERT(!m_finished, "MeshEditor::collapse: after finish()");
  PAPERSIM_ASSERT(h.is_valid() && h.idx() < static_cast<int>(m.n_halfedges()) &&
                      !m.status(m.edge_handle(h)).deleted(),
                  "MeshEditor::collapse: not a half-edge of the mesh");
  std::string own;
  if (!m.is_collapse_ok(h)) own = "topology";
  if (own.empty()) own = collapse_boundary_reason(h);
  EditProposal p;
  if (own.empty()) {
    p = propose_collapse(h);
    own = quality_reason(p);
  }
  if (!accept(p, own, check)) return false;
  transfer_collapse(h);
  ++m_stats.collapses;
  return true;
}

namespace {

/// A face of the fan around a collapsing vertex, before or after the collapse.
struct FanFace {
  FaceHandle f;
  Triangle2 x;  ///< material corners [m]
  double area;  ///< material area [m^2]
  OpenMesh::Vec3d plastic = {0, 0, 0};
  double damage = 0.0;
};

/// The new faces tile the same polygon as the old ones: each old face's integral is shared among
/// the new faces in proportion to their overlaps, normalised so that it is conserved exactly.
void share_by_overlap(const std::vector<FanFace>& old_faces, std::vector<FanFace>& new_faces) {
  std::vector<double> overlap(new_faces.size());
  for (const FanFace& o : old_faces) {
    double total = 0.0;
    for (size_t i = 0; i < new_faces.size(); ++i)
      total += overlap[i] = triangle_overlap(new_faces[i].x, o.x);
    if (!(total > 0)) {
      // Numerically no overlap (a sliver): share by area.
      total = 0.0;
      for (size_t i = 0; i < new_faces.size(); ++i) total += overlap[i] = new_faces[i].area;
    }
    for (size_t i = 0; i < new_faces.size(); ++i) {
      const double share = o.area * overlap[i] / total;
      new_faces[i].plastic += o.plastic * share;
      new_faces[i].damage += o.damage * share;
    }
  }
  for (FanFace& n : new_faces) {
    n.plastic /= n.area;
    n.damage /= n.area;
  }
}

}  // namespace

void MeshEditor::transfer_collapse(HalfedgeHandle h) {
  TriMesh& m = m_sheet.mesh();
  const auto& kh = m_sheet.plastic_curvature_handle();
  const auto& dh = m_sheet.damage_handle();
  const VertexHandle u = m.from_vertex_handle(h), w = m.to_vertex_handle(h);
  std::vector<FanFace> old_faces, new_faces;
  for (auto f : m.vf_range(u)) {
    Triangle2 before, after;
    bool has_w = false;
    int k = 0;
    for (auto v : m.fv_range(f)) {
      has_w = has_w || v == w;
      before.row(k) = material(v).transpose();
      after.row(k++) = material(v == u ? w : VertexHandle(v)).transpose();
    }
    old_faces.push_back({f, before, triangle_area(before), m.property(kh, f), m.property(dh, f)});
    if (!has_w) new_faces.push_back({f, after, triangle_area(after)});
  }
  share_by_overlap(old_faces, new_faces);
  m.collapse(h);
  for (const FanFace& n : new_faces) {
    m.property(kh, n.f) = n.plastic;
    m.property(dh, n.f) = n.damage;
  }
}

void MeshEditor::finish() {
  if (m_finished) return;
  m_finished = true;
  TriMesh& m = m_sheet.mesh();
  m.garbage_collection();
  const int n = static_cast<int>(m.n_vertices());
  m_state.positions.resize(n, 3);
  m_state.velocities.resize(n, 3);
  if (m_has_distance) m_state.obstacle_distance.resize(n);
  for (auto v : m.vertices()) {
    m_state.positions.row(v.idx()) = to_eigen(m.property(m_position, v)).transpose();
    m_state.velocities.row(v.idx()) = to_eigen(m.property(m_velocity, v)).transpose();
    if (m_has_distance) m_state.obstacle_distance(v.idx()) = m.property(m_distance, v);
  }
  m.remove_property(m_position);
  m.remove_property(m_velocity);
  m.remove_property(m_metric);
  m.remove_property(m_distance);
  if (!m_had_face_status) m.release_face_status();
  if (!m_had_edge_status) m.release_edge_status();
  if (!m_had_vertex_status) m.release_vertex_status();
}

}  // namespace papersim::remesh
