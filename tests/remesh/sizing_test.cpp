#include "remesh/sizing.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "remesh_test_support.hpp"

using namespace papersim::remesh;
using namespace papersim::remesh::testing;

namespace {

Eigen::Vector2d eigenvalues(const Eigen::Matrix2d& m) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(m).eigenvalues();
}

Eigen::Matrix2d random_psd(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix2d a;
  a << u(rng), u(rng), u(rng), u(rng);
  return 100.0 * a * a.transpose();
}

}  // namespace

TEST(TensorMax, DominatesEveryTensorAndIsTight) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Eigen::Matrix2d> ts;
    for (int i = 0; i < 1 + trial % 4; ++i) ts.push_back(random_psd(rng));
    const Eigen::Matrix2d m = tensor_max(ts);
    double scale = 0;
    for (const auto& t : ts) scale = std::max(scale, t.trace());
    // M - M_i is positive semi-definite (to rounding of the tensors' size).
    for (const auto& t : ts) EXPECT_GE(eigenvalues(m - t).minCoeff(), -1e-9 * scale);
    // Tight: no smaller trace can dominate the largest of the tensors, and the maximum never
    // exceeds the sum.
    EXPECT_GE(m.trace(), scale * (1 - 1e-12));
    Eigen::Matrix2d sum = Eigen::Matrix2d::Zero();
    for (const auto& t : ts) sum += t;
    EXPECT_LE(m.trace(), sum.trace() * (1 + 1e-12));
  }
  // Two orthogonal rank-one tensors: the maximum is their sum, diag(a, b).
  const Eigen::Matrix2d m =
      tensor_max({Eigen::Vector2d(4, 0).asDiagonal(), Eigen::Vector2d(0, 9).asDiagonal()});
  EXPECT_TRUE(m.isApprox(Eigen::Matrix2d(Eigen::Vector2d(4, 9).asDiagonal()), 1e-12)) << m;
  // A tensor that dominates the others is the maximum.
  const Eigen::Matrix2d big = Eigen::Vector2d(10, 10).asDiagonal();
  EXPECT_TRUE(tensor_max({Eigen::Vector2d(3, 1).asDiagonal(), big}).isApprox(big, 1e-12));
  EXPECT_EQ(tensor_max({}), Eigen::Matrix2d::Zero());
}

TEST(ClampMetric, BoundsSizesAndAspect) {
  RemeshParams p;
  const Eigen::Vector2d l = eigenvalues(clamp_metric(Eigen::Vector2d(1e9, 0).asDiagonal(), p));
  EXPECT_NEAR(l(1), 1 / (p.size_min * p.size_min), 1e-6 * l(1));
  EXPECT_NEAR(l(0), p.aspect_min * p.aspect_min * l(1), 1e-6 * l(0));
  const Eigen::Vector2d z = eigenvalues(clamp_metric(Eigen::Matrix2d::Zero(), p));
  EXPECT_NEAR(z(0), 1 / (p.size_max * p.size_max), 1e-9);
  EXPECT_NEAR(z(1), 1 / (p.size_max * p.size_max), 1e-9);
}

TEST(CompressionMetric, AsksForBucklesOfTheGivenAmplitude) {
  // Compressed along x by Green strain e (no curvature): l^2 |e| = c^2 along x, nothing along y.
  const double c = 1e-4, e = -4e-4;
  const Eigen::Matrix2d m =
      compression_metric(Eigen::Vector2d(e, 0).asDiagonal(), Eigen::Matrix2d::Zero(), c);
  EXPECT_NEAR(m(0, 0), -e / (c * c), 1e-9 * (-e / (c * c)));
  EXPECT_NEAR(m(1, 1), 0.0, 1e-9 * (-e / (c * c)));
  // Stretching asks for nothing.
  EXPECT_LT(compression_metric(Eigen::Vector2d(1e-3, 1e-3).asDiagonal(), Eigen::Matrix2d::Zero(), c)
                .norm(),
            1e-6);
}

namespace {

/// The flat sheet compressed uniformly along material x to Green strain g < 0.
RemeshState compressed_state(const SheetMesh& mesh, double g) {
  RemeshState s = flat_state(mesh);
  s.positions.col(0) *= std::sqrt(1 + 2 * g);
  return s;
}

/// The wanted edge length along material x of every face [m].
std::vector<double> wanted_along_x(const std::vector<Eigen::Matrix2d>& m) {
  std::vector<double> out;
  for (const auto& mf : m) out.push_back(1 / std::sqrt(mf(0, 0)));
  return out;
}

}  // namespace

TEST(CompressionMetric, FaceThatCanBuckleIsNotRefined) {
  // A flat 5 mm grid compressed along x by Green strain 5e-4: ArcSim's metric alone asks for
  // c / sqrt(|G|) = 4.5 mm, finer than the grid; but a buckle of wavelength 2 h = 10 mm taking
  // up that strain spans 2 pi sqrt(|G|) = 0.14 rad per 5 mm edge, below refine_angle: the grid
  // can already carry it, so the compression criterion asks for nothing finer than the grid.
  const double g = -5e-4, h = 0.005;
  SheetMesh mesh = grid(0.1, 0.1, 21, 21);
  RemeshState s = compressed_state(mesh, g);
  RemeshParams p;
  p.size_min = 1e-3;
  p.size_max = 0.1;
  const Eigen::Matrix2d arcsim = compression_metric(Eigen::Vector2d(g, 0).asDiagonal(),
                                                    Eigen::Matrix2d::Zero(), p.refine_compression);
  EXPECT_NEAR(1 / std::sqrt(arcsim(0, 0)), p.refine_compression / std::sqrt(-g), 1e-9);
  EXPECT_LT(1 / std::sqrt(arcsim(0, 0)), h);
  for (const SizingTerms& t : sizing_terms(mesh, s, p)) {
    const double l = 1 / std::sqrt(t.compression(0, 0));
    EXPECT_NEAR(l, p.refine_angle * h / (2 * M_PI * std::sqrt(-g)), 1e-6);
    EXPECT_GT(l, h);
    EXPECT_LT(std::abs(t.compression(1, 1)), 1e-9 * t.compression(0, 0));  // nothing along y
  }
  // So a remeshing pass splits nothing (it coarsens: the sheet is flat).
  const int before = mesh.num_vertices();
  const RemeshStats stats = remesh(mesh, s, p);
  EXPECT_EQ(stats.splits, 0);
  EXPECT_LT(mesh.num_vertices(), before);
}

TEST(CompressionMetric, CompressedCoarseFaceRefinesByTheBuckleItNeedsNotToSizeMin) {
  // A 20 mm grid compressed by 1%: beyond what its edges can buckle (G > (refine_angle /
  // 2 pi)^2 = 1.0e-3), so it is refined, to the edges a buckle of wavelength 40 mm needs,
  // refine_angle h / (2 pi sqrt(|G|)) = 6.4 mm, not to ArcSim's c / sqrt(|G|) = 1 mm at once.
  const double g = -1e-2, h = 0.02;
  SheetMesh mesh = grid(0.2, 0.2, 11, 11);
  RemeshState s = compressed_state(mesh, g);
  RemeshParams p;
  p.size_min = 1e-3;
  const std::vector<Eigen::Matrix2d> m = sizing(mesh, s, p);
  for (double l : wanted_along_x(m))
    EXPECT_NEAR(l, p.refine_angle * h / (2 * M_PI * std::sqrt(-g)), 1e-6);
  // A face finer than 2 pi c / refine_angle (3.1 mm) gets ArcSim's metric unchanged.
  SheetMesh fine = grid(0.02, 0.02, 11, 11);  // 2 mm
  const std::vector<Eigen::Matrix2d> mf = sizing(fine, compressed_state(fine, -4e-3), p);
  for (double l : wanted_along_x(mf)) EXPECT_NEAR(l, p.refine_compression / std::sqrt(4e-3), 1e-9);
}

TEST(CompressionMetric, AGivenMembraneStrainReplacesTheChords) {
  // The 20 mm grid compressed by 1% of the test above, but with the strain its membrane measures
  // given as zero (as the arc membrane measures a sheet bent smoothly): no compression demand;
  // given as the chords' own, the same demand as from the positions. A pass reads the strain at
  // its start and empties it, since its edits change the faces.
  const double g = -1e-2;
  SheetMesh mesh = grid(0.2, 0.2, 11, 11);
  RemeshState s = compressed_state(mesh, g);
  RemeshParams p;
  p.size_min = 1e-3;
  const std::vector<SizingTerms> from_chords = sizing_terms(mesh, s, p);
  s.membrane_strain = Eigen::MatrixX3d::Zero(mesh.num_faces(), 3);
  for (const SizingTerms& t : sizing_terms(mesh, s, p)) EXPECT_EQ(t.compression.norm(), 0.0);
  s.membrane_strain.col(0).setConstant(g);  // compressed_state's Green strain along x
  const std::vector<SizingTerms> given = sizing_terms(mesh, s, p);
  ASSERT_EQ(given.size(), from_chords.size());
  for (size_t f = 0; f < given.size(); ++f) {
    EXPECT_GT(from_chords[f].compression(0, 0), 0.0);
    EXPECT_NEAR(given[f].compression(0, 0), from_chords[f].compression(0, 0),
                1e-9 * from_chords[f].compression(0, 0));
  }
  remesh(mesh, s, p);
  EXPECT_EQ(s.membrane_strain.rows(), 0);
}

TEST(Sizing, PlasticCurvatureRefinesAFlatSheetAlongTheCrease) {
  // A crease pressed flat: the world shape is flat, the plastic curvature remembers the fold.
  SheetMesh mesh = grid(0.1, 0.1, 11, 11);
  Eigen::MatrixX3d k = Eigen::MatrixX3d::Zero(mesh.num_faces(), 3);
  k(0, 1) = 50;  // bent about the x axis by 50 1/m: edges across of refine_angle / 50 = 4 mm
  mesh.set_plastic_curvature(k);
  const std::vector<SizingTerms> t = sizing_terms(mesh, flat_state(mesh), RemeshParams());
  EXPECT_NEAR(1 / std::sqrt(t[0].plastic(1, 1)), 0.2 / 50, 1e-12);
  EXPECT_EQ(t[0].plastic(0, 0), 0.0);
  EXPECT_EQ(t[0].curvature.norm(), 0.0);
  EXPECT_EQ(t[1].plastic.norm(), 0.0);
}

TEST(Sizing, CylinderCurvatureAcrossTheAxis) {
  // A fine grid wrapped on a cylinder of radius R (axis along x): the curvature criterion asks
  // for l = refine_angle * R across the axis; along it the aspect clamp (l / aspect_min) or
  // size_max, whichever is shorter.
  const double r = 0.05;
  SheetMesh mesh = grid(0.2, 0.2, 41, 41);
  RemeshParams p;
  p.refine_compression = 0;
  const std::vector<Eigen::Matrix2d> m = sizing(mesh, cylinder_state(mesh, r), p);
  const double across = p.refine_angle * r;
  const double along = std::min(p.size_max, across / p.aspect_min);
  // Per face the discrete shape operator of a triangle depends on its three hinges; its mean
  // over the sheet is the curvature to O(h^2 / R^2) (h = 5 mm, R = 50 mm: 1%), so the mean
  // metric is checked to 5 %.
  Eigen::Matrix2d mean = Eigen::Matrix2d::Zero();
  for (const auto& mf : m) mean += mf / m.size();
  EXPECT_NEAR(1 / std::sqrt(mean(1, 1)), across, 0.05 * across);
  EXPECT_NEAR(1 / std::sqrt(mean(0, 0)), along, 0.05 * along);
}

TEST(Sizing, DegenerateInputDoesNotBreakIt) {
  SheetMesh mesh = grid(0.03, 0.04, 5, 6);
  RemeshState s = flat_state(mesh);
  s.positions.setZero();  // every world edge has zero length
  RemeshParams p;
  p.obstacle_distance = 0.01;  // on, but no distances given
  const std::vector<Eigen::Matrix2d> m = sizing(mesh, s, p);
  ASSERT_EQ(static_cast<int>(m.size()), mesh.num_faces());
  for (const auto& mf : m) {
    ASSERT_TRUE(mf.allFinite());
    // Crushed to a point: maximal compression, so the finest size.
    EXPECT_NEAR(eigenvalues(mf).maxCoeff(), 1 / (p.size_min * p.size_min),
                1e-6 / (p.size_min * p.size_min));
  }
  const RemeshStats stats = remesh(mesh, s, p);
  EXPECT_GT(stats.splits, 0);
  EXPECT_EQ(s.positions.rows(), mesh.num_vertices());
  EXPECT_TRUE(s.positions.allFinite());
}

TEST(Sizing, ObstacleProximityRefinesWhereTheDistanceChanges) {
  // A flat sheet tilted over a plane: the distance grows along y, 1 mm at y = 0.
  SheetMesh mesh = grid(0.2, 0.2, 11, 11);
  RemeshState s = flat_state(mesh);
  const Eigen::MatrixX2d x = mesh.material_coords();
  s.obstacle_distance = 1e-3 + 0.5 * x.col(1).array();
  RemeshParams p;
  p.obstacle_distance = 0.02;
  const std::vector<Eigen::Matrix2d> m = sizing(mesh, s, p);
  const Eigen::MatrixX3i f = mesh.faces();
  for (int i = 0; i < f.rows(); ++i) {
    const double y = (x(f(i, 0), 1) + x(f(i, 1), 1) + x(f(i, 2), 1)) / 3;
    if (y > 0.1) {
      // Far from the obstacle (every corner beyond obstacle_distance): size_max.
      EXPECT_NEAR(m[i](1, 1), 1 / (p.size_max * p.size_max), 1e-9);
    }
  }
  // Next to it the wanted size across is about d / |grad d| (1 mm / 0.5, clamped to size_min).
  EXPECT_NEAR(m[0](1, 1), 1 / (p.size_min * p.size_min), 1e-6 / (p.size_min * p.size_min));
}

TEST(Sizing, ErrorsNameTheParameterOrArray) {
  SheetMesh mesh = grid(0.2, 0.3, 5, 6);
  RemeshState s = flat_state(mesh);
  RemeshParams p;
  p.size_max = 1e-3;
  try {
    sizing(mesh, s, p);
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("size_max"), std::string::npos) << e.what();
  }
  p = RemeshParams();
  p.aspect_min = 0;
  EXPECT_THROW(sizing(mesh, s, p), ParameterError);
  p = RemeshParams();
  s.obstacle_distance = Eigen::VectorXd::Zero(3);
  try {
    remesh(mesh, s, p);
    FAIL() << "expected MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("state.obstacle_distance"), std::string::npos) << e.what();
  }
  s = flat_state(mesh);
  s.membrane_strain =
      Eigen::MatrixX3d::Zero(mesh.num_vertices(), 3);  // one row per vertex, not face
  try {
    remesh(mesh, s, p);
    FAIL() << "expected MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(
        std::string(e.what()).find("state.membrane_strain has 30 rows, the mesh has 40 faces"),
        std::string::npos)
        << e.what();
  }
  s.membrane_strain = Eigen::MatrixX3d::Zero(mesh.num_faces(), 3);
  s.membrane_strain(7, 2) = std::nan("");
  try {
    sizing(mesh, s, p);
    FAIL() << "expected MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("state.membrane_strain of face 7"), std::string::npos)
        << e.what();
  }
  s = flat_state(mesh);
  s.positions(2, 1) = std::nan("");
  EXPECT_THROW(remesh(mesh, s, p), MeshError);
}
