/// Cost of one remesh() pass of an A4 sheet (0.210 x 0.297 m, 31 x 42 = 1,302 vertices, alternating
/// diagonals) folded sharply by 90 degrees across its middle (a line of vertices), with the
/// reference parameters (RemeshParams defaults: refine_angle 0.2 rad, refine_compression 1e-4 m,
/// edges 3-100 mm, aspect 0.2). Every iteration remeshes a fresh copy of the same input (the copy
/// is not timed), so every iteration does the same work. For scale, the same run times sizing()
/// alone on that input and one pass over the flat sheet at rest (pure coarsening).
///
/// Counters: vertices_in, vertices_out, splits, flips, collapses (per pass).
///
/// Run:  build-perf/remesh/remesh_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <cmath>

#include "remesh/remesh.hpp"
#include "remesh/sheet_generator.hpp"

namespace pr = papersim::remesh;

namespace {

constexpr double WIDTH = 0.210, HEIGHT = 0.297;  // A4 [m]
constexpr int NX = 31, NY = 42;
constexpr double FOLD_Y = 20 * HEIGHT / (NY - 1);  // on a line of vertices [m]

pr::SheetMesh a4_grid() {
  pr::RectangleOptions o;
  o.width = WIDTH;
  o.height = HEIGHT;
  o.nx = NX;
  o.ny = NY;
  return pr::make_rectangle(o);
}

/// World = material, with the part beyond FOLD_Y turned by `angle` about the fold line.
pr::RemeshState folded(const pr::SheetMesh& mesh, double angle) {
  const Eigen::MatrixX2d x = mesh.material_coords();
  pr::RemeshState s;
  s.positions = Eigen::MatrixX3d::Zero(x.rows(), 3);
  s.velocities = Eigen::MatrixX3d::Zero(x.rows(), 3);
  for (int v = 0; v < x.rows(); ++v) {
    const double t = std::max(0.0, x(v, 1) - FOLD_Y);
    s.positions.row(v) << x(v, 0), std::min(x(v, 1), FOLD_Y) + t * std::cos(angle),
        t * std::sin(angle);
  }
  return s;
}

void run_remesh(benchmark::State& st, double angle) {
  const pr::SheetMesh mesh0 = a4_grid();
  const pr::RemeshState state0 = folded(mesh0, angle);
  const pr::RemeshParams params;
  pr::RemeshStats stats;
  int vertices_out = 0;
  for (auto _ : st) {
    st.PauseTiming();
    pr::SheetMesh mesh = mesh0;
    pr::RemeshState state = state0;
    st.ResumeTiming();
    stats = pr::remesh(mesh, state, params);
    vertices_out = mesh.num_vertices();
    benchmark::DoNotOptimize(state.positions.data());
  }
  st.counters["vertices_in"] = mesh0.num_vertices();
  st.counters["vertices_out"] = vertices_out;
  st.counters["splits"] = stats.splits;
  st.counters["flips"] = stats.flips;
  st.counters["collapses"] = stats.collapses;
}

void BM_remesh_fold90(benchmark::State& st) { run_remesh(st, M_PI / 2); }
void BM_remesh_flat(benchmark::State& st) { run_remesh(st, 0.0); }

void BM_sizing_fold90(benchmark::State& st) {
  const pr::SheetMesh mesh = a4_grid();
  const pr::RemeshState state = folded(mesh, M_PI / 2);
  const pr::RemeshParams params;
  for (auto _ : st) benchmark::DoNotOptimize(pr::sizing(mesh, state, params).data());
  st.counters["vertices_in"] = mesh.num_vertices();
}

}  // namespace

BENCHMARK(BM_remesh_fold90)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_remesh_flat)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_sizing_fold90)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
