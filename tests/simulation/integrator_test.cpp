// Newton with the exact Hessian first: it falls back to the PSD-projected Hessian only where the
// exact one is indefinite (a compressed, buckling membrane) and converges either way.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "remesh/sheet_generator.hpp"
#include "simulation/run.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

struct Outcome {
  StepStats stats;
  Eigen::VectorXd x;
};

/// A 5 x 5 cm sheet that starts flat but squeezed along x by `strain` (negative: stretched),
/// with a 0.1 mm bump so that it can buckle upwards, its edges x = 0 and x = 5 cm held; one
/// step of 0.5 s.
Outcome squeeze_sheet(double strain, bool exact_first, bool backoff = false,
                      int trust_region_cg = 0) {
  remesh::RectangleOptions o;
  o.width = o.height = 0.05;
  o.nx = o.ny = 11;
  const remesh::SheetMesh mesh = remesh::make_rectangle(o);
  const Eigen::MatrixX2d X = mesh.material_coords();
  const int nv = mesh.num_vertices();
  Eigen::VectorXd x0(3 * nv);
  for (int v = 0; v < nv; ++v)
    x0.segment<3>(3 * v) << (1 - strain) * X(v, 0), X(v, 1),
        1e-4 * std::sin(M_PI * X(v, 0) / o.width);
  std::vector<HandleSpec> handles;
  for (int v = 0; v < nv; ++v) {
    const bool left = X(v, 0)<1e-9, right = X(v, 0)> o.width - 1e-9;
    if (!left && !right) continue;
    HandleSpec h;
    h.material_point = X.row(v).transpose();
    handles.push_back(h);
  }
  PhysicsSetup setup;
  setup.gravity.setZero();
  setup.handles = anchor_handles(mesh, x0, handles);
  setup.self_contact = false;
  Terms terms = build_terms(mesh, setup);
  NewtonParams p;
  p.exact_hessian_first = exact_first;
  p.exact_retry_skip_max = backoff ? 64 : 0;
  p.trust_region_cg = trust_region_cg;
  Integrator integrator(nv, std::move(terms.list), p);
  SheetState state;
  state.positions = x0;
  state.velocities = Eigen::VectorXd::Zero(3 * nv);
  Outcome out;
  out.stats = integrator.step(state, 0.5);
  out.x = state.positions;
  return out;
}

}  // namespace

TEST(Integrator, CompressedSheetFallsBackToTheProjectedHessianAndConverges) {
  const Outcome exact = squeeze_sheet(0.02, true);
  EXPECT_EQ(exact.stats.failed_solves, 0);
  EXPECT_GT(exact.stats.projected_hessians, 0)
      << "a flat sheet squeezed by 2% has negative curvature (buckling)";
  EXPECT_TRUE(exact.x.allFinite());
  // The sheet buckled upwards rather than compressing: its middle rose by millimetres.
  double top = 0;
  for (Eigen::Index v = 0; v < exact.x.size() / 3; ++v) top = std::max(top, exact.x[3 * v + 2]);
  EXPECT_GT(top, 2e-3);
}

TEST(Integrator, StretchedSheetNeverNeedsProjectionAndMatchesProjectedNewton) {
  // Under tension every element Hessian is PSD: the exact path is always taken, and both
  // settings find the same minimiser (to the Newton tolerance 1e-4 m/s x h = 50 micrometres).
  const Outcome exact = squeeze_sheet(-2e-3, true);
  const Outcome projected = squeeze_sheet(-2e-3, false);
  EXPECT_EQ(exact.stats.projected_hessians, 0);
  EXPECT_EQ(exact.stats.failed_solves, 0);
  EXPECT_EQ(projected.stats.failed_solves, 0);
  EXPECT_LT((exact.x - projected.x).cwiseAbs().maxCoeff(), 5e-5);
}

TEST(Integrator, BackoffSkipsExactHessiansThatStayIndefiniteAndFindsTheSameBuckle) {
  // While the sheet buckles, the exact Hessian stays indefinite for many iterations: with the
  // backoff, most of them factor the projected Hessian directly (fewer failed exact attempts),
  // and Newton still converges to the same buckled state (to the stopping test's 50 um).
  const Outcome every = squeeze_sheet(0.02, true, false);
  const Outcome backoff = squeeze_sheet(0.02, true, true);
  EXPECT_EQ(backoff.stats.failed_solves, 0);
  EXPECT_GT(backoff.stats.projected_hessians, 0);
  EXPECT_LT(backoff.stats.projected_hessians, every.stats.projected_hessians);
  EXPECT_LT((backoff.x - every.x).cwiseAbs().maxCoeff(), 5e-5);
  std::printf(
      "exact attempts that failed: %d every iteration, %d with the backoff; Newton iterations %d / "
      "%d\n",
      every.stats.projected_hessians, backoff.stats.projected_hessians,
      every.stats.newton_iterations, backoff.stats.newton_iterations);
}

TEST(Integrator, TrustRegionStepsOnTheExactHessianFindTheSameBuckle) {
  // With conjugate gradients on the exact Hessian where it is indefinite, Newton still converges
  // and finds the buckle projected Newton finds (to the stopping test's 50 um), in no more
  // iterations.
  const Outcome projected = squeeze_sheet(0.02, true);
  const Outcome trust = squeeze_sheet(0.02, true, false, 20);
  EXPECT_EQ(trust.stats.failed_solves, 0);
  EXPECT_GT(trust.stats.trust_region_steps, 0);
  EXPECT_EQ(projected.stats.trust_region_steps, 0);
  EXPECT_LE(trust.stats.newton_iterations, projected.stats.newton_iterations);
  EXPECT_LT((trust.x - projected.x).cwiseAbs().maxCoeff(), 5e-5);
  std::printf("Newton iterations %d projected, %d with trust-region steps (%d of them)\n",
              projected.stats.newton_iterations, trust.stats.newton_iterations,
              trust.stats.trust_region_steps);
}
