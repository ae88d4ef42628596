#include "remesh/mesh_editor.hpp"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <string>

#include "remesh_test_support.hpp"

using namespace papersim::remesh;
using namespace papersim::remesh::testing;
using OpenMesh::EdgeHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

namespace {

// 4 x 4 grid of a 0.3 x 0.3 m square: vertex (i, j) has index 4 j + i, spacing 0.1 m.
constexpr int N = 4;
int vid(int i, int j) { return j * N + i; }

struct Fixture {
  SheetMesh mesh = grid(0.3, 0.3, N, N);
  RemeshState state;
  Eigen::Vector4d bounds;
  Eigen::Vector4d integral, scale;
  explicit Fixture(unsigned seed = 1) {
    state = cylinder_state(mesh, 0.2);
    randomize_attributes(mesh, state, seed);
    bounds = mesh.material_bounds();
    integral = integrals(mesh);
    scale = abs_integrals(mesh);
  }
  /// Area integrals equal to rounding: each edit moves a handful of products by an ulp or so.
  void expect_conserved() const {
    const Eigen::Vector4d now = integrals(mesh);
    for (int i = 0; i < 4; ++i)
      EXPECT_NEAR(now(i), integral(i), 1e-13 * scale(i)) << "component " << i;
  }
  void expect_valid() const {
    EXPECT_GT(min_aspect(mesh), 0.0) << "a face is inverted or degenerate";
    EXPECT_EQ(euler_characteristic(mesh), 1);
    EXPECT_TRUE(boundary_on_rectangle(mesh, bounds));
    EXPECT_TRUE(has_corners(mesh, bounds));
    EXPECT_EQ(mesh.material_bounds(), bounds);
    EXPECT_EQ(state.positions.rows(), mesh.num_vertices());
    EXPECT_EQ(state.velocities.rows(), mesh.num_vertices());
  }
};

EdgeHandle edge(const MeshEditor& ed, int a, int b) {
  const HalfedgeHandle h = ed.mesh().find_halfedge(VertexHandle(a), VertexHandle(b));
  EXPECT_TRUE(h.is_valid()) << a << "-" << b;
  return ed.mesh().edge_handle(h);
}

HalfedgeHandle halfedge(const MeshEditor& ed, int from, int to) {
  const HalfedgeHandle h = ed.mesh().find_halfedge(VertexHandle(from), VertexHandle(to));
  EXPECT_TRUE(h.is_valid()) << from << "->" << to;
  return h;
}

}  // namespace

TEST(MeshEditor, SplitInteriorEdgeIsExactAndConservative) {
  Fixture fx;
  const Eigen::Vector2d xa = fx.mesh.material_coord(vid(1, 1)),
                        xb = fx.mesh.material_coord(vid(2, 1));
  const Eigen::Vector3d pa = fx.state.positions.row(vid(1, 1)),
                        pb = fx.state.positions.row(vid(2, 1));
  const Eigen::Vector3d va = fx.state.velocities.row(vid(1, 1)),
                        vb = fx.state.velocities.row(vid(2, 1));
  int new_index = -1;
  {
    MeshEditor ed(fx.mesh, fx.state);
    const VertexHandle v = ed.split(edge(ed, vid(1, 1), vid(2, 1)));
    ASSERT_TRUE(v.is_valid());
    new_index = v.idx();
    EXPECT_EQ(ed.stats().splits, 1);
    ed.finish();
  }
  EXPECT_EQ(fx.mesh.num_vertices(), N * N + 1);
  EXPECT_EQ(fx.mesh.num_faces(), 2 * (N - 1) * (N - 1) + 2);
  // Material midpoint exactly; positions and velocities linear.
  EXPECT_EQ(fx.mesh.material_coord(new_index), Eigen::Vector2d(0.5 * (xa + xb)));
  EXPECT_TRUE(fx.state.positions.row(new_index).isApprox((0.5 * (pa + pb)).transpose(), 1e-15));
  EXPECT_TRUE(fx.state.velocities.row(new_index).isApprox((0.5 * (va + vb)).transpose(), 1e-15));
  fx.expect_conserved();
  fx.expect_valid();
}

TEST(MeshEditor, SplitBoundaryEdgeStaysOnTheBoundaryLine) {
  Fixture fx;
  int new_index = -1;
  {
    MeshEditor ed(fx.mesh, fx.state);
    new_index = ed.split(edge(ed, vid(1, 0), vid(2, 0))).idx();
    ASSERT_GE(new_index, 0);
  }
  EXPECT_EQ(fx.mesh.material_coord(new_index).y(), 0.0) << "exactly on the side y = 0";
  EXPECT_TRUE(fx.mesh.mesh().is_boundary(VertexHandle(new_index)));
  EXPECT_EQ(fx.mesh.num_faces(), 2 * (N - 1) * (N - 1) + 1);
  fx.expect_conserved();
  fx.expect_valid();
}

TEST(MeshEditor, FlipTransfersByAreaAndRefusesBoundaryAndNonConvex) {
  Fixture fx;
  {
    MeshEditor ed(fx.mesh, fx.state);
    // Cell (1, 1) has the diagonal (1,1)-(2,2) in the alternating pattern ((i + j) even).
    EXPECT_TRUE(ed.flip(edge(ed, vid(1, 1), vid(2, 2))));
    EXPECT_FALSE(ed.flip(edge(ed, vid(0, 0), vid(1, 0))));
    EXPECT_EQ(ed.stats().refusals.at("boundary"), 1);
    EXPECT_EQ(ed.stats().flips, 1);
  }
  EXPECT_TRUE(
      fx.mesh.mesh().find_halfedge(VertexHandle(vid(2, 1)), VertexHandle(vid(1, 2))).is_valid());
  fx.expect_conserved();
  fx.expect_valid();
  // Flipping the side of a cell whose quad (two triangles) is not convex would invert a face.
  Fixture fy;
  {
    MeshEditor ed(fy.mesh, fy.state);
    // Split the diagonal of cell (1, 1), then the edge (1,1)-(2,1) seen from the new vertex and
    // (2,1) is the middle of a straight line: flipping (m, (2,1)) would make a degenerate face.
    const VertexHandle m = ed.split(edge(ed, vid(1, 1), vid(2, 2)));
    ASSERT_TRUE(m.is_valid());
    const VertexHandle s = ed.split(edge(ed, vid(1, 1), m.idx()));
    ASSERT_TRUE(s.is_valid());
    // s lies on the straight segment (1,1)-(2,2); the edge (s, m) has a straight angle at s and m.
    EXPECT_FALSE(ed.flip(edge(ed, s.idx(), m.idx())));
    EXPECT_EQ(ed.stats().refusals.count("inverted"), 1u);
  }
  fy.expect_conserved();
  fy.expect_valid();
}

TEST(MeshEditor, CollapseInteriorKeepsSurvivorAndConservesIntegrals) {
  Fixture fx;
  const int u = vid(1, 1), w = vid(2, 1);
  const Eigen::Vector3d pw = fx.state.positions.row(w), vw = fx.state.velocities.row(w);
  const Eigen::Vector2d xw = fx.mesh.material_coord(w);
  {
    MeshEditor ed(fx.mesh, fx.state);
    ASSERT_TRUE(ed.collapse(halfedge(ed, u, w)));
    EXPECT_EQ(ed.stats().collapses, 1);
  }
  EXPECT_EQ(fx.mesh.num_vertices(), N * N - 1);
  EXPECT_EQ(fx.mesh.num_faces(), 2 * (N - 1) * (N - 1) - 2);
  // Garbage collection renumbers: find the survivor by its material coordinates.
  int found = -1;
  for (int v = 0; v < fx.mesh.num_vertices(); ++v)
    if (fx.mesh.material_coord(v) == xw) found = v;
  ASSERT_GE(found, 0);
  EXPECT_EQ(Eigen::Vector3d(fx.state.positions.row(found)), pw);
  EXPECT_EQ(Eigen::Vector3d(fx.state.velocities.row(found)), vw);
  fx.expect_conserved();
  fx.expect_valid();
}

TEST(MeshEditor, CollapseKeepsBoundaryAndCorners) {
  Fixture fx;
  {
    MeshEditor ed(fx.mesh, fx.state);
    // A corner never goes.
    EXPECT_FALSE(ed.collapse(halfedge(ed, vid(0, 0), vid(1, 0))));
    // A boundary vertex never moves inside.
    EXPECT_FALSE(ed.collapse(halfedge(ed, vid(1, 0), vid(1, 1))));
    EXPECT_EQ(ed.stats().refusals.at("boundary"), 2);
    // A boundary vertex may slide along a straight side into its neighbour.
    EXPECT_TRUE(ed.collapse(halfedge(ed, vid(1, 0), vid(2, 0))));
    // An interior vertex may merge into a boundary one.
    EXPECT_TRUE(ed.collapse(halfedge(ed, vid(2, 2), vid(3, 2))));
  }
  fx.expect_conserved();
  fx.expect_valid();
}

TEST(MeshEditor, VetoSeesTheProposalAndIsHonoured) {
  Fixture fx;
  const SheetMesh before = fx.mesh;
  const RemeshState state_before = fx.state;
  int calls = 0;
  EditProposal seen;
  auto veto = [&](const EditProposal& p) {
    ++calls;
    seen = p;
    return std::string("no");
  };
  {
    MeshEditor ed(fx.mesh, fx.state, veto);
    EXPECT_FALSE(ed.split(edge(ed, vid(1, 1), vid(2, 1))).is_valid());
    ASSERT_EQ(seen.kind, EditKind::split);
    ASSERT_EQ(seen.vertices.size(), 4u);
    EXPECT_EQ(seen.removed_faces.size(), 2u);
    EXPECT_EQ(seen.editor, &ed);
    // Each new face is counter-clockwise in material space and the inserted vertex (-1) sits at
    // the midpoint in both spaces.
    const Eigen::Vector3d mid_world =
        0.5 * (fx.state.positions.row(vid(1, 1)) + fx.state.positions.row(vid(2, 1))).transpose();
    for (size_t f = 0; f < seen.vertices.size(); ++f) {
      EXPECT_GT(
          signed_area2(seen.material[f].row(0).transpose(), seen.material[f].row(1).transpose(),
                       seen.material[f].row(2).transpose()),
          0.0);
      for (int k = 0; k < 3; ++k)
        if (seen.vertices[f][k] < 0) {
          EXPECT_TRUE(seen.world[f].row(k).transpose().isApprox(mid_world));
        }
    }
    EXPECT_FALSE(ed.flip(edge(ed, vid(1, 1), vid(2, 2))));
    EXPECT_EQ(seen.kind, EditKind::flip);
    EXPECT_FALSE(ed.collapse(halfedge(ed, vid(1, 1), vid(2, 1))));
    EXPECT_EQ(seen.kind, EditKind::collapse);
    EXPECT_EQ(seen.removed_faces.size(), 8u);  // vertex (1, 1) has valence 8
    EXPECT_EQ(seen.vertices.size(), 6u);       // the two faces on the edge vanish
    EXPECT_EQ(ed.stats().refusals.at("veto: no"), 3);
    EXPECT_EQ(ed.stats().splits + ed.stats().flips + ed.stats().collapses, 0);
  }
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(fx.mesh.faces(), before.faces());
  EXPECT_EQ(fx.mesh.material_coords(), before.material_coords());
  EXPECT_EQ(fx.mesh.plastic_curvature(), before.plastic_curvature());
  EXPECT_EQ(fx.mesh.damage(), before.damage());
  EXPECT_EQ(fx.state.positions, state_before.positions);
  EXPECT_EQ(fx.state.velocities, state_before.velocities);
}

TEST(MeshEditor, RandomEditSequenceKeepsEveryInvariant) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Fixture fx(seed);
    fx.mesh = grid(0.3, 0.2, 7, 6, 0.3, seed);
    fx.state = cylinder_state(fx.mesh, 0.15);
    randomize_attributes(fx.mesh, fx.state, seed);
    fx.bounds = fx.mesh.material_bounds();
    fx.integral = integrals(fx.mesh);
    fx.scale = abs_integrals(fx.mesh);
    std::mt19937 rng(seed);
    int applied = 0;
    {
      MeshEditor ed(fx.mesh, fx.state);
      for (int step = 0; step < 300; ++step) {
        const TriMesh& m = ed.mesh();
        std::vector<EdgeHandle> edges(m.edges().begin(), m.edges().end());
        const EdgeHandle e = edges[rng() % edges.size()];
        switch (rng() % 3) {
          case 0:
            applied += ed.split(e).is_valid();
            break;
          case 1:
            applied += ed.flip(e);
            break;
          default:
            applied += ed.collapse(m.halfedge_handle(e, rng() % 2));
            break;
        }
        for (auto f : m.faces()) {
          Eigen::Vector2d x[3];
          int k = 0;
          for (auto v : m.fv_range(f)) x[k++] = ed.material(v);
          ASSERT_TRUE(is_proper_triangle(x[0], x[1], x[2])) << "step " << step;
        }
      }
    }
    EXPECT_GT(applied, 100);
    fx.expect_conserved();
    fx.expect_valid();
  }
}

TEST(MeshEditor, RejectsStateOfTheWrongSize) {
  SheetMesh mesh = grid(0.3, 0.3, N, N);
  RemeshState state = flat_state(mesh);
  state.velocities.conservativeResize(3, 3);
  try {
    MeshEditor ed(mesh, state);
    FAIL() << "expected MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("state.velocities"), std::string::npos) << e.what();
  }
}

TEST(TriangleOverlap, MatchesKnownAreas) {
  Eigen::Matrix<double, 3, 2> a, b;
  a << 0, 0, 1, 0, 0, 1;
  EXPECT_NEAR(triangle_overlap(a, a), 0.5, 1e-15);
  b << 0, 0, 1, 0, 1, 1;  // shares half of a: the triangle (0,0), (1,0), (0.5,0.5)
  EXPECT_NEAR(triangle_overlap(a, b), 0.25, 1e-15);
  b << 2, 0, 3, 0, 2, 1;
  EXPECT_EQ(triangle_overlap(a, b), 0.0);
}

// Regression: remeshing a sheet draped on spheres split the edge opposite one vertex again and
// again (the flips that would repair the fan were vetoed), halving the children's aspect each time
// until a face was degenerate for the Morley plate (aspect 3e-10). The editor now refuses any edit
// creating a face thinner than EDIT_ASPECT_MIN.
TEST(MeshEditor, RepeatedSplitsTowardOneVertexStopAtTheAspectFloor) {
  // One triangle: base a-b on y = 0 of length 1 m, apex c at height 1 m.
  Eigen::MatrixX2d x(3, 2);
  x << -0.5, 0.0, 0.5, 0.0, 0.0, 1.0;
  Eigen::MatrixX3i f(1, 3);
  f << 0, 1, 2;
  SheetMesh mesh(x, f);
  RemeshState state;
  state.positions = Eigen::MatrixX3d::Zero(3, 3);
  state.positions.leftCols(2) = x;
  state.velocities = Eigen::MatrixX3d::Zero(3, 3);
  MeshEditor ed(mesh, state);
  // Split the base segment at the a end again and again: the child (a, m, c) with base L has
  // aspect about 2.6 L, so it crosses 1e-2 near L = 2^-8; without the floor the splits went on
  // to L = 2^-30, where twice the area still exceeds 1e-10 times the longest edge squared.
  VertexHandle end(1);
  int applied = 0;
  for (int k = 0; k < 40; ++k) {
    const VertexHandle m = ed.split(edge(ed, 0, end.idx()));
    if (!m.is_valid()) break;
    end = m;
    ++applied;
  }
  EXPECT_GE(applied, 6) << "splits whose children are acceptable must not be refused";
  EXPECT_LE(applied, 9);
  EXPECT_GE(ed.stats().refusals.at("degenerate"), 1);
  ed.finish();
  EXPECT_GE(min_aspect(mesh), EDIT_ASPECT_MIN);
}

// A flip whose new face runs through three nearly collinear vertices (the middle one 1e-8 m off
// the line: twice its area is 1e-8 times its longest edge squared, which the inversion test
// accepts) is refused.
TEST(MeshEditor, FlipThroughNearlyCollinearVerticesIsRefused) {
  // a (0, 0), b (1, 0), m (0.5, 1e-8) just above a-b, x (0.5, -1) below; faces (a, x, m) and
  // (x, b, m) share edge x-m, whose flip would make (a, b, m).
  Eigen::MatrixX2d p(4, 2);
  p << 0.0, 0.0, 1.0, 0.0, 0.5, 1e-8, 0.5, -1.0;
  Eigen::MatrixX3i f(2, 3);
  f << 0, 3, 2, 3, 1, 2;
  SheetMesh mesh(p, f);
  RemeshState state;
  state.positions = Eigen::MatrixX3d::Zero(4, 3);
  state.positions.leftCols(2) = p;
  state.velocities = Eigen::MatrixX3d::Zero(4, 3);
  MeshEditor ed(mesh, state);
  EXPECT_FALSE(ed.flip(edge(ed, 3, 2)));
  EXPECT_EQ(ed.stats().refusals.at("degenerate"), 1);
  EXPECT_EQ(ed.stats().flips, 0);
}

// With the invariant checks on (Debug, or PAPERSIM_ASSERTS as in the test build), an edit of a
// handle that is not the mesh's, or any edit after finish(), is refused naming the edit.
TEST(MeshEditor, InvariantChecksRefuseAnEditOfNoEdgeOrAfterFinish) {
#ifndef PAPERSIM_ENABLE_ASSERTS
  GTEST_SKIP() << "built without PAPERSIM_ASSERTS";
#else
  Fixture fx;
  MeshEditor ed(fx.mesh, fx.state);
  const auto refused = [](auto&& call, const std::string& what) {
    try {
      call();
      ADD_FAILURE() << what << " accepted";
    } catch (const std::logic_error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused([&] { ed.split(EdgeHandle()); }, "MeshEditor::split: not an edge");
  refused([&] { ed.flip(EdgeHandle(1 << 20)); }, "MeshEditor::flip: not an edge");
  refused([&] { ed.collapse(HalfedgeHandle(-1)); }, "MeshEditor::collapse: not a half-edge");
  const EdgeHandle e = edge(ed, vid(1, 1), vid(2, 1));
  EXPECT_EQ(ed.stats().splits, 0);
  ed.finish();
  refused([&] { ed.split(e); }, "MeshEditor::split: after finish()");
  fx.expect_valid();
#endif
}
