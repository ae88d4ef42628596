// The plastic return mapping (simulation/plasticity.hpp) and the bending energies' plastic state.
#include "simulation/plasticity.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <random>

#include "remesh/sheet_generator.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/energies/morley_bending_energy.hpp"
#include "simulation/errors.hpp"
#include "simulation/output_files.hpp"
#include "simulation/run.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

/// Random curvature tensors (#F by 3) with norms in [lo, hi] [1/m].
Eigen::MatrixX3d random_curvatures(int n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(lo, hi);
  Eigen::MatrixX3d k(n, 3);
  for (int f = 0; f < n; ++f) {
    const Eigen::Vector3d d(g(rng), g(rng), g(rng));
    k.row(f) = (u(rng) / curvature_norm(d) * d).transpose();
  }
  return k;
}

/// A jittered 6 x 7 sheet of 6 x 7 cm bent into a cylinder of curvature `bend` [1/m] about y.
struct BentSheet {
  remesh::SheetMesh mesh;
  Eigen::VectorXd x;
};
BentSheet bent_sheet(double bend) {
  remesh::RectangleOptions o;
  o.width = 0.06;
  o.height = 0.07;
  o.nx = 6;
  o.ny = 7;
  o.jitter = 0.2;
  o.seed = 3;
  BentSheet s{remesh::make_rectangle(o), {}};
  const Eigen::MatrixX2d X = s.mesh.material_coords();
  s.x.resize(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v)
    s.x.segment<3>(3 * v) << std::sin(bend * X(v, 0)) / bend, X(v, 1),
        (1 - std::cos(bend * X(v, 0))) / bend;
  return s;
}

/// A 2 x 0.6 cm strip (3 mm edges, no gravity, no ground) wrapped by handles on every vertex
/// onto a cylinder about y of curvature k [1/m] over 50 ms, held, and released at 0.1 s.
Scene bent_strip_scene(double k, double yield, BendingModel model, double duration) {
  Scene scene;
  scene.sheet.width = 0.02;
  scene.sheet.height = 0.006;
  scene.sheet.edge_length = 3e-3;
  scene.sheet.position = Eigen::Vector3d::Zero();
  scene.sheet.material.yield_curvature = yield;
  scene.sheet.material.bending_model = model;
  scene.sheet.material.damping = 20;
  scene.gravity = Eigen::Vector3d::Zero();
  scene.ground = false;
  scene.time_step = 5e-3;
  scene.duration = duration;
  remesh::SheetMesh mesh;
  SheetState state;
  initial_sheet(scene, mesh, state);
  const Eigen::MatrixX2d X = mesh.material_coords();
  for (int v = 0; v < X.rows(); ++v) {
    HandleSpec h;
    h.material_point = X.row(v).transpose();
    h.release_time = 0.1;
    h.stiffness = 1e4;
    const double s = X(v, 0) - 0.01;
    for (int j = 0; j <= 5; ++j) {
      const double kj = k * j / 5;
      HandleKeyframe f;
      f.time = 0.01 * j;
      if (j > 0)
        f.displacement = Eigen::Vector3d(std::sin(kj * s) / kj - s, 0, (1 - std::cos(kj * s)) / kj);
      h.keyframes.push_back(f);
    }
    scene.handles.push_back(h);
  }
  return scene;
}

}  // namespace

TEST(ReturnMapping, NoChangeBelowYield) {
  const double ky = 200;
  const Eigen::MatrixX3d plastic0 = random_curvatures(50, 0, 500, 1);
  // Elastic curvature below the yield (norm up to 0.999 k_y, the boundary included).
  Eigen::MatrixX3d K = plastic0 + random_curvatures(50, 0, 0.999 * ky, 2);
  K.row(0) = plastic0.row(0) + Eigen::RowVector3d(ky, 0, 0);  // exactly at the yield: no flow
  Eigen::MatrixX3d plastic = plastic0;
  Eigen::VectorXd damage = Eigen::VectorXd::LinSpaced(50, 0, 2);
  const Eigen::VectorXd damage0 = damage;
  const PlasticUpdate u = return_mapping(K, ky, plastic, damage);
  EXPECT_EQ(u.yielded_faces, 0);
  EXPECT_EQ(plastic, plastic0);
  EXPECT_EQ(damage, damage0);
}

TEST(ReturnMapping, MovesByTheExactExcessAboveYield) {
  const double ky = 200;
  const int n = 50;
  const Eigen::MatrixX3d plastic0 = random_curvatures(n, 0, 500, 3);
  const Eigen::MatrixX3d elastic = random_curvatures(n, 1.01 * ky, 20 * ky, 4);
  const Eigen::MatrixX3d K = plastic0 + elastic;
  Eigen::MatrixX3d plastic = plastic0;
  Eigen::VectorXd damage = Eigen::VectorXd::Constant(n, 0.25);
  const PlasticUpdate u = return_mapping(K, ky, plastic, damage);
  EXPECT_EQ(u.yielded_faces, n);
  for (int f = 0; f < n; ++f) {
    const Eigen::Vector3d ke = elastic.row(f).transpose();
    const Eigen::Vector3d dk = (plastic - plastic0).row(f).transpose();
    const Eigen::Vector3d after = (K - plastic).row(f).transpose();
    // Perfect plasticity: the elastic curvature ends on the yield surface, in its own direction,
    // and the plastic curvature moved by the excess |Ke| - k_y.
    EXPECT_NEAR(curvature_norm(after), ky, 1e-10 * ky) << f;
    EXPECT_NEAR((after - ky / curvature_norm(ke) * ke).norm(), 0, 1e-10 * ky) << f;
    EXPECT_NEAR(curvature_norm(dk), curvature_norm(ke) - ky, 1e-10 * curvature_norm(ke)) << f;
    // Damage grows by the increment in yield curvatures.
    EXPECT_NEAR(damage[f] - 0.25, curvature_norm(dk) / ky, 1e-12 * damage[f]) << f;
  }
}

TEST(ReturnMapping, UniaxialBendFromRest) {
  // K = (3 k_y, 0, 0) from rest: Kp = (2 k_y, 0, 0), damage 2.
  Eigen::MatrixX3d K(1, 3);
  K << 600, 0, 0;
  Eigen::MatrixX3d plastic = Eigen::MatrixX3d::Zero(1, 3);
  Eigen::VectorXd damage = Eigen::VectorXd::Zero(1);
  return_mapping(K, 200, plastic, damage);
  EXPECT_NEAR(plastic(0, 0), 400, 1e-9);
  EXPECT_NEAR(plastic.row(0).tail<2>().norm(), 0, 1e-12);
  EXPECT_NEAR(damage[0], 2, 1e-12);
}

TEST(ReturnMapping, NormCountsTheOffDiagonalTwice) {
  // The tensor [[0, 1], [1, 0]] has Frobenius norm sqrt(2).
  EXPECT_NEAR(curvature_norm(Eigen::Vector3d(0, 0, 1)), std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(curvature_norm(Eigen::Vector3d(3, 4, 0)), 5, 1e-15);
}

TEST(ReturnMapping, RejectsBadInput) {
  Eigen::MatrixX3d K = Eigen::MatrixX3d::Zero(2, 3), plastic = Eigen::MatrixX3d::Zero(2, 3);
  Eigen::VectorXd damage = Eigen::VectorXd::Zero(2);
  EXPECT_THROW(return_mapping(K, 0.0, plastic, damage), NumericError);
  Eigen::VectorXd short_damage = Eigen::VectorXd::Zero(1);
  EXPECT_THROW(return_mapping(K, 200, plastic, short_damage), NumericError);
  K(1, 0) = std::nan("");
  EXPECT_THROW(return_mapping(K, 200, plastic, damage), NumericError);
}

class PlasticBending : public ::testing::TestWithParam<BendingModel> {};

TEST_P(PlasticBending, DamageDividesTheStiffnessByOnePlusWeakeningTimesDamage) {
  // Uniform damage d with no plastic curvature scales the whole energy by 1 / (1 + w d).
  const BentSheet s = bent_sheet(30);
  Material m;
  m.bending_model = GetParam();
  m.weakening = 2.0;
  const double e0 = make_bending_energy(s.mesh, m)->value(s.x);
  remesh::SheetMesh damaged = s.mesh;
  damaged.set_damage(Eigen::VectorXd::Constant(s.mesh.num_faces(), 1.5));
  const double e1 = make_bending_energy(damaged, m)->value(s.x);
  ASSERT_GT(e0, 0);
  EXPECT_NEAR(e1 / e0, 1 / (1 + 2.0 * 1.5), 1e-12);
}

TEST_P(PlasticBending, EnergyIsMeasuredFromThePlasticRestState) {
  // A cylinder of curvature k with plastic curvature (k, 0, 0) everywhere stores (almost) no
  // energy; the Morley and fit models are exact for constant curvature up to the small-slope
  // approximation of the hinge angles (k L = 1.8 here: a relative error of some 1e-3 of the
  // energy the same shape stores from flat).
  const double k = 30;
  const BentSheet s = bent_sheet(k);
  Material m;
  m.bending_model = GetParam();
  remesh::SheetMesh plastic = s.mesh;
  Eigen::MatrixX3d kp = Eigen::MatrixX3d::Zero(s.mesh.num_faces(), 3);
  kp.col(0).setConstant(k);
  plastic.set_plastic_curvature(kp);
  const double from_flat = make_bending_energy(s.mesh, m)->value(s.x);
  const double from_plastic = make_bending_energy(plastic, m)->value(s.x);
  EXPECT_LT(from_plastic, 0.02 * from_flat);
  // And the flat sheet now stores the energy the cylinder stored from flat.
  Eigen::VectorXd flat(s.x.size());
  const Eigen::MatrixX2d X = s.mesh.material_coords();
  for (int v = 0; v < X.rows(); ++v) flat.segment<3>(3 * v) << X(v, 0), X(v, 1), 0;
  EXPECT_NEAR(make_bending_energy(plastic, m)->value(flat), from_flat, 0.02 * from_flat);
}

TEST_P(PlasticBending, SetPlasticStateMatchesAFreshEnergy) {
  // Updating the state of an existing term gives the energy of a term built on that state.
  const BentSheet s = bent_sheet(40);
  Material m;
  m.bending_model = GetParam();
  m.weakening = 1.0;
  const std::unique_ptr<BendingEnergy> e = make_bending_energy(s.mesh, m);
  remesh::SheetMesh other = s.mesh;
  other.set_plastic_curvature(random_curvatures(s.mesh.num_faces(), 0, 60, 5));
  Eigen::VectorXd damage = Eigen::VectorXd::LinSpaced(s.mesh.num_faces(), 0, 3);
  other.set_damage(damage);
  e->set_plastic_state(other.plastic_curvature(), other.damage());
  const double fresh = make_bending_energy(other, m)->value(s.x);
  EXPECT_NEAR(e->value(s.x), fresh, 1e-10 * fresh);
  Eigen::VectorXd g1 = Eigen::VectorXd::Zero(s.x.size()), g2 = g1;
  e->add_gradient(s.x, g1);
  make_bending_energy(other, m)->add_gradient(s.x, g2);
  EXPECT_LT((g1 - g2).norm(), 1e-10 * g2.norm());
}

INSTANTIATE_TEST_SUITE_P(Models, PlasticBending,
                         ::testing::Values(BendingModel::fit, BendingModel::morley),
                         [](const auto& info) {
                           return info.param == BendingModel::fit ? "fit" : "morley";
                         });

TEST(MorleyPlasticity, PlasticCurvatureAloneDoesNotRefactor) {
  const BentSheet s = bent_sheet(40);
  Material m;
  m.bending_model = BendingModel::morley;
  MorleyBendingEnergy e(s.mesh, m);
  const long after_construction = e.factorizations();
  EXPECT_EQ(after_construction, 1);
  const Eigen::VectorXd damage = s.mesh.damage();
  for (unsigned i = 0; i < 3; ++i)
    e.set_plastic_state(random_curvatures(s.mesh.num_faces(), 0, 80, 10 + i), damage);
  EXPECT_EQ(e.factorizations(), after_construction)
      << "plastic curvature changes only the right-hand side";
  e.set_plastic_state(s.mesh.plastic_curvature(),
                      Eigen::VectorXd::Constant(s.mesh.num_faces(), 0.5));
  EXPECT_EQ(e.factorizations(), after_construction + 1)
      << "damage changes the stiffness: one numeric factorisation";
}

TEST(MorleyPlasticity, AnUpdateLandsOnTheYieldSurfaceAndASecondChangesNothing) {
  // A cylinder of curvature 30 1/m above k_y = 20 1/m. The yield measure is a function of the
  // shape alone, so one update puts every face on or inside the yield surface and a second
  // update at the same shape changes nothing (no plastic flow feeding on itself).
  const BentSheet s = bent_sheet(30);
  Material m;
  m.bending_model = BendingModel::morley;
  m.yield_curvature = 20;
  remesh::SheetMesh mesh = s.mesh;
  MorleyBendingEnergy e(mesh, m);
  const Eigen::MatrixX3d measured = e.yield_curvatures(s.x);
  const PlasticUpdate first = apply_plasticity(e, s.x, m.yield_curvature, mesh);
  EXPECT_EQ(first.yielded_faces, mesh.num_faces());
  EXPECT_EQ(e.yield_curvatures(s.x), measured)
      << "the measure does not depend on the plastic state";
  const Eigen::MatrixX3d K = measured - mesh.plastic_curvature();
  for (int f = 0; f < K.rows(); ++f)
    EXPECT_NEAR(curvature_norm(K.row(f).transpose()), m.yield_curvature, 1e-9);
  const PlasticUpdate second = apply_plasticity(e, s.x, m.yield_curvature, mesh);
  EXPECT_EQ(second.yielded_faces, 0);
  // The measure is exact for constant curvature up to the small-slope approximation of the hinge
  // angles (k h = 0.3 per 1 cm edge: a few percent): the plastic k_xx takes the excess 30 - 20.
  EXPECT_NEAR(mesh.plastic_curvature().col(0).mean(), 10, 1.0);
  EXPECT_NEAR(mesh.damage().mean(), 10.0 / 20.0, 0.06);
}

TEST(RunPlasticity, AStepUpdatesThePlasticStateUnderMorleyOnly) {
  // Bent to 3 k_y: under morley the run's mesh and bending term take the plastic state; under
  // fit (the elastic reference) the state stays zero.
  simulation::Run morley(bent_strip_scene(150, 50, BendingModel::morley, 0.08));
  while (!morley.finished()) morley.step();
  EXPECT_GT(morley.mesh().damage().minCoeff(), 0.5) << "every face held at 3 k_y yields";
  EXPECT_NEAR(morley.mesh().plastic_curvature().col(0).mean(), 100, 10);
  const double e = morley.terms().bending->value(morley.state().positions);
  const double fresh = make_bending_energy(morley.mesh(), morley.scene().sheet.material)
                           ->value(morley.state().positions);
  EXPECT_NEAR(e, fresh, 1e-9 * fresh) << "the term holds the mesh's plastic state";
  simulation::Run fit(bent_strip_scene(150, 50, BendingModel::fit, 0.08));
  while (!fit.finished()) fit.step();
  EXPECT_EQ(fit.mesh().damage().maxCoeff(), 0.0);
  EXPECT_EQ(fit.mesh().plastic_curvature().cwiseAbs().maxCoeff(), 0.0);
}

TEST(RunPlasticity, PlasticStateSurvivesSheetPlyAndSheetMesh) {
  // A run's sheet.ply carries the plastic state; a scene starting from it (`sheet.mesh`) has the
  // same state, bit for bit, and the same bending energy at the same positions.
  simulation::Run first(bent_strip_scene(150, 50, BendingModel::morley, 0.08));
  while (!first.finished()) first.step();
  ASSERT_GT(first.mesh().damage().maxCoeff(), 0);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("papersim_plastic_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  write_outputs(dir, first.scene(), first.mesh(), first.state());
  Scene again = bent_strip_scene(150, 50, BendingModel::morley, 0.08);
  again.handles.clear();
  again.sheet.mesh_path = (dir / "sheet.ply").string();
  simulation::Run second(again);
  std::filesystem::remove_all(dir);
  EXPECT_EQ(second.mesh().plastic_curvature(), first.mesh().plastic_curvature());
  EXPECT_EQ(second.mesh().damage(), first.mesh().damage());
  EXPECT_EQ(second.state().positions, first.state().positions);
  const double e1 = first.terms().bending->value(first.state().positions);
  EXPECT_NEAR(second.terms().bending->value(second.state().positions), e1, 1e-9 * e1);
}
