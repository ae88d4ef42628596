#include "remesh/sheet_mesh.hpp"

#include <gtest/gtest.h>

#include <iostream>

#include "remesh/errors.hpp"
#include "remesh/sheet_generator.hpp"

using namespace papersim::remesh;

TEST(SheetMesh, RectangleCountsAndArea) {
  for (auto tri : {Triangulation::alternating, Triangulation::random, Triangulation::regular}) {
    RectangleOptions o;
    o.nx = 5;
    o.ny = 7;
    o.triangulation = tri;
    o.jitter = 0.3;
    o.seed = 3;
    const SheetMesh m = make_rectangle(o);
    EXPECT_EQ(m.num_vertices(), 35);
    EXPECT_EQ(m.num_faces(), 48);
    // Euler characteristic of a disk: V - E + F = 1.
    EXPECT_EQ(m.num_vertices() - m.num_edges() + m.num_faces(), 1);
    const Eigen::MatrixX2d X = m.material_coords();
    const Eigen::MatrixX3i F = m.faces();
    double area = 0;
    for (int f = 0; f < F.rows(); ++f) {
      const Eigen::Vector2d e1 = X.row(F(f, 1)) - X.row(F(f, 0));
      const Eigen::Vector2d e2 = X.row(F(f, 2)) - X.row(F(f, 0));
      const double a = 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
      EXPECT_GT(a, 0.0) << "faces are counter-clockwise";
      area += a;
    }
    EXPECT_NEAR(area, o.width * o.height, 1e-14);
  }
}

TEST(SheetMesh, AlternatingHasNoGrain) {
  RectangleOptions o;
  o.nx = 11;
  o.ny = 11;
  const SheetMesh m = make_rectangle(o);
  const Hinges h = interior_hinges(m);
  const Eigen::MatrixX2d X = m.material_coords();
  int up = 0, down = 0;
  for (int e = 0; e < h.vertices.rows(); ++e) {
    const Eigen::Vector2d d = X.row(h.vertices(e, 1)) - X.row(h.vertices(e, 0));
    if (std::abs(d.x()) > 1e-12 && std::abs(d.y()) > 1e-12) (d.x() * d.y() > 0 ? up : down)++;
  }
  EXPECT_EQ(up, down);
}

TEST(SheetMesh, HingesAreConsistent) {
  RectangleOptions o;
  o.nx = 4;
  o.ny = 3;
  const SheetMesh m = make_rectangle(o);
  const Hinges h = interior_hinges(m);
  const int boundary_edges = 2 * (o.nx - 1) + 2 * (o.ny - 1);
  EXPECT_EQ(h.vertices.rows(), m.num_edges() - boundary_edges);
  const Eigen::MatrixX3i F = m.faces();
  const Eigen::MatrixX3i fh = face_hinges(m, h);
  for (int e = 0; e < h.vertices.rows(); ++e) {
    // (v0, v1, a) is a face in counter-clockwise order.
    const int fa = h.faces(e, 0);
    bool found = false;
    for (int k = 0; k < 3; ++k)
      found |= F(fa, k) == h.vertices(e, 0) && F(fa, (k + 1) % 3) == h.vertices(e, 1) &&
               F(fa, (k + 2) % 3) == h.vertices(e, 2);
    EXPECT_TRUE(found);
  }
  int referenced = 0;
  for (int f = 0; f < fh.rows(); ++f)
    for (int k = 0; k < 3; ++k) referenced += fh(f, k) >= 0;
  EXPECT_EQ(referenced, 2 * h.vertices.rows());
}

TEST(SheetMesh, RejectsBadInput) {
  Eigen::MatrixX2d X(4, 2);
  X << 0, 0, 1, 0, 0, 1, 2, 0;
  Eigen::MatrixX3i F(1, 3);
  F << 0, 1, 3;  // collinear: zero area
  EXPECT_THROW(SheetMesh(X, F), MeshError);
  X(1, 0) = std::nan("");
  F << 0, 1, 2;
  EXPECT_THROW(SheetMesh(X, F), MeshError);
  // Three faces on one edge: non-manifold.
  Eigen::MatrixX2d Y(5, 2);
  Y << 0, 0, 1, 0, 0.5, 1, 0.5, -1, 0.5, 0.5;
  Eigen::MatrixX3i G(3, 3);
  G << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  // The error is ours alone: OpenMesh's own "complex edge" message must not reach stderr.
  testing::internal::CaptureStderr();
  EXPECT_THROW(SheetMesh(Y, G), MeshError);
  std::cerr.flush();
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  RectangleOptions o;
  o.nx = 1;
  EXPECT_THROW(make_rectangle(o), MeshError);
}

TEST(SheetMesh, RotatedLatticeCoversTheRectangle) {
  LatticeOptions o;
  o.width = 0.1;
  o.height = 0.03;
  o.edge_length = 4e-3;
  const SheetMesh m = make_rotated_lattice(o);
  const Eigen::MatrixX2d X = m.material_coords();
  const Eigen::MatrixX3i F = m.faces();
  double area = 0, min_angle = M_PI;
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = X.row(F(f, k));
    const Eigen::Vector2d e1 = p[1] - p[0], e2 = p[2] - p[0];
    area += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d u = p[(k + 1) % 3] - p[k], w = p[(k + 2) % 3] - p[k];
      min_angle = std::min(min_angle, std::acos(u.normalized().dot(w.normalized())));
    }
  }
  EXPECT_NEAR(area, o.width * o.height, 1e-12);
  EXPECT_EQ(m.num_vertices() - m.num_edges() + m.num_faces(), 1) << "a disk";
  EXPECT_GT(min_angle, 15 * M_PI / 180) << "no slivers";
}

TEST(SheetGenerator, RotatedLatticeKeepsRequestedLinesOfVertices) {
  LatticeOptions o;
  o.width = 0.06;
  o.height = 0.02;
  o.edge_length = 2.5e-3;
  o.lines_x = {0.005};
  const SheetMesh m = make_rotated_lattice(o);
  const Eigen::MatrixX2d X = m.material_coords();
  const Eigen::MatrixX3i F = m.faces();
  // No triangle crosses the line: each lies on one side (vertices on the line count as both).
  for (int f = 0; f < F.rows(); ++f) {
    bool left = false, right = false;
    for (int k = 0; k < 3; ++k) {
      left |= X(F(f, k), 0) < 0.005 - 1e-12;
      right |= X(F(f, k), 0) > 0.005 + 1e-12;
    }
    EXPECT_FALSE(left && right) << "face " << f << " crosses x = 5 mm";
  }
  EXPECT_EQ(m.num_vertices() - m.num_edges() + m.num_faces(), 1) << "a disk";
  o.lines_x = {0.07};
  EXPECT_THROW(make_rotated_lattice(o), MeshError);
}

TEST(SheetGenerator, RotatedLatticeAtAnAspectHasFacesLongAcrossTheGrain) {
  LatticeOptions o;
  o.width = 0.15;
  o.height = 0.1;
  o.edge_length = 2.5e-3;
  o.aspect = 0.2;
  o.angle = 30 * M_PI / 180;
  o.lines_x = {0.005};
  const SheetMesh m = make_rotated_lattice(o);
  const Eigen::MatrixX2d X = m.material_coords();
  const Eigen::MatrixX3i F = m.faces();
  const Eigen::Vector2d grain(std::cos(o.angle), std::sin(o.angle)), across(-grain.y(), grain.x());
  double area = 0;
  int interior = 0;
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = X.row(F(f, k));
    const Eigen::Vector2d e1 = p[1] - p[0], e2 = p[2] - p[0], c = (p[0] + p[1] + p[2]) / 3;
    area += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
    // Away from the sides and the line, every face is half a lattice cell: its extent is one
    // spacing along the grain (2.5 mm) and one across it (12.5 mm).
    const double far = 2 * o.edge_length / o.aspect;
    if (c.x() < far || c.x() > o.width - far || c.y() < far || c.y() > o.height - far ||
        std::abs(c.x() - 0.005) < far)
      continue;
    ++interior;
    double along_lo = 1, along_hi = -1, across_lo = 1, across_hi = -1;
    for (const auto& q : p) {
      along_lo = std::min(along_lo, q.dot(grain)), along_hi = std::max(along_hi, q.dot(grain));
      across_lo = std::min(across_lo, q.dot(across)),
      across_hi = std::max(across_hi, q.dot(across));
    }
    EXPECT_NEAR(along_hi - along_lo, o.edge_length, 1e-9) << "face " << f;
    EXPECT_NEAR(across_hi - across_lo, o.edge_length / o.aspect, 1e-9) << "face " << f;
  }
  EXPECT_GT(interior, 50);
  EXPECT_NEAR(area, o.width * o.height, 1e-12);
  EXPECT_EQ(m.num_vertices() - m.num_edges() + m.num_faces(), 1) << "a disk";
  o.aspect = 0;
  EXPECT_THROW(make_rotated_lattice(o), MeshError);
  o.aspect = 1.5;
  EXPECT_THROW(make_rotated_lattice(o), MeshError);
}

namespace {
/// An edge across a cell of the lattice (its ends differ in both material coordinates): the
/// two triangles beside it make a convex quadrilateral, so flipping it leaves valid faces.
bool diagonal(const SheetMesh& m, TriMesh::EdgeHandle e) {
  if (m.mesh().is_boundary(e)) return false;
  const auto h = m.mesh().halfedge_handle(e, 0);
  const Eigen::Vector2d a = m.material_coord(m.mesh().from_vertex_handle(h).idx());
  const Eigen::Vector2d b = m.material_coord(m.mesh().to_vertex_handle(h).idx());
  const Eigen::Vector2d d = (b - a).cwiseAbs();
  return d.x() > 0.03 && d.y() > 0.03;
}
}  // namespace

// rebuilt() numbers edges as building from the arrays does (as reading a checkpoint does), and
// keeps vertices, faces and plastic state where they were, after edits that renumber nothing.
TEST(SheetMesh, RebuiltIsTheMeshReadBackFromItsArrays) {
  RectangleOptions o;
  o.nx = 5;
  o.ny = 6;
  o.triangulation = Triangulation::random;
  o.seed = 2;
  o.jitter = 0.2;
  SheetMesh m = make_rectangle(o);
  Eigen::MatrixX3d k = Eigen::MatrixX3d::Random(m.num_faces(), 3);
  Eigen::VectorXd d = Eigen::VectorXd::LinSpaced(m.num_faces(), 0.0, 1.0);
  m.set_plastic_curvature(k);
  m.set_damage(d);
  // Flip a few interior edges: connectivity changes, the edge numbering stays the editor's.
  int flips = 0;
  for (auto e : m.mesh().edges())
    if (flips < 4 && diagonal(m, e) && m.mesh().is_flip_ok(e)) {
      m.mesh().flip(e);
      ++flips;
    }
  ASSERT_EQ(flips, 4);
  const SheetMesh r = m.rebuilt();
  EXPECT_EQ(r.material_coords(), m.material_coords());
  EXPECT_EQ(r.plastic_curvature(), k);
  EXPECT_EQ(r.damage(), d);
  EXPECT_EQ(interior_hinges(r).faces.rows(), interior_hinges(m).faces.rows());
  // The same faces (each may start at another corner) and, read back, the same edge numbering.
  const SheetMesh read(r.material_coords(), r.faces());
  EXPECT_EQ(read.faces(), r.faces());
  EXPECT_EQ(interior_hinges(read).vertices, interior_hinges(r).vertices);
  EXPECT_EQ(r.rebuilt().faces(), r.faces());
  EXPECT_NE(interior_hinges(m).vertices, interior_hinges(r).vertices);  // the flips' order is gone
}
