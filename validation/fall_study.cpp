// A fall scenario (or pull) over many seeds (issue acceptance): every run finishes, no NaN, no
// vertex, face or obstacle edge inside an obstacle at any step, no self-intersection at the end,
// the largest principal stretch within the limit; reports wall time and the share spent in
// contact. With --remesh the runs remesh (docs/scene.md, "Remeshing"): every kept pass was
// checked exactly for self-intersection and stretch by the run (a pass that fails is undone and
// counted as a rollback); the table adds the vertex counts (start, largest, end), the passes,
// the rollbacks, the rescues (a failed step taken again after a pass with the obstacle
// criterion on, remesh.rescue_distance) and the largest jump of the mechanical energy across a
// pass. Every run also reports how often its self-contact stiffness doubled (two layers closing
// below the adaptive stiffness's floor; docs/crumple.md, "The adaptive self-contact stiffness").
// --set KEY=VALUE changes a scene key of every run (e.g. contact.static_whole_step=true).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "common/cli_checks.hpp"
#include "simulation/batch.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/safety.hpp"
#include "validation/statistics.hpp"
#include "validation/study_table.hpp"

namespace ps = papersim::simulation;
namespace pv = papersim::validation;

namespace {

using papersim::validation::median;

}  // namespace

// The study; main turns an unwritable --csv into exit status 5.
static int study(int argc, char** argv) {
  CLI::App app{"fall_study: a fall scenario over seeds, with its acceptance checks"};
  std::string name = "fall-sphere", csv;
  int seeds = 20, first = 0, trust_region_cg = -1;
  double size_min = 0, size_max = 100, start_edge = 0, angle = 0, step = 0, rescue = -1;
  app.add_option("--scenario", name, "fall-cylinder, fall-gable, fall-sphere, fall-spheres or pull")
      ->check(
          CLI::IsMember({"fall-cylinder", "fall-gable", "fall-sphere", "fall-spheres", "pull"}));
  app.add_option("--remesh", size_min,
                 "remesh with this remesh.size_min [mm] (0: the scenario's setting)")
      ->check(papersim::common::non_negative());
  app.add_option("--remesh-max", size_max, "remesh.size_max with --remesh [mm]")
      ->capture_default_str()
      ->check(papersim::common::positive());
  app.add_option("--remesh-angle", angle,
                 "remesh.refine_angle with --remesh [rad] (0: the scene's)")
      ->check(papersim::common::non_negative());
  app.add_option("--rescue-distance", rescue,
                 "remesh.rescue_distance with --remesh [mm] (0: no rescue; default: the scene's)")
      ->check(papersim::common::non_negative());
  app.add_option("--start-edge", start_edge, "start mesh edge length [mm] (0: the scenario's)")
      ->check(papersim::common::non_negative());
  app.add_option("--step", step, "time step [ms] (0: the scenario's)")
      ->check(papersim::common::non_negative());
  app.add_option("--seeds", seeds, "number of seeds")->check(papersim::common::positive());
  app.add_option("--first", first, "first seed (seeds first .. first + N - 1)")
      ->check(papersim::common::non_negative());
  app.add_option("--csv", csv, "also write the table as CSV");
  app.add_option("--trust-region-cg", trust_region_cg,
                 "solver.trust_region_cg (default: the scenario's)")
      ->check(CLI::Range(0, 1000));
  std::vector<std::string> set_pairs;
  app.add_option(
      "--set", set_pairs,
      "KEY=VALUE: set a scene key of every run (dotted, e.g. contact.static_whole_step=true; the "
      "value is JSON), before the options above; repeatable");
  CLI11_PARSE(app, argc, argv);
  nlohmann::json overrides;
  try {
    overrides = ps::parse_overrides(set_pairs);
    ps::apply_overrides(ps::make_scenario(name, first), overrides,
                        "--set");  // a bad key fails before any run
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fall_study: %s\n", e.what());
    return 2;
  }
  if (size_min > size_max) {
    std::fprintf(stderr, "fall_study: --remesh %g mm is larger than --remesh-max %g mm\n", size_min,
                 size_max);
    return 2;
  }
  pv::StudyTable table(
      csv,
      "scenario,seed,vertices,wall_seconds,newton_iterations,failed_solves,max_stretch,"
      "min_obstacle,min_ground,self_intersections,contact_share,self_contact_share,"
      "vertices_start,vertices_max,remesh_passes,remesh_rollbacks,max_energy_jump,"
      "max_energy_jump_relative,verdict,rollback_reasons,remesh_rescues,stiffness_doublings");
  std::printf(
      "%-5s %-6s %-8s %-7s %-6s %-9s %-10s %-10s %-5s %-7s %-7s %-15s %-6s %-5s %-4s %-9s %-4s "
      "%s\n",
      "seed", "verts", "wall_s", "newton", "halved", "max_s1", "min_obst", "min_ground", "self",
      "contact", "self_c", "v_start/max", "passes", "rollb", "resc", "e_jump", "dbl",
      "verdict (rollbacks by reason)");
  int failures = 0;
  std::vector<double> walls, shares, jumps;
  for (int seed = first; seed < first + seeds; ++seed) {
    ps::Scene scene = ps::make_scenario(name, seed);
    if (!set_pairs.empty()) scene = ps::apply_overrides(scene, overrides, "--set");
    if (start_edge > 0) scene.sheet.edge_length = 1e-3 * start_edge;
    if (step > 0) scene.time_step = 1e-3 * step;
    if (trust_region_cg >= 0) scene.newton.trust_region_cg = trust_region_cg;
    if (size_min > 0) {
      scene.remesh.enabled = true;
      scene.remesh.params.size_min = 1e-3 * size_min;
      scene.remesh.params.size_max = 1e-3 * size_max;
      if (angle > 0) scene.remesh.params.refine_angle = angle;
      if (rescue >= 0) scene.remesh.rescue_distance = 1e-3 * rescue;
    }
    std::string verdict = "PASS";
    double wall = 0, s1 = 0, obstacle = INFINITY, ground = INFINITY, share = 0, self_share = 0;
    int newton = 0, halved = 0, verts = 0, self = -1, verts_start = 0, verts_max = 0, passes = 0,
        rollbacks = 0, rescues = 0;
    int doublings = 0;  // self-contact stiffness doublings (adaptive barrier stiffness)
    double jump = 0, jump_relative = 0;
    std::string reasons;  // "obstacle 3 stretch 1"
    try {
      const ps::RunResult r = ps::run_scene(scene, {});
      const ps::RunQuality& q = r.quality;
      wall = r.wall_seconds;
      newton = r.totals.newton_iterations;
      halved = r.totals.failed_solves;
      verts = r.sheet.vertices;
      verts_start = r.sheet.vertices_start;
      verts_max = r.sheet.vertices_max;
      if (r.remesh) {
        passes = r.remesh->passes;
        rollbacks = r.remesh->rollbacks;
        rescues = r.remesh->rescues;
        jump = r.remesh->max_energy_jump;
        jump_relative = r.remesh->max_energy_jump_relative;
        for (const auto& [reason, n] : r.remesh->rollback_reasons)
          reasons += (reasons.empty() ? "" : " ") + reason + " " + std::to_string(n);
      }
      s1 = q.max_principal_stretch;
      self = q.self_intersections;
      const pv::ObstacleGaps gaps = pv::obstacle_gaps(scene, r);
      ground = gaps.ground;
      obstacle = gaps.obstacles;
      if (r.contact) share = r.contact->seconds / wall;
      if (r.self_contact) {
        self_share = r.self_contact->seconds / wall;
        doublings = r.self_contact->stiffness_doublings;
      }
      verdict = pv::safety_verdict(scene, r);
    } catch (const std::exception& e) {
      verdict = std::string("FAIL ") + e.what();
    }
    if (verdict != "PASS") ++failures;
    walls.push_back(wall);
    shares.push_back(share + self_share);
    jumps.push_back(jump_relative);
    const std::string counts = std::to_string(verts_start) + "/" + std::to_string(verts_max);
    std::printf(
        "%-5d %-6d %-8.2f %-7d %-6d %-9.6f %-10.3g %-10.3g %-5d %-7.3f %-7.3f %-15s %-6d %-5d %-4d "
        "%-9.3g %-4d %s%s\n",
        seed, verts, wall, newton, halved, s1, obstacle, ground, self, share, self_share,
        counts.c_str(), passes, rollbacks, rescues, jump, doublings, verdict.c_str(),
        reasons.empty() ? "" : (" (" + reasons + ")").c_str());
    std::fflush(stdout);
    if (table.enabled()) {
      std::ostringstream row;
      row << name << ',' << seed << ',' << verts << ',' << wall << ',' << newton << ',' << halved
          << ',' << s1 << ',' << obstacle << ',' << ground << ',' << self << ',' << share << ','
          << self_share << ',' << verts_start << ',' << verts_max << ',' << passes << ','
          << rollbacks << ',' << jump << ',' << jump_relative << ',' << verdict << ',' << reasons
          << ',' << rescues << ',' << doublings;
      table.add(row.str());
    }
  }
  std::sort(walls.begin(), walls.end());
  if (size_min > 0)
    std::printf(
        "remeshing %g..%g mm: largest energy jump across a pass relative to the energy range so "
        "far: "
        "median %.3g, worst %.3g\n",
        size_min, size_max, median(jumps), *std::max_element(jumps.begin(), jumps.end()));
  std::printf(
      "%s: %d seeds, %d failed; wall time median %.2f s, worst %.2f s; contact (obstacles + self) "
      "median %.0f%% of the wall time\n",
      name.c_str(), seeds, failures, median(walls), walls.back(), 100 * median(shares));
  return failures == 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  return papersim::validation::run_study("fall_study", study, argc, argv);
}
