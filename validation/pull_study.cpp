// The pull scenario over many seeds (issue acceptance): every run finishes, no NaN, the largest
// principal stretch stays within the limit at every step, the lifted points reach their targets,
// nothing goes below the ground, the Gauss-Bonnet residual of the output mesh is below 1e-9,
// and the same seed gives a bitwise-identical mesh.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "common/cli_checks.hpp"
#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/metrics.hpp"
#include "validation/statistics.hpp"
#include "validation/study_table.hpp"

namespace ps = papersim::simulation;

// The study; main turns an unwritable --csv into exit status 5.
static int study(int argc, char** argv) {
  CLI::App app{"pull_study: the pull scenario over seeds, with its acceptance checks"};
  int seeds = 20, first = 0;
  std::string csv;
  app.add_option("--seeds", seeds, "number of seeds")->check(papersim::common::positive());
  app.add_option("--first", first, "first seed (seeds first .. first + N - 1)")
      ->check(papersim::common::non_negative());
  app.add_option("--csv", csv, "also write the table as CSV");
  CLI11_PARSE(app, argc, argv);
  papersim::validation::StudyTable table(csv,
                                         "seed,vertices,wall_seconds,newton_iterations,max_stretch,"
                                         "handle_error,min_ground,gauss_bonnet,points,verdict");
  std::printf("%-5s %-7s %-9s %-10s %-11s %-11s %-11s %-10s %-8s %s\n", "seed", "verts", "wall_s",
              "newton", "max_s1", "handle_err", "min_ground", "gauss_bon", "points", "verdict");
  int failures = 0;
  std::vector<double> walls;
  for (int seed = first; seed < first + seeds; ++seed) {
    const ps::Scene scene = ps::make_scenario("pull", seed);
    std::string verdict = "PASS";
    double wall = 0, s1 = 0, herr = 0, ground = 0, gauss_bonnet = 0;
    int newton = 0, verts = 0;
    try {
      const ps::RunResult r = ps::run_scene(scene, {});
      wall = r.wall_seconds;
      newton = r.totals.newton_iterations;
      verts = r.sheet.vertices;
      s1 = r.quality.max_principal_stretch;
      herr = r.quality.max_handle_error.value_or(0.0);
      ground = r.quality.min_obstacle_distance.at(0);
      const Eigen::MatrixX3i F = r.mesh.faces();
      const Eigen::MatrixX3d P =
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
              r.state.positions.data(), r.mesh.num_vertices(), 3);
      gauss_bonnet = papersim::validation::developability_metrics(
                         P, F, papersim::validation::build_topology(F, r.mesh.num_vertices()))
                         .gauss_bonnet_residual;
      if (!r.state.positions.allFinite())
        verdict = "FAIL nan";
      else if (s1 > 1 + scene.sheet.material.strain_limit)
        verdict = "FAIL stretch";
      else if (herr > 1e-3)
        verdict = "FAIL handle";
      else if (ground < -scene.sheet.material.thickness)
        verdict = "FAIL ground";
      else if (!(std::abs(gauss_bonnet) < 1e-9))
        verdict = "FAIL gauss-bonnet";
      if (seed == first) {
        const ps::RunResult again = ps::run_scene(scene, {});
        if (!(again.state.positions.array() == r.state.positions.array()).all())
          verdict = "FAIL not repeatable";
      }
    } catch (const std::exception& e) {
      verdict = std::string("FAIL ") + e.what();
    }
    if (verdict != "PASS") ++failures;
    walls.push_back(wall);
    std::printf("%-5d %-7d %-9.2f %-10d %-11.6f %-11.3g %-11.3g %-10.2g %-8zu %s\n", seed, verts,
                wall, newton, s1, herr, ground, gauss_bonnet, scene.handles.size(),
                verdict.c_str());
    std::fflush(stdout);
    if (table.enabled()) {
      std::ostringstream row;
      row << seed << ',' << verts << ',' << wall << ',' << newton << ',' << s1 << ',' << herr << ','
          << ground << ',' << gauss_bonnet << ',' << scene.handles.size() << ',' << verdict;
      table.add(row.str());
    }
  }
  std::sort(walls.begin(), walls.end());
  std::printf("%d seeds, %d failed; wall time median %.2f s, worst %.2f s\n", seeds, failures,
              papersim::validation::median(walls), walls.back());
  return failures == 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  return papersim::validation::run_study("pull_study", study, argc, argv);
}
