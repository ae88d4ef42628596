// The fold scenario over seeds (issue 16 acceptance): every run finishes, no NaN, no penetration
// of the ground or the roller at any step, no self-intersection at the end, the largest
// principal stretch within the limit; and at the end (2.5 s after the release) a plastic crease
// along the fold: the plastic crease network (papersim metrics, from the plastic state alone)
// has a line at least half as long as the fold, and the plastic curvature across the fold,
// integrated over a 2 cm band about the fold line, gives the fold's residual rest angle.
// Reports wall time per sample (median, worst).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/metrics.hpp"
#include "validation/safety.hpp"
#include "validation/statistics.hpp"

namespace ps = papersim::simulation;
namespace pv = papersim::validation;

namespace {

constexpr double BAND = 0.01;  ///< half-width of the band about the fold line [m]

/// The fold line of a fold scene in material space: through the centre, perpendicular to d.
struct FoldLine {
  Eigen::Vector2d centre, d;
  double chord = 0;  ///< length of the line inside the sheet [m]
};

FoldLine fold_line(const ps::Scene& scene) {
  FoldLine f;
  f.centre = Eigen::Vector2d(0.5 * scene.sheet.width, 0.5 * scene.sheet.height);
  f.d = (f.centre - scene.handles.at(0).material_point).normalized();
  // Half-chord along t = perp(d) from the centre to the rectangle's boundary.
  const Eigen::Vector2d t(-f.d.y(), f.d.x());
  double half = INFINITY;
  for (int a = 0; a < 2; ++a)
    if (std::abs(t[a]) > 1e-12) half = std::min(half, f.centre[a] / std::abs(t[a]));
  f.chord = 2 * half;
  return f;
}

/// Residual rest angle of the fold [rad]: the plastic normal curvature across the fold,
/// d^T Kp d, integrated over the faces whose centroid lies within BAND of the fold line and
/// divided by the fold's length (the band's area over its width).
double fold_rest_angle(const papersim::remesh::SheetMesh& mesh, const FoldLine& f) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const Eigen::MatrixX3d K = mesh.plastic_curvature();
  double integral = 0, area = 0;
  for (int i = 0; i < F.rows(); ++i) {
    const Eigen::Vector2d a = X.row(F(i, 0)), b = X.row(F(i, 1)), c = X.row(F(i, 2));
    if (std::abs(((a + b + c) / 3 - f.centre).dot(f.d)) > BAND) continue;
    const double A = 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    const double kn = K(i, 0) * f.d.x() * f.d.x() + K(i, 1) * f.d.y() * f.d.y() + 2 * K(i, 2) * f.d.x() * f.d.y();
    integral += kn * A;
    area += A;
  }
  return area > 0 ? integral / (area / (2 * BAND)) : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"papersim_fold_study: the fold scenario over seeds, with its acceptance checks"};
  std::string csv;
  int seeds = 20, first = 0;
  double crease_angle = 30.0, edge = 0.0;
  app.add_option("--seeds", seeds, "number of seeds")->check(CLI::PositiveNumber);
  app.add_option("--first", first, "first seed (seeds first .. first + N - 1)")->check(CLI::NonNegativeNumber);
  app.add_option("--crease-angle", crease_angle, "crease threshold of the plastic network [deg]")
      ->check(CLI::Range(0.1, 179.0));
  app.add_option("--edge", edge, "initial edge length [m] instead of the scenario's (0: the scenario's)")
      ->check(CLI::Range(0.0, 0.05));
  app.add_option("--csv", csv, "also write the table as CSV");
  CLI11_PARSE(app, argc, argv);
  std::printf("%-5s %-6s %-8s %-7s %-6s %-9s %-10s %-10s %-5s %-6s %-9s %-9s %-9s %s\n", "seed", "verts", "wall_s",
              "newton", "halved", "max_s1", "min_roller", "min_ground", "self", "plines", "longest_m", "fold_m",
              "rest_deg", "verdict");
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "seed,vertices,wall_seconds,newton_iterations,failed_solves,max_stretch,min_roller,min_ground,"
           "self_intersections,plastic_lines,longest_plastic_line,fold_length,fold_rest_angle_deg,verdict\n";
  }
  int failures = 0;
  std::vector<double> walls;
  for (int seed = first; seed < first + seeds; ++seed) {
    ps::Scene scene = ps::make_scenario("fold", seed);
    if (edge > 0) scene.sheet.edge_length = edge;
    const FoldLine line = fold_line(scene);
    std::string verdict = "PASS";
    double wall = 0, s1 = 0, roller = INFINITY, ground = INFINITY, longest = 0, rest = 0;
    int newton = 0, halved = 0, verts = 0, self = -1, lines = 0;
    try {
      const ps::RunResult r = ps::run_scene(scene, {});
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
      lines = m.creases.plastic_network_lines;
      longest = lines > 0 ? m.creases.plastic_network_line_lengths.front() : 0.0;
      rest = fold_rest_angle(r.mesh, line) * 180 / M_PI;
      verdict = pv::safety_verdict(scene, r);
      if (verdict == "PASS" && longest < 0.5 * line.chord) verdict = "FAIL no plastic crease along the fold";
    } catch (const std::exception& e) {
      verdict = std::string("FAIL ") + e.what();
    }
    if (verdict != "PASS") ++failures;
    walls.push_back(wall);
    std::printf("%-5d %-6d %-8.1f %-7d %-6d %-9.6f %-10.3g %-10.3g %-5d %-6d %-9.4f %-9.4f %-9.1f %s\n", seed, verts,
                wall, newton, halved, s1, roller, ground, self, lines, longest, line.chord, rest, verdict.c_str());
    std::fflush(stdout);
    if (out)
      out << seed << ',' << verts << ',' << wall << ',' << newton << ',' << halved << ',' << s1 << ',' << roller << ','
          << ground << ',' << self << ',' << lines << ',' << longest << ',' << line.chord << ',' << rest << ','
          << verdict << '\n';
  }
  std::sort(walls.begin(), walls.end());
  std::printf("fold: %d seeds, %d failed; wall time median %.1f s, worst %.1f s\n", seeds, failures,
              pv::median(walls), walls.back());
  return failures == 0 ? 0 : 1;
}
