// A fall scenario over many seeds (issue acceptance): every run finishes, no NaN, no vertex,
// face or obstacle edge inside an obstacle at any step, no self-intersection at the end, the
// largest principal stretch within the limit; reports wall time and the share spent in contact.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/statistics.hpp"

namespace ps = papersim::simulation;

namespace {

using papersim::validation::median;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fall_study: a fall scenario over seeds, with its acceptance checks"};
  std::string name = "fall-sphere", csv;
  int seeds = 20, first = 0;
  app.add_option("--scenario", name, "fall-cylinder, fall-gable, fall-sphere or fall-spheres")
      ->check(CLI::IsMember({"fall-cylinder", "fall-gable", "fall-sphere", "fall-spheres"}));
  app.add_option("--seeds", seeds, "number of seeds")->check(CLI::PositiveNumber);
  app.add_option("--first", first, "first seed (seeds first .. first + N - 1)")->check(CLI::NonNegativeNumber);
  app.add_option("--csv", csv, "also write the table as CSV");
  CLI11_PARSE(app, argc, argv);
  std::printf("%-5s %-6s %-8s %-7s %-6s %-9s %-10s %-10s %-5s %-7s %-7s %s\n", "seed", "verts", "wall_s",
              "newton", "halved", "max_s1", "min_obst", "min_ground", "self", "contact", "self_c", "verdict");
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "scenario,seed,vertices,wall_seconds,newton_iterations,failed_solves,max_stretch,min_obstacle,"
           "min_ground,self_intersections,contact_share,self_contact_share,verdict\n";
  }
  int failures = 0;
  std::vector<double> walls, shares;
  for (int seed = first; seed < first + seeds; ++seed) {
    const ps::Scene scene = ps::make_scenario(name, seed);
    std::string verdict = "PASS";
    double wall = 0, s1 = 0, obstacle = INFINITY, ground = INFINITY, share = 0, self_share = 0;
    int newton = 0, halved = 0, verts = 0, self = -1;
    try {
      const ps::RunResult r = ps::run_scene(scene, {});
      const ps::RunQuality& q = r.quality;
      wall = r.wall_seconds;
      newton = r.totals.newton_iterations;
      halved = r.totals.failed_solves;
      verts = r.sheet.vertices;
      s1 = q.max_principal_stretch;
      self = q.self_intersections;
      const std::vector<double>& d = q.min_obstacle_distance;
      for (size_t o = 0; o < d.size(); ++o) {
        if (o == 0 && scene.ground)
          ground = d[o];
        else
          obstacle = std::min(obstacle, d[o]);
      }
      if (r.contact) share = r.contact->seconds / wall;
      if (r.self_contact) self_share = r.self_contact->seconds / wall;
      if (!r.state.positions.allFinite())
        verdict = "FAIL nan";
      else if (!(obstacle > 0) || !(ground > 0))
        verdict = "FAIL penetration";
      else if (self != 0)
        verdict = "FAIL self-intersection";
      else if (s1 > 1 + scene.sheet.material.strain_limit)
        verdict = "FAIL stretch";
    } catch (const std::exception& e) {
      verdict = std::string("FAIL ") + e.what();
    }
    if (verdict != "PASS") ++failures;
    walls.push_back(wall);
    shares.push_back(share + self_share);
    std::printf("%-5d %-6d %-8.2f %-7d %-6d %-9.6f %-10.3g %-10.3g %-5d %-7.3f %-7.3f %s\n", seed, verts, wall,
                newton, halved, s1, obstacle, ground, self, share, self_share, verdict.c_str());
    std::fflush(stdout);
    if (out)
      out << name << ',' << seed << ',' << verts << ',' << wall << ',' << newton << ',' << halved << ',' << s1 << ','
          << obstacle << ',' << ground << ',' << self << ',' << share << ',' << self_share << ',' << verdict << '\n';
  }
  std::sort(walls.begin(), walls.end());
  std::printf("%s: %d seeds, %d failed; wall time median %.2f s, worst %.2f s; contact (obstacles + self) "
              "median %.0f%% of the wall time\n",
              name.c_str(), seeds, failures, median(walls), walls.back(), 100 * median(shares));
  return failures == 0 ? 0 : 1;
}
