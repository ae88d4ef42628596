// The stress suite's 180-degree fold (validation/fold_scene.hpp) on uniform meshes and remeshed
// (issue 14): a fold sharper than the edges is smeared, and the Morley plate then stores a third
// to a half of the fold's energy (docs/elastica_30deg_diagnosis.md). For each run: vertices,
// CPU time, the bending energy at the end, the fold's measured radius r (half the height of the
// loop: the largest minus the smallest z of the sheet's mid-surface, the bottom layer lying flat
// on the ground) and the continuum bending energy of a 180-degree arc of that radius over the
// sheet's width w, pi D w / r (the convention of papersim_bending_probe), with their ratio; and
// the safety figures (self-intersecting pairs, largest stretch, smallest ground distance).
//   papersim_fold_remesh [--edges 8,4] [--remesh 1:100,2:100] [--start-edge 8] [--csv F]
// Sizes in mm. The loop of a pressed fold is a teardrop, not a semicircle: the ratio measures
// how much of the fold's energy a mesh keeps relative to the arc that spans the same height, so
// it is compared between meshes, not expected to be 1.
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "common/cli_checks.hpp"
#include "simulation/simulate.hpp"
#include "validation/fold_scene.hpp"
#include "validation/study_table.hpp"

namespace ps = papersim::simulation;

namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Comma-separated positive numbers.
std::vector<double> numbers(const std::string& text, const char* option) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !(x > 0) || !std::isfinite(x))
      throw std::runtime_error(std::string(option) + ": '" + item + "' is not a positive number");
    out.push_back(x);
  }
  return out;
}

struct Row {
  std::string mesh;
  std::string failure;  ///< why the run failed (empty when it finished)
  int vertices = 0, vertices_max = 0, self = -1, rollbacks = 0;
  double cpu = 0, bend = 0, radius = 0, continuum = 0, stretch = 0, limit = 0, ground = 0;
};

Row run(const std::string& label, const ps::Scene& scene) {
  std::fprintf(stderr, "%s ...\n", label.c_str());
  const double c0 = cpu_seconds();
  Row row;
  row.mesh = label;
  ps::RunResult r;
  try {
    r = ps::run_scene(scene, {});
  } catch (const std::exception& e) {  // reported in the table; the other meshes still run
    row.failure = e.what();
    row.cpu = cpu_seconds() - c0;
    std::fprintf(stderr, "%s failed: %s\n", label.c_str(), e.what());
    return row;
  }
  row.cpu = cpu_seconds() - c0;
  row.vertices = r.sheet.vertices;
  row.vertices_max = r.sheet.vertices_max;
  row.bend = r.energy.bend;
  const Eigen::VectorXd& x = r.state.positions;
  double zmin = INFINITY, zmax = -INFINITY;
  for (Eigen::Index i = 2; i < x.size(); i += 3)
    zmin = std::min(zmin, x(i)), zmax = std::max(zmax, x(i));
  row.radius = 0.5 * (zmax - zmin);
  row.continuum = M_PI * scene.sheet.material.bending_stiffness * scene.sheet.height / row.radius;
  row.self = r.quality.self_intersections;
  row.stretch = r.quality.max_principal_stretch;
  row.limit = r.quality.strain_limit;
  row.ground =
      r.quality.min_obstacle_distance.empty() ? NAN : r.quality.min_obstacle_distance.front();
  if (r.remesh) row.rollbacks = r.remesh->rollbacks;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_fold_remesh: the 180-degree fold's energy against the continuum, uniform vs "
      "remeshed"};
  std::string edges_text = "8,4", remesh_text = "1:100", csv;
  double start_edge = 8;
  app.add_option("--edges", edges_text, "uniform edge lengths [mm], comma separated")
      ->capture_default_str();
  app.add_option(
         "--remesh", remesh_text,
         "remeshed runs, comma separated MIN:MAX (remesh.size_min and size_max [mm]); empty: none")
      ->capture_default_str();
  app.add_option("--start-edge", start_edge, "start mesh of the remeshed runs [mm]")
      ->capture_default_str()
      ->check(papersim::common::positive());
  app.add_option("--csv", csv, "also write the table as CSV");
  CLI11_PARSE(app, argc, argv);
  try {
    // Every setting is read, and the CSV's path written, before the first run.
    std::vector<std::pair<double, double>> remeshes;
    std::stringstream in(remesh_text);
    std::string item;
    while (std::getline(in, item, ',')) {
      double lo = 0, hi = 0;
      int used = 0;
      if (std::sscanf(item.c_str(), "%lf:%lf%n", &lo, &hi, &used) != 2 ||
          used != static_cast<int>(item.size()) || !(lo > 0) || !(hi >= lo) || !std::isfinite(hi))
        throw std::runtime_error("--remesh: '" + item +
                                 "' is not MIN:MAX in mm with 0 < MIN <= MAX");
      remeshes.emplace_back(lo, hi);
    }
    const std::vector<double> edges = numbers(edges_text, "--edges");
    papersim::validation::StudyTable table(
        csv,
        "mesh,vertices,vertices_max,cpu_seconds,bending_energy_J,radius_m,continuum_J,ratio,"
        "self_intersections,max_stretch,min_ground_m,remesh_rollbacks,failure");
    std::vector<Row> rows;
    for (double e : edges) {
      char label[32];
      std::snprintf(label, sizeof label, "uniform %g mm", e);
      rows.push_back(run(label, papersim::validation::fold_180_scene(1e-3 * e)));
    }
    for (const auto& [lo, hi] : remeshes) {
      ps::Scene s = papersim::validation::fold_180_scene(1e-3 * start_edge);
      s.remesh.enabled = true;
      s.remesh.params.size_min = 1e-3 * lo;
      s.remesh.params.size_max = 1e-3 * hi;
      char label[64];
      std::snprintf(label, sizeof label, "remesh %g:%g", lo, hi);
      rows.push_back(run(label, s));
    }
    std::printf("%-16s %8s %8s %8s %12s %9s %12s %7s %5s %10s %10s %6s\n", "mesh", "vertices",
                "max_vert", "cpu_s", "bend_J", "radius_mm", "continuum_J", "ratio", "self",
                "max_s1", "ground_mm", "rollb");
    bool safe = true;
    for (const Row& r : rows) {
      std::ostringstream out;
      if (!r.failure.empty()) {
        std::printf("%-16s FAILED after %.1f s of CPU: %s\n", r.mesh.c_str(), r.cpu,
                    r.failure.c_str());
        out << r.mesh << ",,," << r.cpu << ",,,,,,,,,\"" << r.failure << '"';
        table.add(out.str());
        safe = false;
        continue;
      }
      std::printf("%-16s %8d %8d %8.1f %12.4g %9.2f %12.4g %7.3f %5d %10.6f %10.4f %6d\n",
                  r.mesh.c_str(), r.vertices, r.vertices_max, r.cpu, r.bend, 1e3 * r.radius,
                  r.continuum, r.bend / r.continuum, r.self, r.stretch, 1e3 * r.ground,
                  r.rollbacks);
      out << r.mesh << ',' << r.vertices << ',' << r.vertices_max << ',' << r.cpu << ',' << r.bend
          << ',' << r.radius << ',' << r.continuum << ',' << r.bend / r.continuum << ',' << r.self
          << ',' << r.stretch << ',' << r.ground << ',' << r.rollbacks << ',';
      table.add(out.str());
      safe = safe && r.self == 0 && r.ground > 0 && r.stretch <= 1 + r.limit;
    }
    return safe ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_fold_remesh: %s\n", e.what());
    return 1;
  }
}
