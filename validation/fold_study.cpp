// The fold scenario over seeds (issue 16 acceptance): every run finishes, no NaN, no penetration
// of the ground or the roller at any step, no self-intersection at the end, the largest
// principal stretch within the limit; and at the end (2.5 s after the release) a plastic crease
// along the fold: the straight line that best fits the plastic curvature within 5 cm of the
// fold line the scenario aims at is found, and the residual rest angle across it (plastic
// curvature integrated over a 4 cm band, piece by piece along the line; validation/fold_crease.hpp)
// exceeds the crease threshold along a run at least half as long as the line. Reports where that
// crease lies against the aimed line (offset, turn), the crease lines along it (count, longest,
// total length, mean rest angle) and wall time per sample (median, worst).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "common/cli_checks.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/fold_crease.hpp"
#include "validation/metrics.hpp"
#include "validation/safety.hpp"
#include "validation/statistics.hpp"
#include "validation/study_table.hpp"

namespace ps = papersim::simulation;
namespace pv = papersim::validation;

namespace {

/// The fold line a fold scene aims at: through the sheet's centre, perpendicular to the
/// direction from the pulled point to the centre.
pv::FoldLine aimed_line(const ps::Scene& scene) {
  const Eigen::Vector2d centre(0.5 * scene.sheet.width, 0.5 * scene.sheet.height);
  return pv::fold_line_in_rectangle(centre, centre - scene.handles.at(0).material_point,
                                    scene.sheet.width, scene.sheet.height);
}

/// The crease near the aimed line: the fitted line and the crease measured along it.
struct CreaseFound {
  pv::FoldLine line;
  pv::FoldCrease crease;
  double offset = 0.0;  ///< distance of the aimed line's centre from the fitted line [m]
  double turn = 0.0;    ///< angle between the two lines [deg]
  int network = 0;      ///< lines of `papersim metrics`' plastic crease network
};

CreaseFound find_crease(const ps::Scene& scene, const papersim::remesh::SheetMesh& mesh,
                        const Eigen::MatrixX3d& positions, double crease_angle_deg) {
  const pv::FoldLine aimed = aimed_line(scene);
  CreaseFound f;
  pv::MetricsOptions metrics_options;
  metrics_options.crease_angle_deg = crease_angle_deg;
  f.network = pv::compute_metrics(mesh.material_coords(), positions, mesh.faces(),
                                  mesh.plastic_curvature(), metrics_options)
                  .creases.plastic_network_lines;
  f.line = pv::fit_crease_line(mesh.material_coords(), mesh.faces(), mesh.plastic_curvature(),
                               aimed, scene.sheet.width, scene.sheet.height);
  pv::FoldCreaseOptions options;
  options.threshold = crease_angle_deg * M_PI / 180;
  f.crease = pv::measure_fold_crease(mesh.material_coords(), mesh.faces(), mesh.plastic_curvature(),
                                     f.line, options);
  f.offset = std::abs((aimed.centre - f.line.centre).dot(f.line.d));
  f.turn = std::acos(std::clamp(std::abs(f.line.d.dot(aimed.d)), 0.0, 1.0)) * 180 / M_PI;
  return f;
}

/// The study's verdict: the safety verdict, and a crease along at least half the fitted line.
std::string crease_verdict(const std::string& safety, const CreaseFound& f) {
  if (safety == "PASS" && f.crease.longest < 0.5 * f.line.chord)
    return "FAIL no plastic crease along the fold";
  return safety;
}

/// The quality figures of a finished run's meta.json (`quality`).
ps::RunQuality quality_from_meta(const nlohmann::json& q) {
  ps::RunQuality r;
  r.max_principal_stretch = q.at("max_principal_stretch").get<double>();
  r.min_principal_stretch = q.at("min_principal_stretch").get<double>();
  r.min_obstacle_distance = q.at("min_obstacle_distance").get<std::vector<double>>();
  r.self_intersections = q.at("self_intersections").get<int>();
  return r;
}

/// --measure: the crease of finished runs (DIR/sheet.ply, and the scene from DIR/scene.json or
/// else DIR/meta.json); with DIR/meta.json also the run's figures and the study's verdict.
/// Returns 1 when a verdict is FAIL.
/// With `csv`, the table is also written there as CSV (the columns of the table), through a
/// temporary name renamed once every row is written.
int measure(const std::vector<std::string>& dirs, double crease_angle, const std::string& csv) {
  for (const std::string& dir : dirs)
    if (!std::filesystem::exists(dir + "/sheet.ply"))
      throw std::runtime_error(dir + ": not a finished run (no sheet.ply)");
  // One list of columns for both the table and the CSV: name and table width.
  static const std::vector<std::pair<const char*, int>> columns = {
      {"seed", 5},        {"wall_s", 8},   {"newton", 7},   {"max_s1", 9},    {"min_roller", 10},
      {"min_ground", 10}, {"self", 5},     {"lines", 6},    {"longest_m", 9}, {"creased_m", 9},
      {"line_m", 9},      {"rest_deg", 9}, {"mean_deg", 8}, {"network", 8},   {"offset_mm", 9},
      {"turn_deg", 8},    {"run", 24},     {"verdict", 0}};
  std::ostringstream rows;
  const auto emit = [&](const std::vector<std::string>& cells) {
    if (cells.size() != columns.size())
      throw std::logic_error("fold_study: a row of the wrong width");
    for (std::size_t c = 0; c < columns.size(); ++c) {
      std::printf(c + 1 < columns.size() ? "%-*s " : "%-*s\n", columns[c].second, cells[c].c_str());
      rows << cells[c] << (c + 1 < columns.size() ? ',' : '\n');
    }
  };
  {
    std::vector<std::string> names;
    for (const auto& [name, width] : columns) names.emplace_back(name);
    emit(names);
  }
  const auto fixed = [](const char* format, double v) {
    char b[64];
    std::snprintf(b, sizeof b, format, v);
    return std::string(b);
  };
  int failures = 0;
  for (const std::string& dir : dirs) {
    nlohmann::json meta;
    const bool has_meta = std::filesystem::exists(dir + "/meta.json");
    if (has_meta) {
      std::ifstream in(dir + "/meta.json");
      try {
        meta = nlohmann::json::parse(in);
      } catch (const std::exception& e) {
        throw std::runtime_error(dir + "/meta.json: " + e.what());
      }
    }
    const ps::Scene scene = std::filesystem::exists(dir + "/scene.json") || !has_meta
                                ? ps::load_scene(dir + "/scene.json")
                                : ps::scene_from_json(meta.at("scene"), dir + "/meta.json");
    if (scene.handles.empty()) throw std::runtime_error(dir + ": not a fold scene (no handle)");
    const papersim::remesh::SheetData sheet = papersim::remesh::read_sheet(dir + "/sheet.ply");
    const CreaseFound f = find_crease(scene, sheet.mesh, sheet.positions, crease_angle);
    std::string wall = "-", newton = "-", s1 = "-", roller = "-", ground = "-", self = "-",
                verdict = "-";
    if (has_meta) {
      try {
        const ps::RunQuality q = quality_from_meta(meta.at("quality"));
        const pv::ObstacleGaps gaps = pv::obstacle_gaps(scene, q);
        wall = fixed("%.1f", meta.at("run").at("wall_seconds").get<double>());
        newton = std::to_string(meta.at("run").at("newton_iterations").get<int>());
        s1 = fixed("%.6f", q.max_principal_stretch);
        roller = fixed("%.3g", gaps.obstacles);
        ground = fixed("%.3g", gaps.ground);
        self = std::to_string(q.self_intersections);
        verdict = crease_verdict(pv::safety_verdict(scene, q, sheet.positions.allFinite()), f);
      } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(dir + "/meta.json: " + e.what());
      }
      if (verdict != "PASS") ++failures;
    }
    emit({std::to_string(scene.seed), wall, newton, s1, roller, ground, self,
          std::to_string(f.crease.lines), fixed("%.4f", f.crease.longest),
          fixed("%.4f", f.crease.creased), fixed("%.4f", f.line.chord),
          fixed("%.1f", f.crease.angle * 180 / M_PI), fixed("%.1f", f.crease.mean_all * 180 / M_PI),
          std::to_string(f.network), fixed("%.1f", f.offset * 1e3), fixed("%.2f", f.turn), dir,
          verdict});
  }
  if (!csv.empty()) papersim::common::write_text_atomically(csv, rows.str());
  return failures == 0 ? 0 : 1;
}

}  // namespace

// The study; main turns an unwritable --csv into exit status 5.
static int study(int argc, char** argv) {
  CLI::App app{"papersim_fold_study: the fold scenario over seeds, with its acceptance checks"};
  std::string csv, keep;
  std::vector<std::string> measure_dirs;
  int seeds = 20, first = 0;
  double crease_angle = 30.0, edge = 0.0;
  app.add_option("--seeds", seeds, "number of seeds")->check(papersim::common::positive());
  app.add_option("--first", first, "first seed (seeds first .. first + N - 1)")
      ->check(papersim::common::non_negative());
  app.add_option("--crease-angle", crease_angle,
                 "crease threshold of the residual rest angle [deg]")
      ->check(CLI::Range(0.1, 179.0));
  app.add_option("--edge", edge,
                 "initial edge length [m] instead of the scenario's (0: the scenario's)")
      ->check(CLI::Range(0.0, 0.05));
  app.add_option("--csv", csv, "also write the table as CSV");
  app.add_option("--keep", keep,
                 "write each seed's outputs (sheet.ply with the plastic state, meta.json, "
                 "scene.json) to DIR/seed_N");
  app.add_option("--measure", measure_dirs,
                 "only measure finished runs and stop: each DIR with sheet.ply and the scene "
                 "(scene.json, or else meta.json), e.g. from --keep, papersim scenario fold or "
                 "papersim run; with meta.json also the run's safety checks and the verdict "
                 "(exit status 1 when one is FAIL)")
      ->check(CLI::ExistingDirectory);
  CLI11_PARSE(app, argc, argv);
  if (!measure_dirs.empty()) {
    try {
      return measure(measure_dirs, crease_angle, csv);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "papersim_fold_study: %s\n", e.what());
      return 2;
    }
  }
  pv::StudyTable table(csv,
                       "seed,vertices,wall_seconds,newton_iterations,failed_solves,max_stretch,"
                       "min_roller,min_ground,self_intersections,crease_lines,longest_crease,"
                       "creased_length,fold_length,crease_rest_angle_deg,fold_mean_rest_angle_deg,"
                       "plastic_network_lines,crease_offset_m,crease_turn_deg,verdict");
  std::printf(
      "%-5s %-6s %-8s %-7s %-6s %-9s %-10s %-10s %-5s %-6s %-9s %-9s %-9s %-8s %-8s %-7s %-9s %-8s "
      "%s\n",
      "seed", "verts", "wall_s", "newton", "halved", "max_s1", "min_roller", "min_ground", "self",
      "lines", "longest_m", "creased_m", "fold_m", "rest_deg", "mean_deg", "network", "offset_mm",
      "turn_deg", "verdict");
  int failures = 0;
  std::vector<double> walls;
  for (int seed = first; seed < first + seeds; ++seed) {
    ps::Scene scene = ps::make_scenario("fold", seed);
    if (edge > 0) scene.sheet.edge_length = edge;
    const pv::FoldLine aimed = aimed_line(scene);
    std::string verdict = "PASS";
    double wall = 0, s1 = 0, roller = INFINITY, ground = INFINITY;
    int newton = 0, halved = 0, verts = 0, self = -1;
    CreaseFound found;
    found.line = aimed;
    auto start = std::chrono::steady_clock::now();
    try {
      ps::RunOptions run_options;
      // Progress on stderr every 10% of the simulated time, and every 5 minutes of wall time
      // while the steps are slow, with the ETA of this seed.
      run_options.progress = [seed, last = -1, printed = 0.0](double f, double seconds) mutable {
        const int tenth = static_cast<int>(10 * f);
        if (tenth == last && seconds - printed < 300.0) return;
        const double eta = f > 0 ? seconds * (1 - f) / f : 0.0;
        if (tenth == last)
          std::fprintf(stderr, "fold seed %d %5.1f%%  elapsed %.0f s  ETA %.0f s\n", seed, 100 * f,
                       seconds, eta);
        else
          std::fprintf(stderr, "fold seed %d %3d%%  elapsed %.0f s  ETA %.0f s\n", seed, 10 * tenth,
                       seconds, eta);
        last = tenth;
        printed = seconds;
      };
      if (!keep.empty()) {
        run_options.out_dir = keep + "/seed_" + std::to_string(seed);
        std::ostringstream text;
        text << std::setw(2) << ps::scene_to_json(scene) << '\n';
        run_options.extra_files.emplace_back("scene.json", text.str());
      }
      start = std::chrono::steady_clock::now();
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
      found = find_crease(scene, r.mesh, r.state.positions_matrix(), crease_angle);
      verdict = crease_verdict(pv::safety_verdict(scene, r), found);
    } catch (const std::exception& e) {
      // Wall time up to the failure.
      wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      verdict = std::string("FAIL ") + e.what();
    }
    if (verdict != "PASS") ++failures;
    walls.push_back(wall);
    const double deg = 180 / M_PI;
    const pv::FoldCrease& crease = found.crease;
    const pv::FoldLine& line = found.line;
    const double offset = found.offset, turn = found.turn;
    std::printf(
        "%-5d %-6d %-8.1f %-7d %-6d %-9.6f %-10.3g %-10.3g %-5d %-6d %-9.4f %-9.4f %-9.4f %-8.1f "
        "%-8.1f %-7d %-9.1f "
        "%-8.1f %s\n",
        seed, verts, wall, newton, halved, s1, roller, ground, self, crease.lines, crease.longest,
        crease.creased, line.chord, crease.angle * deg, crease.mean_all * deg, found.network,
        offset * 1e3, turn, verdict.c_str());
    std::fflush(stdout);
    if (table.enabled()) {  // rewritten whole after every seed: a stopped study keeps the seeds it
                            // finished
      std::ostringstream row;
      row << seed << ',' << verts << ',' << wall << ',' << newton << ',' << halved << ',' << s1
          << ',' << roller << ',' << ground << ',' << self << ',' << crease.lines << ','
          << crease.longest << ',' << crease.creased << ',' << line.chord << ','
          << crease.angle * deg << ',' << crease.mean_all * deg << ',' << found.network << ','
          << offset << ',' << turn << ',' << verdict;
      table.add(row.str());
    }
  }
  std::sort(walls.begin(), walls.end());
  std::printf("fold: %d seeds, %d failed; wall time median %.1f s, worst %.1f s\n", seeds, failures,
              pv::median(walls), walls.back());
  return failures == 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  return papersim::validation::run_study("fold_study", study, argc, argv);
}
