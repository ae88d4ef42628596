#include "remesh/sheet_mesh.hpp"

#include <OpenMesh/Core/System/omstream.hh>
#include <cmath>
#include <string>
#include <vector>

#include "remesh/errors.hpp"

namespace papersim::remesh {

SheetMesh::SheetMesh() { add_properties(); }

SheetMesh::SheetMesh(const SheetMesh& other) : m_mesh(other.m_mesh) {
  // OpenMesh copies property data with the mesh; the handles are found again by name.
  m_mesh.get_property_handle(m_plastic, "plastic_curvature");
  m_mesh.get_property_handle(m_damage, "damage");
}

SheetMesh& SheetMesh::operator=(const SheetMesh& other) {
  if (this != &other) {
    m_mesh = other.m_mesh;
    m_mesh.get_property_handle(m_plastic, "plastic_curvature");
    m_mesh.get_property_handle(m_damage, "damage");
  }
  return *this;
}

void SheetMesh::add_properties() {
  m_mesh.add_property(m_plastic, "plastic_curvature");
  m_mesh.add_property(m_damage, "damage");
}

namespace {

void check_faces(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces) {
  const int nv = static_cast<int>(material_coords.rows());
  if (!material_coords.allFinite())
    throw MeshError("mesh: material coordinates contain NaN or inf");
  for (int f = 0; f < faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k)
      if (faces(f, k) < 0 || faces(f, k) >= nv)
        throw MeshError("mesh: face " + std::to_string(f) + " has vertex index " +
                        std::to_string(faces(f, k)) + " out of range");
    const Eigen::Vector2d a = material_coords.row(faces(f, 0));
    const Eigen::Vector2d e1 = Eigen::Vector2d(material_coords.row(faces(f, 1))) - a;
    const Eigen::Vector2d e2 = Eigen::Vector2d(material_coords.row(faces(f, 2))) - a;
    const double area2 = e1.x() * e2.y() - e1.y() * e2.x();
    const double scale = std::max(e1.squaredNorm(), e2.squaredNorm());
    if (!(std::abs(area2) > 1e-12 * scale) || scale == 0.0)
      throw MeshError("mesh: face " + std::to_string(f) +
                      " is degenerate in material space (zero area)");
  }
}

}  // namespace

SheetMesh::SheetMesh(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces)
    : SheetMesh() {
  check_faces(material_coords, faces);
  // OpenMesh prints "PolyMeshT::add_face: complex edge" to its error stream for a face it
  // refuses; the library never prints (a refused face is a MeshError below), so that stream is
  // switched off once, for the whole process, before the first face is added.
  static const bool openmesh_quiet = (omerr().disable(), true);
  (void)openmesh_quiet;
  std::vector<TriMesh::VertexHandle> vh(material_coords.rows());
  for (int v = 0; v < material_coords.rows(); ++v)
    vh[v] = m_mesh.add_vertex(TriMesh::Point(material_coords(v, 0), material_coords(v, 1), 0.0));
  for (int f = 0; f < faces.rows(); ++f) {
    auto a = vh[faces(f, 0)], b = vh[faces(f, 1)], c = vh[faces(f, 2)];
    // Orient every face counter-clockwise in material space.
    const Eigen::Vector2d pa = material_coords.row(faces(f, 0));
    const Eigen::Vector2d e1 = Eigen::Vector2d(material_coords.row(faces(f, 1))) - pa;
    const Eigen::Vector2d e2 = Eigen::Vector2d(material_coords.row(faces(f, 2))) - pa;
    if (e1.x() * e2.y() - e1.y() * e2.x() < 0) std::swap(b, c);
    if (!m_mesh.add_face(a, b, c).is_valid())
      throw MeshError("mesh: face " + std::to_string(f) + " makes an edge non-manifold");
  }
  if (m_mesh.n_faces() == 0) throw MeshError("mesh: no faces");
  for (auto f : m_mesh.faces()) {
    m_mesh.property(m_plastic, f) = OpenMesh::Vec3d(0, 0, 0);
    m_mesh.property(m_damage, f) = 0.0;
  }
}

Eigen::MatrixX2d SheetMesh::material_coords() const {
  Eigen::MatrixX2d m(num_vertices(), 2);
  for (auto v : m_mesh.vertices()) {
    const auto& p = m_mesh.point(v);
    m(v.idx(), 0) = p[0];
    m(v.idx(), 1) = p[1];
  }
  return m;
}

Eigen::Vector2d SheetMesh::material_coord(int v) const {
  const auto& p = m_mesh.point(TriMesh::VertexHandle(v));
  return {p[0], p[1]};
}

Eigen::MatrixX3i SheetMesh::faces() const {
  Eigen::MatrixX3i f(num_faces(), 3);
  for (auto fh : m_mesh.faces()) {
    int k = 0;
    for (auto v : m_mesh.fv_range(fh)) f(fh.idx(), k++) = v.idx();
  }
  return f;
}

Eigen::MatrixX3d SheetMesh::plastic_curvature() const {
  Eigen::MatrixX3d k(num_faces(), 3);
  for (auto f : m_mesh.faces()) {
    const auto& p = m_mesh.property(m_plastic, f);
    k.row(f.idx()) << p[0], p[1], p[2];
  }
  return k;
}

void SheetMesh::set_plastic_curvature(const Eigen::MatrixX3d& k) {
  if (k.rows() != num_faces()) throw MeshError("mesh: plastic curvature needs one row per face");
  for (auto f : m_mesh.faces())
    m_mesh.property(m_plastic, f) = OpenMesh::Vec3d(k(f.idx(), 0), k(f.idx(), 1), k(f.idx(), 2));
}

Eigen::VectorXd SheetMesh::damage() const {
  Eigen::VectorXd d(num_faces());
  for (auto f : m_mesh.faces()) d(f.idx()) = m_mesh.property(m_damage, f);
  return d;
}

void SheetMesh::set_damage(const Eigen::VectorXd& d) {
  if (d.size() != num_faces()) throw MeshError("mesh: damage needs one value per face");
  for (auto f : m_mesh.faces()) m_mesh.property(m_damage, f) = d(f.idx());
}

SheetMesh SheetMesh::rebuilt() const {
  SheetMesh m(material_coords(), faces());
  m.set_plastic_curvature(plastic_curvature());
  m.set_damage(damage());
  return m;
}

Eigen::Vector4d SheetMesh::material_bounds() const {
  const Eigen::MatrixX2d m = material_coords();
  return {m.col(0).minCoeff(), m.col(1).minCoeff(), m.col(0).maxCoeff(), m.col(1).maxCoeff()};
}

Hinges interior_hinges(const SheetMesh& sheet) {
  const TriMesh& mesh = sheet.mesh();
  std::vector<Eigen::Vector4i> verts;
  std::vector<Eigen::Vector2i> faces;
  verts.reserve(mesh.n_edges());
  faces.reserve(mesh.n_edges());
  for (auto e : mesh.edges()) {
    if (mesh.is_boundary(e)) continue;
    auto h = mesh.halfedge_handle(e, 0);
    auto ho = mesh.opposite_halfedge_handle(h);
    // h runs v0 -> v1 inside face A (counter-clockwise), so its next halfedge ends at a.
    const int v0 = mesh.from_vertex_handle(h).idx();
    const int v1 = mesh.to_vertex_handle(h).idx();
    const int a = mesh.to_vertex_handle(mesh.next_halfedge_handle(h)).idx();
    const int b = mesh.to_vertex_handle(mesh.next_halfedge_handle(ho)).idx();
    verts.emplace_back(v0, v1, a, b);
    faces.emplace_back(mesh.face_handle(h).idx(), mesh.face_handle(ho).idx());
  }
  Hinges hinges;
  hinges.vertices.resize(verts.size(), 4);
  hinges.faces.resize(faces.size(), 2);
  for (size_t i = 0; i < verts.size(); ++i) {
    hinges.vertices.row(i) = verts[i].transpose();
    hinges.faces.row(i) = faces[i].transpose();
  }
  return hinges;
}

Eigen::MatrixX3i face_hinges(const SheetMesh& sheet, const Hinges& hinges) {
  const Eigen::MatrixX3i faces = sheet.faces();
  Eigen::MatrixX3i fh = Eigen::MatrixX3i::Constant(faces.rows(), 3, -1);
  for (int h = 0; h < hinges.vertices.rows(); ++h) {
    const int v0 = hinges.vertices(h, 0), v1 = hinges.vertices(h, 1);
    for (int s = 0; s < 2; ++s) {
      const int f = hinges.faces(h, s);
      for (int k = 0; k < 3; ++k) {
        const int p = faces(f, (k + 1) % 3), q = faces(f, (k + 2) % 3);
        if ((p == v0 && q == v1) || (p == v1 && q == v0)) fh(f, k) = h;
      }
    }
  }
  return fh;
}

std::vector<int> faces_inside(const SheetMesh& mesh, const Eigen::Vector4d& box) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  auto inside = [&](int v) {
    return X(v, 0) >= box[0] - 1e-12 && X(v, 1) >= box[1] - 1e-12 && X(v, 0) <= box[2] + 1e-12 &&
           X(v, 1) <= box[3] + 1e-12;
  };
  std::vector<int> faces;
  for (int f = 0; f < F.rows(); ++f)
    if (inside(F(f, 0)) && inside(F(f, 1)) && inside(F(f, 2))) faces.push_back(f);
  return faces;
}

}  // namespace papersim::remesh
