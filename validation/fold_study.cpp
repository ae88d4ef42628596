// The fold scenario over seeds (issue 16 acceptance): every run finishes, no NaN, no penetration
// of the ground or the roller at any step, no self-intersection at the end, the largest
// principal stretch within the limit; and at the end (2.5 s after the release) a plastic crease
// along the fold: the residual rest angle across the fold line (plastic curvature integrated
// over a 4 cm band, piece by piece along the line: validation/fold_crease.hpp) exceeds the crease
// threshold along a run at least half as long as the fold. Reports the crease lines along the
// fold (count, longest, total length, mean rest angle) and wall time per sample (median, worst).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/fold_crease.hpp"
#include "validation/metrics.hpp"
#include "validation/safety.hpp"
#include "validation/statistics.hpp"

namespace ps = papersim::simulation;
namespace pv = papersim::validation;


int main(int argc, char** argv) {
  CLI::App app{"papersim_fold_study: the fold scenario over seeds, with its acceptance checks"};
  std::string csv, keep;
  int seeds = 20, first = 0;
  double crease_angle = 30.0, edge = 0.0;
  app.add_option("--seeds", seeds, "number of seeds")->check(CLI::PositiveNumber);
  app.add_option("--first", first, "first seed (seeds first .. first + N - 1)")->check(CLI::NonNegativeNumber);
  app.add_option("--crease-angle", crease_angle, "crease threshold of the residual rest angle [deg]")
      ->check(CLI::Range(0.1, 179.0));
  app.add_option("--edge", edge, "initial edge length [m] instead of the scenario's (0: the scenario's)")
      ->check(CLI::Range(0.0, 0.05));
  app.add_option("--csv", csv, "also write the table as CSV");
  app.add_option("--keep", keep, "write each seed's outputs (sheet.ply with the plastic state, meta.json) to DIR/seed_N");
  CLI11_PARSE(app, argc, argv);
  std::printf("%-5s %-6s %-8s %-7s %-6s %-9s %-10s %-10s %-5s %-6s %-9s %-9s %-9s %-8s %-8s %-7s %s\n", "seed",
              "verts", "wall_s", "newton", "halved", "max_s1", "min_roller", "min_ground", "self", "lines",
              "longest_m", "creased_m", "fold_m", "rest_deg", "mean_deg", "network", "verdict");
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "seed,vertices,wall_seconds,newton_iterations,failed_solves,max_stretch,min_roller,min_ground,"
           "self_intersections,crease_lines,longest_crease,creased_length,fold_length,crease_rest_angle_deg,"
           "fold_mean_rest_angle_deg,plastic_network_lines,verdict\n";
  }
  int failures = 0;
  std::vector<double> walls;
  for (int seed = first; seed < first + seeds; ++seed) {
    ps::Scene scene = ps::make_scenario("fold", seed);
    if (edge > 0) scene.sheet.edge_length = edge;
    const Eigen::Vector2d centre(0.5 * scene.sheet.width, 0.5 * scene.sheet.height);
    const pv::FoldLine line = pv::fold_line_in_rectangle(centre, centre - scene.handles.at(0).material_point,
                                                         scene.sheet.width, scene.sheet.height);
    std::string verdict = "PASS";
    double wall = 0, s1 = 0, roller = INFINITY, ground = INFINITY;
    int newton = 0, halved = 0, verts = 0, self = -1, network = 0;
    pv::FoldCrease crease;
    try {
      ps::RunOptions run_options;
      if (!keep.empty()) run_options.out_dir = keep + "/seed_" + std::to_string(seed);
      const ps::RunResult r = ps::run_scene(scene, run_options);
      const ps::RunQuality& q = r.quality;
      wall = r.wall_seconds;
      newton = r.totals.newton_iterations;
      halved = r.totals.failed_solves;
      verts = r.sheet.vertices;
      s1 = q.max_principal_stretch;
      self = q.self_intersections;
      ground = q.min_obstacle_distance.at(0);
      roller = q.min_obstacle_distance.at(1);
      pv::MetricsOptions options;
      options.crease_angle_deg = crease_angle;
      const pv::MeshMetrics m = pv::compute_metrics(r.mesh.material_coords(), r.state.positions_matrix(),
                                                    r.mesh.faces(), r.mesh.plastic_curvature(), options);
      network = m.creases.plastic_network_lines;
      pv::FoldCreaseOptions crease_options;
      crease_options.threshold = crease_angle * M_PI / 180;
      crease = pv::measure_fold_crease(r.mesh.material_coords(), r.mesh.faces(), r.mesh.plastic_curvature(), line,
                                       crease_options);
      verdict = pv::safety_verdict(scene, r);
      if (verdict == "PASS" && crease.longest < 0.5 * line.chord) verdict = "FAIL no plastic crease along the fold";
    } catch (const std::exception& e) {
      verdict = std::string("FAIL ") + e.what();
    }
    if (verdict != "PASS") ++failures;
    walls.push_back(wall);
    const double deg = 180 / M_PI;
    std::printf("%-5d %-6d %-8.1f %-7d %-6d %-9.6f %-10.3g %-10.3g %-5d %-6d %-9.4f %-9.4f %-9.4f %-8.1f %-8.1f %-7d %s\n",
                seed, verts, wall, newton, halved, s1, roller, ground, self, crease.lines, crease.longest,
                crease.creased, line.chord, crease.angle * deg, crease.mean_all * deg, network, verdict.c_str());
    std::fflush(stdout);
    if (out)
      out << seed << ',' << verts << ',' << wall << ',' << newton << ',' << halved << ',' << s1 << ',' << roller << ','
          << ground << ',' << self << ',' << crease.lines << ',' << crease.longest << ',' << crease.creased << ','
          << line.chord << ',' << crease.angle * deg << ',' << crease.mean_all * deg << ',' << network << ','
          << verdict << '\n';
  }
  std::sort(walls.begin(), walls.end());
  std::printf("fold: %d seeds, %d failed; wall time median %.1f s, worst %.1f s\n", seeds, failures,
              pv::median(walls), walls.back());
  return failures == 0 ? 0 : 1;
}
