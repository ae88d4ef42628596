// The crumple scenario (Narain et al. 2013, Fig. 1): an A4 sheet inside a spherical cavity that
// shrinks from 0.2 m to 0.05 m between 1 and 5 s. Runs one seed step by step and reports, every
// --report seconds of simulated time, the wall time, vertex count, Newton iterations, halved
// steps, the smallest distance to the cavity's wall (> 0: no penetration), the largest principal
// stretch and the number of intersecting triangle pairs; with --out it also writes the sheet
// there at every report (DIR/sheet.ply, replaced atomically, plastic state included), so a run
// stopped early leaves its last state. At the end (or at the last report) the crease figures of
// papersim metrics: total and plastic crease length, the plastic crease network (from the plastic
// state alone) with its line-length distribution and log-normal fit, and the junction degrees.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "collision/self_intersection.hpp"
#include "common/atomic_file.hpp"
#include "common/cli_checks.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/run.hpp"
#include "simulation/scenario.hpp"
#include "validation/metrics.hpp"

namespace ps = papersim::simulation;
namespace pv = papersim::validation;

namespace {

struct Options {
  int seed = 0;
  double edge = 0.0;         ///< initial edge length [m]; 0: the scenario's
  double time_step = 0.0;    ///< [s]; 0: the scenario's
  double duration = 0.0;     ///< [s]; 0: the scenario's 5 s
  double report = 0.1;       ///< simulated time between reports [s]
  double stiffness = 0.0;    ///< contact stiffness [Pa]; 0: the scenario's
  double crease_angle = 30;  ///< crease threshold [deg]
  std::string out;
};

/// Radius of the scene's cavity (its first obstacle) at time t [m].
double cavity_radius(const ps::Scene& scene, double t) {
  const auto& c = scene.obstacles.at(0);
  return c.radius * papersim::collision::RigidMotion(c.keyframes).scale(t);
}

/// One line of the progress table; returns the number of intersecting triangle pairs.
int report_line(const ps::Run& run, double wall) {
  const ps::RunResult r = run.result(wall);
  const auto& d = run.step_obstacle_distance();
  const double cavity = d.empty() ? NAN : d.back();
  std::printf(
      "%7.3f %9.1f %6d %8d %6d %11.3e %11.3e %9.6f %5d %8.4f\n", run.state().time, wall,
      r.sheet.vertices, r.totals.newton_iterations, r.totals.failed_solves, cavity,
      r.quality.min_obstacle_distance.empty() ? NAN : r.quality.min_obstacle_distance.back(),
      r.quality.max_principal_stretch, r.quality.self_intersections,
      cavity_radius(run.scene(), run.state().time));
  std::fflush(stdout);
  return r.quality.self_intersections;
}

void write_state(const ps::Run& run, const std::string& dir) {
  std::filesystem::create_directories(dir);
  papersim::remesh::write_sheet_file((std::filesystem::path(dir) / "sheet.ply").string(),
                                     run.mesh(), run.state().positions_matrix(),
                                     run.state().velocities_matrix(), run.scene().sheet.width,
                                     run.scene().sheet.height);
}

void print_creases(const ps::Run& run, double crease_angle) {
  pv::MetricsOptions options;
  options.crease_angle_deg = crease_angle;
  const pv::MeshMetrics m =
      pv::compute_metrics(run.mesh().material_coords(), run.state().positions_matrix(),
                          run.mesh().faces(), run.mesh().plastic_curvature(), options);
  const pv::CreaseMetrics& c = m.creases;
  std::printf(
      "creases (threshold %.0f deg): %d edges, %d lines, total length %.4f m (plastic %.4f m, "
      "elastic %.4f m)\n",
      crease_angle, c.edges, c.lines, c.total_length, c.plastic_length, c.elastic_length);
  std::printf(
      "  line lengths: min %.4f median %.4f mean %.4f max %.4f m; log-normal mu %.3f sigma %.3f, "
      "KS %.3f\n",
      c.length_min, c.length_median, c.length_mean, c.length_max, c.log_length_mean,
      c.log_length_std, c.log_normal_ks);
  std::printf("  junctions %d: degree 3: %d, 4: %d, 5+: %d\n", c.junctions, c.junction_degrees[0],
              c.junction_degrees[1], c.junction_degrees[2]);
  std::printf("plastic network (material space): %d edges, %d lines, %d junctions, length %.4f m\n",
              c.plastic_network_edges, c.plastic_network_lines, c.plastic_network_junctions,
              c.plastic_network_length);
  std::printf(
      "  log-normal fit of its line lengths: mu %.3f sigma %.3f (median line %.4f m), KS %.3f",
      c.plastic_network_log_length_mean, c.plastic_network_log_length_std,
      std::exp(c.plastic_network_log_length_mean), c.plastic_network_log_normal_ks);
  const int n = c.plastic_network_lines;
  if (n >= 3) std::printf(" (5%% rejection above %.3f)", 0.89 / std::sqrt(static_cast<double>(n)));
  std::printf("\n  line lengths [m], longest first:");
  for (double l : c.plastic_network_line_lengths) std::printf(" %.4f", l);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_crumple_study: the crumple scenario, one seed, with progress and crease "
      "statistics"};
  Options o;
  app.add_option("--seed", o.seed, "scenario seed")->check(papersim::common::non_negative());
  app.add_option("--edge", o.edge, "initial edge length [m] (0: the scenario's 10 mm)")
      ->check(CLI::Range(0.0, 0.05));
  app.add_option("--time-step", o.time_step, "time step [s] (0: the scenario's 2 ms)")
      ->check(CLI::Range(0.0, 0.01));
  app.add_option("--duration", o.duration, "simulated time [s] (0: the scenario's 5 s)")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--stiffness", o.stiffness, "contact stiffness [Pa] (0: the scenario's 400 Pa)")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--report", o.report, "simulated time between progress lines [s]")
      ->check(CLI::Range(1e-3, 100.0));
  app.add_option("--crease-angle", o.crease_angle, "crease threshold [deg]")
      ->check(CLI::Range(0.1, 179.0));
  app.add_option("--out", o.out, "folder for DIR/sheet.ply, rewritten at every progress line");
  CLI11_PARSE(app, argc, argv);
  ps::Scene scene = ps::make_scenario("crumple", static_cast<std::uint64_t>(o.seed));
  if (o.edge > 0) scene.sheet.edge_length = o.edge;
  if (o.time_step > 0) scene.time_step = o.time_step;
  if (o.duration > 0) scene.duration = o.duration;
  if (o.stiffness > 0) scene.contact.stiffness = o.stiffness;
  try {
    if (!o.out.empty())
      std::filesystem::create_directories(
          o.out);  // a folder that cannot be made fails before the run
    const auto start = std::chrono::steady_clock::now();
    const auto wall = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    ps::Run run(scene);
    std::printf("crumple seed %d: %d vertices, edge %.1f mm, step %.1f ms, %.2f s\n", o.seed,
                static_cast<int>(run.state().num_vertices()), 1e3 * scene.sheet.edge_length,
                1e3 * scene.time_step, scene.duration);
    std::printf("%7s %9s %6s %8s %6s %11s %11s %9s %5s %8s\n", "t_s", "wall_s", "verts", "newton",
                "halved", "wall_gap_m", "min_gap_m", "max_s1", "self", "radius_m");
    double next = o.report;
    while (!run.finished()) {
      run.step();
      if (run.state().time + 1e-9 < next && !run.finished()) continue;
      next += o.report;
      report_line(run, wall());
      if (!o.out.empty()) write_state(run, o.out);
    }
    const ps::RunResult r = run.result(wall());
    const double gap = r.quality.min_obstacle_distance.back();
    std::printf(
        "finished: wall %.1f s, %d vertices, min gap to the cavity %.3e m (%s), %d intersecting "
        "pairs, "
        "max stretch %.6f (limit %.4f)\n",
        r.wall_seconds, r.sheet.vertices, gap, gap > 0 ? "no penetration" : "PENETRATION",
        r.quality.self_intersections, r.quality.max_principal_stretch,
        1 + scene.sheet.material.strain_limit);
    print_creases(run, o.crease_angle);
    const bool pass = gap > 0 && r.quality.self_intersections == 0 &&
                      r.state.positions.allFinite() &&
                      r.quality.max_principal_stretch <= 1 + scene.sheet.material.strain_limit;
    return pass ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_crumple_study: %s\n", e.what());
    return 2;
  }
}
