// Heavy elastica (VALIDATION.md section 1): a strip clamped at one end sags under its own weight.
// Tip drop / L against the shooting solution, for the strip along the mesh grid and at 30 degrees
// to the mesh grain.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>

#include "remesh/sheet_generator.hpp"
#include "simulation/run.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

struct ElasticaResult {
  double tip_drop = 0;  // / L
  double reach = 0;     // / L
  int steps = 0;
};

/// Strip of free length L and width w on [0, L + c] x [0, w]; vertices with x <= c are clamped.
/// Relaxed to rest by damped backward Euler with large steps.
ElasticaResult run_elastica(const remesh::SheetMesh& mesh, double L, double c, double G,
                            BendingModel model, MembraneModel membrane = MembraneModel::chord) {
  Material m;
  m.bending_model = model;
  m.membrane_model = membrane;
  m.poisson = 0.0;  // the table is for a beam: no anticlastic (Poisson) stiffening
  const double g = G * m.bending_stiffness / (m.density * L * L * L);
  const Eigen::MatrixX2d X = mesh.material_coords();
  const int nv = mesh.num_vertices();
  Eigen::VectorXd x0(3 * nv);
  for (int v = 0; v < nv; ++v) x0.segment<3>(3 * v) << X(v, 0), X(v, 1), 0.0;
  // The run's composition of the incremental potential, with the band x <= c clamped (its
  // slopes as well as its corners).
  PhysicsSetup setup;
  setup.material = m;
  setup.material.damping = 20.0;
  setup.gravity = Eigen::Vector3d(0, 0, -g);
  const double inf = std::numeric_limits<double>::infinity();
  ClampSpec clamp;
  clamp.region = Eigen::Vector4d(-inf, -inf, c, inf);
  clamp.stiffness = 1e6;
  setup.clamps = {clamp};
  setup.placement = InitialPlacement(mesh, x0);
  setup.self_contact = false;
  Terms terms = build_terms(mesh, setup);
  NewtonParams newton;
  newton.tolerance = 1e-6;  // [m/s]: solves that stop early stall the creep to rest (known_answers)
  Integrator integrator(nv, std::move(terms.list), newton);
  SheetState state;
  state.positions = x0;
  state.velocities = Eigen::VectorXd::Zero(3 * nv);
  ElasticaResult r;
  for (r.steps = 1; r.steps <= 400; ++r.steps) {
    const StepStats st = integrator.step(state, 0.02);
    if (std::getenv("ELASTICA_DEBUG"))
      std::printf("step %d newton %d substeps %d vmax %g\n", r.steps, st.newton_iterations,
                  st.substeps, state.velocities.cwiseAbs().maxCoeff());
    if (state.velocities.cwiseAbs().maxCoeff() < 1e-6) break;
  }
  const double tip_x = X.col(0).maxCoeff();
  int count = 0;
  for (int v = 0; v < nv; ++v)
    if (X(v, 0) > tip_x - 1e-9) {
      r.tip_drop -= state.positions[3 * v + 2];
      r.reach += state.positions[3 * v] - c;
      ++count;
    }
  r.tip_drop /= count * L;
  r.reach /= count * L;
  return r;
}

/// A strip of free length L and width w with its clamp band c, meshed by a lattice of spacing h
/// at angle_deg to its length, with a line of vertices at the clamp's edge.
remesh::SheetMesh lattice_strip(double L, double w, double h, double c, double angle_deg) {
  remesh::LatticeOptions o;
  o.width = L + c;
  o.height = w;
  o.edge_length = h;
  o.angle = angle_deg * M_PI / 180;
  o.lines_x = {c};
  return remesh::make_rotated_lattice(o);
}

struct Case {
  double G, tip_drop;
};
// Shooting solution of theta'' = -G (1 - s) cos theta (VALIDATION.md table).
const Case CASES[] = {{1, 0.12347}, {8, 0.64063}, {20, 0.82988}};

}  // namespace

class HeavyElastica : public ::testing::TestWithParam<BendingModel> {};

TEST_P(HeavyElastica, StripAlongTheGrid) {
  const double L = 0.1, w = 0.01, h = 2.5e-3, c = 2 * h;
  remesh::RectangleOptions o;
  o.width = L + c;
  o.height = w;
  o.nx = static_cast<int>(std::lround(o.width / h)) + 1;
  o.ny = static_cast<int>(std::lround(w / h)) + 1;
  const remesh::SheetMesh mesh = remesh::make_rectangle(o);
  for (const Case& k : CASES) {
    const ElasticaResult r = run_elastica(mesh, L, c, k.G, GetParam());
    std::printf(
        "heavy elastica along the grid: G = %g tip drop / L = %.5f (expected %.5f, ratio %.4f)\n",
        k.G, r.tip_drop, k.tip_drop, r.tip_drop / k.tip_drop);
    EXPECT_NEAR(r.tip_drop / k.tip_drop, 1.0, 0.02) << "G = " << k.G << " drop " << r.tip_drop;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, HeavyElastica,
                         ::testing::Values(BendingModel::fit, BendingModel::morley),
                         [](const auto& info) {
                           return info.param == BendingModel::fit ? "fit" : "morley";
                         });

// The strip at 30 degrees to the mesh grain (remesh::make_rotated_lattice). The fit model
// converges slowly there (papersim_known_answers --bending fit, sections 1 and 1b): for G = 1
// the tip drop is 5.0% short at 2.5 mm edges, 2.1% at 1.25 mm and 1.6% at 0.8 mm
// (docs/elastica_30deg_diagnosis.md). The Morley model is within 0.3% at 2.5 mm.
TEST(HeavyElasticaMorley, StripAtThirtyDegreesToTheGrain) {
  const double L = 0.1, h = 2.5e-3, c = 2 * h;
  const remesh::SheetMesh mesh = lattice_strip(L, 0.01, h, c, 30);
  for (const Case& k : CASES) {
    const ElasticaResult r = run_elastica(mesh, L, c, k.G, BendingModel::morley);
    std::printf(
        "heavy elastica at 30 degrees (Morley): G = %g tip drop / L = %.5f (expected %.5f, ratio "
        "%.4f)\n",
        k.G, r.tip_drop, k.tip_drop, r.tip_drop / k.tip_drop);
    EXPECT_NEAR(r.tip_drop / k.tip_drop, 1.0, 0.02) << "G = " << k.G << " drop " << r.tip_drop;
  }
}

// Membrane locking (docs/remeshing.md, "Membrane locking"): a 5 cm wide strip of 5 mm square
// cells at 45 degrees to the bend cannot bend without compressing its chords by (k l)^2 / 24, and
// the paper's stiff membrane resists: at G = 8 the tip drop is 7.6% short under the chord model
// (papersim_known_answers --only thin). The arc membrane measures the edges along the bent
// surface and removes the locking: within 0.2% there. Tolerances: 1% for the arc model (five
// times its measured error), and the chord model at least 4% short (the locking this test is
// about; it would pass unlocked chords only if the mesh changed).
TEST(HeavyElasticaArcMembrane, FiveMillimetreCellsAtFortyFiveDegreesDoNotLock) {
  const double L = 0.1, h = 5e-3, c = 2 * h;
  const remesh::SheetMesh mesh = lattice_strip(L, 0.05, h, c, 45);
  const Case k = CASES[1];  // G = 8
  const ElasticaResult chord =
      run_elastica(mesh, L, c, k.G, BendingModel::morley, MembraneModel::chord);
  const ElasticaResult arc =
      run_elastica(mesh, L, c, k.G, BendingModel::morley, MembraneModel::arc);
  std::printf(
      "heavy elastica, 5 mm cells at 45 degrees, G = 8: tip drop / L chord %.5f (ratio %.4f), arc "
      "%.5f "
      "(ratio %.4f), expected %.5f\n",
      chord.tip_drop, chord.tip_drop / k.tip_drop, arc.tip_drop, arc.tip_drop / k.tip_drop,
      k.tip_drop);
  EXPECT_NEAR(arc.tip_drop / k.tip_drop, 1.0, 0.01);
  EXPECT_LT(chord.tip_drop / k.tip_drop, 0.96);
}
