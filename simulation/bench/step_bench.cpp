/// Cost of one backward-Euler time step (Integrator::step, h = 1 ms) of an A4 sheet settling onto
/// a ground plane, at about 1k, 4k, 16k and 64k vertices.
///
/// Scene: an A4 sheet (0.210 x 0.297 m, remesh::make_rectangle, alternating diagonals) curled
/// isometrically into a cylinder of radius 0.2 m about the y axis, its lowest line at half the
/// contact thickness above the plane z = 0 (collision::PlaneCollider, friction 0.3), under gravity,
/// with every energy term: inertia, damping, gravity, membrane (with strain limit), bending,
/// a handle holding one corner, obstacle contact with friction. One step is taken before
/// timing so that contact and friction are active; every timed iteration restarts from that
/// state, so every iteration does the same work.
///
/// Counters per size: vertices, newton (iterations per step), line_search (energy evaluations
/// per step), seconds_assembly / seconds_solve / seconds_line_search per step (from StepStats).
/// After the runs, the fitted scaling exponent p of time ~ vertices^p is printed.
///
/// Run:  build-perf/simulation/papersim_step_bench [--benchmark_filter=...]
///       build-perf/simulation/papersim_step_bench --checksum [vertices] [steps] [threads]
///   (--checksum prints a hash of the positions after `steps` steps: the same for every thread
///   count when the solver is deterministic.)
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "collision/collider.hpp"
#include "remesh/sheet_generator.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/energies/contact_energy.hpp"
#include "simulation/energies/handle_energy.hpp"
#include "simulation/energies/membrane_energy.hpp"
#include "simulation/energies/vertex_energies.hpp"
#include "simulation/integrator.hpp"

namespace ps = papersim::simulation;

namespace {

constexpr double WIDTH = 0.210, HEIGHT = 0.297;  // A4 [m]
constexpr double H = 1e-3;                       // time step [s]
constexpr double CURL_RADIUS = 0.2;              // [m]
constexpr int WARMUP_STEPS = 1;

struct Setup {
  std::unique_ptr<ps::Integrator> integrator;
  ps::SheetState state;  // after the warm-up steps
  int num_vertices = 0;
};

/// Grid (nx, ny) with about `target` vertices and A4 aspect.
papersim::remesh::RectangleOptions grid(int target) {
  papersim::remesh::RectangleOptions o;
  o.width = WIDTH;
  o.height = HEIGHT;
  o.nx = static_cast<int>(std::lround(std::sqrt(target * WIDTH / HEIGHT)));
  o.ny = static_cast<int>(std::lround(static_cast<double>(target) / o.nx));
  o.triangulation = papersim::remesh::Triangulation::alternating;
  return o;
}

std::unique_ptr<Setup> make_setup(int target) {
  auto s = std::make_unique<Setup>();
  const papersim::remesh::SheetMesh mesh = papersim::remesh::make_rectangle(grid(target));
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const int nv = mesh.num_vertices();
  s->num_vertices = nv;
  ps::Material m;
  m.damping = 1.0;
  ps::ContactParams contact;
  contact.stiffness = m.density * 9.81;
  // Isometric curl about the line x = WIDTH / 2, lowest line at dhat / 2.
  Eigen::VectorXd x0(3 * nv);
  for (int v = 0; v < nv; ++v) {
    const double arc = X(v, 0) - 0.5 * WIDTH;
    x0.segment<3>(3 * v) << 0.5 * WIDTH + CURL_RADIUS * std::sin(arc / CURL_RADIUS), X(v, 1),
        0.5 * contact.dhat + CURL_RADIUS * (1 - std::cos(arc / CURL_RADIUS));
  }
  ps::HandleSpec corner;
  corner.material_point = Eigen::Vector2d(0.0, 0.0);
  const Eigen::VectorXd mass = ps::lumped_masses(X, F, m.density);
  std::vector<std::unique_ptr<ps::EnergyTerm>> terms;
  terms.push_back(std::make_unique<ps::InertiaEnergy>(mass));
  terms.push_back(std::make_unique<ps::DampingEnergy>(mass, m.damping));
  terms.push_back(std::make_unique<ps::GravityEnergy>(mass, Eigen::Vector3d(0, 0, -9.81)));
  terms.push_back(std::make_unique<ps::MembraneEnergy>(X, F, m));
  terms.push_back(ps::make_bending_energy(mesh, m));
  terms.push_back(
      std::make_unique<ps::HandleEnergy>(mesh, x0, std::vector<ps::HandleSpec>{corner}));
  auto ground = std::make_shared<papersim::collision::PlaneCollider>();
  ground->friction = 0.3;
  terms.push_back(std::make_unique<ps::ObstacleContactEnergy>(
      mass / m.density, std::vector<std::shared_ptr<const papersim::collision::Collider>>{ground},
      contact));
  s->integrator = std::make_unique<ps::Integrator>(nv, std::move(terms));
  s->state.positions = x0;
  s->state.velocities = Eigen::VectorXd::Zero(3 * nv);
  for (int i = 0; i < WARMUP_STEPS; ++i) s->integrator->step(s->state, H);
  return s;
}

/// One setup per size, built once (the 64k mesh takes seconds to set up).
Setup& setup(int target) {
  static std::map<int, std::unique_ptr<Setup>> cache;
  auto& s = cache[target];
  if (!s) s = make_setup(target);
  return *s;
}

void BM_Step(benchmark::State& bench) {
  Setup& s = setup(static_cast<int>(bench.range(0)));
  ps::StepStats total;
  for (auto _ : bench) {
    bench.PauseTiming();
    ps::SheetState state = s.state;
    bench.ResumeTiming();
    const ps::StepStats st = s.integrator->step(state, H);
    total.newton_iterations += st.newton_iterations;
    total.line_search_evaluations += st.line_search_evaluations;
    total.seconds_assembly += st.seconds_assembly;
    total.seconds_solve += st.seconds_solve;
    total.seconds_line_search += st.seconds_line_search;
    benchmark::DoNotOptimize(state.positions.data());
  }
  const double n = static_cast<double>(bench.iterations());
  bench.counters["vertices"] = s.num_vertices;
  bench.counters["newton"] = total.newton_iterations / n;
  bench.counters["line_search"] = total.line_search_evaluations / n;
  bench.counters["seconds_assembly"] = total.seconds_assembly / n;
  bench.counters["seconds_solve"] = total.seconds_solve / n;
  bench.counters["seconds_line_search"] = total.seconds_line_search / n;
}
BENCHMARK(BM_Step)
    ->Arg(1 << 10)
    ->Arg(1 << 12)
    ->Arg(1 << 14)
    ->Arg(1 << 16)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

/// Console output plus a record of (vertices, seconds per step) for the scaling fit.
class FitReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
      const auto it = r.counters.find("vertices");
      if (it != r.counters.end())
        points.emplace_back(it->second.value, r.GetAdjustedRealTime() * 1e-3);  // ms -> s
    }
  }
  std::vector<std::pair<double, double>> points;
};

/// Least-squares slope of log(time) against log(vertices).
void print_fit(const std::vector<std::pair<double, double>>& points) {
  if (points.size() < 2) return;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& [v, t] : points) {
    const double x = std::log(v), y = std::log(t);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double n = static_cast<double>(points.size());
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  std::printf("scaling: time per step ~ vertices^%.3f (least squares over %zu sizes)\n", slope,
              points.size());
  for (size_t i = 1; i < points.size(); ++i)
    std::printf("  %6.0f -> %6.0f vertices: local exponent %.3f\n", points[i - 1].first,
                points[i].first,
                std::log(points[i].second / points[i - 1].second) /
                    std::log(points[i].first / points[i - 1].first));
}

/// FNV-1a over the bytes of the positions.
std::uint64_t hash(const Eigen::VectorXd& x) {
  std::uint64_t h = 1469598103934665603ull;
  const auto* p = reinterpret_cast<const unsigned char*>(x.data());
  for (size_t i = 0; i < sizeof(double) * static_cast<size_t>(x.size()); ++i)
    h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

int run_checksum(int argc, char** argv) {
  const int target = argc > 2 ? std::atoi(argv[2]) : 4096;
  const int steps = argc > 3 ? std::atoi(argv[3]) : 5;
  const int threads = argc > 4 ? std::atoi(argv[4]) : 0;
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  threads);
  Setup& s = setup(target);
  ps::SheetState state = s.state;
  int newton = 0;
  for (int i = 0; i < steps; ++i) newton += s.integrator->step(state, H).newton_iterations;
  std::printf("checksum vertices %d steps %d threads %d newton %d hash %016llx\n", s.num_vertices,
              steps, threads, newton, static_cast<unsigned long long>(hash(state.positions)));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc > 1 && std::strcmp(argv[1], "--checksum") == 0) return run_checksum(argc, argv);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    FitReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    print_fit(reporter.points);
    benchmark::Shutdown();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_step_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
