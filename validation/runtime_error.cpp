// Run time against error (issue 5 item 2): scenario draws (seeds) simulated over a sweep of
// mesh edge length and time step (uniform meshes) and of remeshing settings (adaptive meshes from
// a coarse start, --remesh), each result compared with a fine reference run of the same
// draw (validation/compare.hpp: RMS and max position error at the same material points,
// symmetric Hausdorff distance; and the shape error, RMS after the best rigid alignment). Writes
// OUT/runtime_error.csv (every draw and setting), OUT/runtime_error_summary.csv (per setting over
// the draws: median wall and CPU time, median and worst RMS error, worst max error) and
// OUT/runtime_error.png (gnuplot: median CPU time against the worst RMS error, one series per mesh
// mode and time step), prints the tables, the settings no other setting beats on both time and
// error (the Pareto front), and the cheapest setting whose RMS error is below --target on every
// draw.
//   papersim_runtime_error --out DIR [--scenario pull] [--seeds 0,1,2,3,4,5,6,7]
//       [--edges 20,14,10,7] [--steps 20,10,5] [--reference-edge 5] [--reference-step 2.5]
//       [--target 2] [--check-edge 3.5] [--remesh 3:100,6:100] [--remesh-start 21]
//       [--set KEY=VALUE ...] [--set-all KEY=VALUE ...] [--replot]
// Edges and the target are in mm, steps in ms. A --remesh setting MIN:MAX[:ANGLE][@EVERY] runs the
// draw with remeshing on (remesh.size_min MIN mm, size_max MAX mm, refine_angle ANGLE rad, a pass
// every EVERY steps, the scene's other remesh keys), starting from a uniform mesh of
// --remesh-start mm, at every step of --steps.
// Cost is measured as the CPU time of the run (this process is single-threaded; on a loaded machine
// CPU time is the steadier figure), wall time is recorded too. Each draw's reference is written to
// DIR/seed_N/reference and reused by later runs from the same scene (draw, resolution, material,
// solver settings: the whole scene file); each sweep run's result is written to
// DIR/seed_N/runs/*.json and read back by a later study of the same scene and reference, so an
// interrupted study resumes, and processes on different seeds can share DIR. --check-edge runs each
// draw once more, finer (DIR/seed_N/reference_check), and compares it with its reference: a draw
// whose end state changes under refinement (a draped sheet choosing another fold pattern) has no
// converged reference, so it is reported and left out of the summary; when no draw holds, no
// setting is recommended and the exit status is 1.
// --set KEY=VALUE changes a scene key of the sweep's runs, not of the references, so a solver
// option (or a remeshing key the sweep does not set, such as remesh.aspect_min) is measured
// against the same references: a study with --set in the same DIR reuses them,
// and its runs are stored apart from those without (the CSVs and the plot are the last study's).
// --set-all KEY=VALUE changes a scene key of every run, the references included: another physics
// (a material key) measured against references of that physics, in a DIR of its own.
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "common/cli_checks.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/batch.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/compare.hpp"
#include "validation/statistics.hpp"

namespace fs = std::filesystem;
namespace ps = papersim::simulation;
namespace pv = papersim::validation;

namespace {

/// A remeshing setting of the sweep: sizes in mm, refine angle in rad (0: the scene's), steps
/// between passes (0: the scene's remesh.every).
struct RemeshSetting {
  double size_min_mm = 0, size_max_mm = 0, angle = 0;
  int every = 0;
  /// "off" for a uniform mesh, else "MIN:MAX" or "MIN:MAX:ANGLE", with "@EVERY" when set.
  std::string label() const;
};

struct Sample {
  std::string remesh = "off";  ///< RemeshSetting::label()
  double edge_mm = 0, step_ms = 0;
  int vertices = 0, vertices_max = 0, steps = 0;
  long newton = 0;
  double wall = 0, cpu = 0;
  pv::SheetDifference error;
};

pv::SheetGeometry geometry_of(const papersim::remesh::SheetMesh& mesh,
                              const Eigen::MatrixX3d& positions) {
  return {mesh.material_coords(), positions, mesh.faces()};
}

Eigen::MatrixX3d as_rows(const Eigen::VectorXd& x) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
      x.data(), x.size() / 3, 3);
}

ps::Scene with_resolution(ps::Scene scene, double edge_mm, double step_ms) {
  scene.sheet.edge_length = 1e-3 * edge_mm;
  scene.time_step = 1e-3 * step_ms;
  return scene;
}

/// x with %g (shortest form: 2.5, not 2.500000).
std::string format_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

std::string RemeshSetting::label() const {
  if (!(size_min_mm > 0)) return "off";
  return format_number(size_min_mm) + ":" + format_number(size_max_mm) +
         (angle > 0 ? ":" + format_number(angle) : "") +
         (every > 0 ? "@" + std::to_string(every) : "");
}

/// `scene` with remeshing on at `setting` (uniform start mesh of start_mm), or off.
ps::Scene with_remesh(ps::Scene scene, const RemeshSetting& setting, double start_mm) {
  scene.remesh.enabled = setting.size_min_mm > 0;
  if (!scene.remesh.enabled) return scene;
  scene.sheet.edge_length = 1e-3 * start_mm;
  scene.remesh.params.size_min = 1e-3 * setting.size_min_mm;
  scene.remesh.params.size_max = 1e-3 * setting.size_max_mm;
  if (setting.angle > 0) scene.remesh.params.refine_angle = setting.angle;
  if (setting.every > 0) scene.remesh.every = setting.every;
  return scene;
}

/// CPU time of this process [s].
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Progress on stderr: percent and ETA of one run.
ps::RunOptions progress_options(const std::string& label) {
  ps::RunOptions o;
  o.progress = [label](double f, double s) {
    const double eta = f > 0 ? s * (1 - f) / f : 0;
    std::fprintf(stderr, "\r  %-28s %5.1f%%  %6.1f s, ETA %6.1f s   ", label.c_str(), 100 * f, s,
                 eta);
    if (f >= 1) std::fprintf(stderr, "\n");
  };
  return o;
}

/// A reference run, read back from DIR/NAME when it was made from the same scene (every field:
/// draw, resolution, material and bending model, solver settings).
pv::SheetGeometry reference_run(const ps::Scene& scene, const fs::path& dir,
                                const std::string& name, double& wall) {
  const fs::path ref = dir / name;
  const nlohmann::json key = ps::scene_to_json(scene);
  if (fs::exists(ref / "sheet.obj") && fs::exists(ref / "meta.json")) {
    std::ifstream in(ref / "meta.json");
    const nlohmann::json meta = nlohmann::json::parse(in, nullptr, false);
    if (!meta.is_discarded() && meta.contains("study_key") && meta["study_key"] == key) {
      const auto data = papersim::remesh::read_sheet((ref / "sheet.obj").string());
      wall = meta["run"]["wall_seconds"];
      std::printf("%s: reused %s (%.1f s when made)\n", name.c_str(), ref.c_str(), wall);
      return geometry_of(data.mesh, data.positions);
    }
  }
  fs::remove_all(ref);
  ps::RunOptions o = progress_options(name);
  o.out_dir = ref.string();
  o.extra_meta = {{"study_key", key}};
  const ps::RunResult r = ps::run_scene(scene, o);
  wall = r.wall_seconds;
  return geometry_of(r.mesh, as_rows(r.state.positions));
}

/// A comma-separated list of positive numbers, or with `seeds` of non-negative integers.
std::vector<double> parse_list(const std::string& text, const char* what, bool seeds = false) {
  std::vector<double> v;
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t end = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, end - pos);
    char* stop = nullptr;
    const double x = std::strtod(item.c_str(), &stop);
    const bool ok = !item.empty() && *stop == '\0' &&
                    (seeds ? x >= 0 && x == std::floor(x) && x < 9e15 : x > 0);
    if (!ok)
      throw std::runtime_error(std::string("--") + what + ": '" + item + "' is not a " +
                               (seeds ? "non-negative integer" : "positive number"));
    v.push_back(x);
    pos = end + 1;
  }
  return v;
}

/// --remesh: a comma-separated list of MIN:MAX[:ANGLE][@EVERY] (sizes in mm, MIN <= MAX; angle in
/// rad; EVERY steps between passes, a whole number >= 1).
std::vector<RemeshSetting> parse_remesh(const std::string& text) {
  std::vector<RemeshSetting> out;
  if (text.empty()) return out;
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t end = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, end - pos);
    const size_t at = item.find('@');
    const std::string sizes = item.substr(0, at);
    RemeshSetting r;
    int used = 0;
    const int n = std::sscanf(sizes.c_str(), "%lf:%lf%n:%lf%n", &r.size_min_mm, &r.size_max_mm,
                              &used, &r.angle, &used);
    bool ok = n >= 2 && used == static_cast<int>(sizes.size()) && r.size_min_mm > 0 &&
              r.size_max_mm >= r.size_min_mm && std::isfinite(r.size_max_mm) &&
              (n == 2 || (r.angle > 0 && std::isfinite(r.angle)));
    if (at != std::string::npos) {
      const std::string every = item.substr(at + 1);
      int every_used = 0;
      ok = ok && std::sscanf(every.c_str(), "%d%n", &r.every, &every_used) == 1 &&
           every_used == static_cast<int>(every.size()) && r.every >= 1;
    }
    if (!ok)
      throw std::runtime_error(
          "--remesh: '" + item +
          "' is not MIN:MAX[:ANGLE][@EVERY] (sizes in mm, 0 < MIN <= MAX; angle in rad, > 0; "
          "EVERY steps between passes, a whole number >= 1)");
    if (n == 2) r.angle = 0;
    out.push_back(r);
    pos = end + 1;
  }
  return out;
}

/// One draw of the study: its reference, the optional check of that reference, and the sweep.
struct SeedResult {
  long long seed = 0;
  int reference_vertices = 0;
  double reference_wall = 0;
  bool checked = false, converged = true;
  pv::SheetDifference check;  ///< the finer run against the reference (when checked)
  std::vector<Sample> samples;
};

/// One setting over the draws whose reference holds: the median wall time, the median and the
/// worst RMS error, and the worst max error.
struct Aggregate {
  std::string remesh = "off";
  double edge_mm = 0, step_ms = 0;
  int draws = 0;
  std::string seeds;  ///< the draws used, space separated
  double median_wall = 0, median_cpu = 0, median_vertices_max = 0, median_rms = 0, worst_rms = 0,
         worst_max = 0;
  double median_rms_aligned = 0, worst_rms_aligned = 0;  ///< shape error (compare.hpp)
};

/// "edge 7 mm" for a uniform setting, "remesh 3:100 from 21 mm" for a remeshed one.
std::string describe(const Aggregate& a) {
  return a.remesh == "off" ? "edge " + format_number(a.edge_mm) + " mm"
                           : "remesh " + a.remesh + " from " + format_number(a.edge_mm) + " mm";
}

using pv::median;

std::vector<Aggregate> aggregate(const std::vector<SeedResult>& draws) {
  std::vector<Aggregate> out;
  if (draws.empty()) return out;
  for (size_t k = 0; k < draws.front().samples.size(); ++k) {
    Aggregate a;
    a.remesh = draws.front().samples[k].remesh;
    a.edge_mm = draws.front().samples[k].edge_mm;
    a.step_ms = draws.front().samples[k].step_ms;
    std::vector<double> walls, cpus, vertices, rms, rms_aligned;
    for (const SeedResult& d : draws) {
      if (!d.converged) continue;
      const Sample& s = d.samples[k];
      a.seeds += (a.seeds.empty() ? "" : " ") + std::to_string(d.seed);
      walls.push_back(s.wall);
      cpus.push_back(s.cpu);
      vertices.push_back(s.vertices_max);
      rms.push_back(s.error.rms);
      rms_aligned.push_back(s.error.rms_aligned);
      a.worst_rms_aligned = std::max(a.worst_rms_aligned, s.error.rms_aligned);
      a.worst_rms = std::max(a.worst_rms, s.error.rms);
      a.worst_max = std::max(a.worst_max, s.error.max);
    }
    a.draws = static_cast<int>(walls.size());
    a.median_wall = median(walls);
    a.median_cpu = median(cpus);
    a.median_vertices_max = median(vertices);
    a.median_rms = median(rms);
    a.median_rms_aligned = median(rms_aligned);
    if (a.draws > 0) out.push_back(a);
  }
  return out;
}

/// Writes `text` to `path` through a temporary name, so a failure leaves no partial file.
void write_file(const fs::path& path, const std::string& text) {
  const fs::path tmp =
      path.string() + "." + std::to_string(getpid()) + ".tmp";  // processes may share DIR
  {
    std::ofstream out(tmp);
    out << text;
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, path);
}

void write_csv(const fs::path& path, const std::vector<SeedResult>& draws) {
  std::ostringstream out;
  out << "seed,reference_converged,remesh,edge_mm,step_ms,vertices,vertices_max,steps,newton_"
         "iterations,wall_seconds,"
         "cpu_seconds,rms_error_m,max_error_m,hausdorff_m,rms_shape_error_m,max_shape_error_m\n";
  for (const SeedResult& d : draws)
    for (const Sample& s : d.samples)
      out << d.seed << ',' << (d.checked ? (d.converged ? "yes" : "no") : "unchecked") << ','
          << s.remesh << ',' << s.edge_mm << ',' << s.step_ms << ',' << s.vertices << ','
          << s.vertices_max << ',' << s.steps << ',' << s.newton << ',' << s.wall << ',' << s.cpu
          << ',' << s.error.rms << ',' << s.error.max << ',' << s.error.hausdorff << ','
          << s.error.rms_aligned << ',' << s.error.max_aligned << '\n';
  write_file(path, out.str());
}

void write_summary_csv(const fs::path& path, const std::vector<Aggregate>& settings) {
  std::ostringstream out;
  out << "remesh,edge_mm,step_ms,draws,median_wall_seconds,median_cpu_seconds,median_vertices_max,"
         "median_rms_error_m,"
         "worst_rms_error_m,worst_max_error_m,seeds,median_rms_shape_error_m,worst_rms_shape_error_"
         "m\n";
  for (const Aggregate& a : settings)
    out << a.remesh << ',' << a.edge_mm << ',' << a.step_ms << ',' << a.draws << ','
        << a.median_wall << ',' << a.median_cpu << ',' << a.median_vertices_max << ','
        << a.median_rms << ',' << a.worst_rms << ',' << a.worst_max << ',' << a.seeds << ','
        << a.median_rms_aligned << ',' << a.worst_rms_aligned << '\n';
  write_file(path, out.str());
}

/// gnuplot, from OUT/runtime_error_summary.csv: median CPU time against the worst (filled) and
/// the median (open) RMS error over the draws, log-log, one colour per time step, circles for
/// uniform meshes labelled by the edge length, triangles for remeshed runs labelled MIN:MAX.
/// `mark` (edge and step of a uniform setting, {0, 0}: none) is circled and labelled "old default".
void write_plot(const fs::path& dir, const std::vector<double>& steps, const std::string& title,
                std::pair<double, double> mark) {
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,600 font 'DejaVu Sans,11'\n"
     << "set output 'runtime_error.png.tmp'\n"
     << "set title '" << title << "'\n"
     << "set logscale xy\nset grid\n"
     << "set xlabel 'RMS position error against the reference of each draw: worst (filled), median "
        "(open) [mm]'\n"
     << "set ylabel 'median CPU time per run [s]'\n"
     << "set key top right\nset datafile separator ','\n";
  // Only the series the summary has rows for (gnuplot fails on a labels series with no point).
  std::set<std::pair<bool, double>> present;
  {
    std::ifstream in(dir / "runtime_error_summary.csv");
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::stringstream row(line);
      std::string remesh, edge, step;
      if (std::getline(row, remesh, ',') && std::getline(row, edge, ',') &&
          std::getline(row, step, ','))
        present.insert({remesh != "off", std::strtod(step.c_str(), nullptr)});
    }
  }
  gp << "plot ";
  int series = 0;
  for (const bool remeshed : {false, true})
    for (size_t i = 0; i < steps.size(); ++i) {
      if (!present.count({remeshed, steps[i]})) continue;
      const std::string pick = std::string("(strcol(1) ") + (remeshed ? "ne" : "eq") +
                               " 'off' && $3==" + format_number(steps[i]) + " ? ";
      const int filled = remeshed ? 9 : 7, open = remeshed ? 8 : 6;
      if (series++) gp << ", \\\n     ";
      gp << "'runtime_error_summary.csv' every ::1 using " << pick
         << "$9*1e3 : 1/0):6 with points pt " << filled << " ps 1.3 lc " << i + 1 << " title '"
         << (remeshed ? "remeshed" : "uniform") << ", step " << format_number(steps[i]) << " ms', "
         << "'' every ::1 using " << pick << "$8*1e3 : 1/0):6 with points pt " << open
         << " ps 1.3 lc " << i + 1 << " notitle, "
         << "'' every ::1 using " << pick << "$9*1e3 : 1/0):6:("
         << (remeshed ? "strcol(1)" : "sprintf('%g mm', $2)")
         << ") with labels offset 1.2,0.6 font ',9' notitle";
    }
  if (mark.first > 0)
    gp << ", \\\n     'runtime_error_summary.csv' every ::1 using (strcol(1) eq 'off' && $2=="
       << format_number(mark.first) << " && $3==" << format_number(mark.second)
       << " ? $9*1e3 : 1/0):6 with points pt 4 ps 3.5 lc rgb 'black' "
       << "title 'old default (" << format_number(mark.first) << " mm, "
       << format_number(mark.second) << " ms)'";
  gp << "\n";
  write_file(dir / "runtime_error.gp", gp.str());
  const std::string cmd = "cd '" + dir.string() + "' && gnuplot runtime_error.gp 2> gnuplot.log";
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("gnuplot failed; see " + (dir / "gnuplot.log").string());
  fs::rename(dir / "runtime_error.png.tmp", dir / "runtime_error.png");
}

void print_sample(long long seed, const Sample& s, const char* note) {
  std::printf("%6lld %10s %8g %8g %8d %8d %7d %8ld %9.2f %9.2f %10.3f %10.3f %10.3f %10.3f%s\n",
              seed, s.remesh.c_str(), s.edge_mm, s.step_ms, s.vertices, s.vertices_max, s.steps,
              s.newton, s.wall, s.cpu, 1e3 * s.error.rms, 1e3 * s.error.max,
              1e3 * s.error.hausdorff, 1e3 * s.error.rms_aligned, note);
  std::fflush(stdout);
}

/// A sweep run's result with the key (its scene and its reference's scene) it was made from.
void write_sample(const fs::path& path, const nlohmann::json& key, const Sample& s) {
  fs::create_directories(path.parent_path());
  const nlohmann::json j = {{"key", key},
                            {"remesh", s.remesh},
                            {"edge_mm", s.edge_mm},
                            {"step_ms", s.step_ms},
                            {"vertices", s.vertices},
                            {"vertices_max", s.vertices_max},
                            {"steps", s.steps},
                            {"newton_iterations", s.newton},
                            {"wall_seconds", s.wall},
                            {"cpu_seconds", s.cpu},
                            {"rms_error_m", s.error.rms},
                            {"max_error_m", s.error.max},
                            {"hausdorff_m", s.error.hausdorff},
                            {"rms_shape_error_m", s.error.rms_aligned},
                            {"max_shape_error_m", s.error.max_aligned}};
  write_file(path, j.dump(1) + "\n");
}

/// The result stored at `path` when it was made with `key`, else nothing.
std::optional<Sample> read_sample(const fs::path& path, const nlohmann::json& key) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("key") || j["key"] != key)
    return std::nullopt;
  try {
    Sample s;
    s.remesh = j.at("remesh").get<std::string>();
    s.edge_mm = j.at("edge_mm"), s.step_ms = j.at("step_ms");
    s.vertices = j.at("vertices"), s.vertices_max = j.at("vertices_max"), s.steps = j.at("steps");
    s.newton = j.at("newton_iterations");
    s.wall = j.at("wall_seconds"), s.cpu = j.at("cpu_seconds");
    s.error.rms = j.at("rms_error_m"), s.error.max = j.at("max_error_m"),
    s.error.hausdorff = j.at("hausdorff_m");
    s.error.rms_aligned = j.at("rms_shape_error_m"),
    s.error.max_aligned = j.at("max_shape_error_m");
    return s;
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;  // an older or damaged file: run again
  }
}

/// One draw: reference (cached), optional check of the reference at a finer edge, and the sweep.
SeedResult study_draw(const std::string& scenario, long long seed, const fs::path& dir,
                      const std::vector<double>& edges, const std::vector<double>& steps,
                      double ref_edge, double ref_step, double check_edge, double target,
                      const std::vector<RemeshSetting>& remeshes, double remesh_start,
                      const nlohmann::json& sets, const nlohmann::json& all_sets) {
  SeedResult d;
  d.seed = seed;
  const ps::Scene base =
      ps::apply_overrides(ps::make_scenario(scenario, seed), all_sets, "--set-all");
  const ps::Scene swept = ps::apply_overrides(base, sets, "--set");
  fs::create_directories(dir);
  const pv::SheetGeometry reference =
      reference_run(with_resolution(base, ref_edge, ref_step), dir, "reference", d.reference_wall);
  d.reference_vertices = static_cast<int>(reference.material.rows());
  std::printf("seed %lld reference: edge %g mm, step %g ms, %d vertices, %.1f s\n", seed, ref_edge,
              ref_step, d.reference_vertices, d.reference_wall);
  if (check_edge > 0) {
    double check_wall = 0;
    const pv::SheetGeometry check = reference_run(with_resolution(base, check_edge, ref_step), dir,
                                                  "reference_check", check_wall);
    d.checked = true;
    d.check = pv::compare_sheets(check, reference);
    d.converged = 1e3 * d.check.rms <= target;
    std::printf(
        "seed %lld reference check: edge %g mm (%ld vertices, %.1f s) against the reference: RMS "
        "%.3f mm, "
        "max %.3f mm, Hausdorff %.3f mm: %s\n",
        seed, check_edge, static_cast<long>(check.material.rows()), check_wall, 1e3 * d.check.rms,
        1e3 * d.check.max, 1e3 * d.check.hausdorff,
        d.converged ? "converged within the target" : "NOT converged within the target");
  }
  std::printf("%6s %10s %8s %8s %8s %8s %7s %8s %9s %9s %10s %10s %10s %10s\n", "seed", "remesh",
              "edge_mm", "step_ms", "vertices", "max_vert", "steps", "newton", "wall_s", "cpu_s",
              "rms_mm", "max_mm", "hausd_mm", "shape_mm");
  const nlohmann::json reference_key = ps::scene_to_json(with_resolution(base, ref_edge, ref_step));
  std::string sets_tag;
  if (!sets.empty()) {
    std::uint64_t h = 14695981039346656037ull;  // FNV-1a of the keys and values
    for (const char c : sets.dump()) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
    char hex[24];
    std::snprintf(hex, sizeof hex, "_set_%016llx", static_cast<unsigned long long>(h));
    sets_tag = hex;
  }
  const auto run_one = [&](const ps::Scene& scene, const std::string& remesh, double edge,
                           double step) {
    // A run already made from the same scene against the same reference (an interrupted study, or
    // another process on other seeds or settings) is read back, not run again.
    // Runs with --set keys are stored apart (named by a hash of the keys), so a study with them
    // and one without can share the folder and its references without replacing each other's runs.
    const fs::path cached = dir / "runs" /
                            ("remesh_" + remesh + "_edge_" + format_number(edge) + "_step_" +
                             format_number(step) + sets_tag + ".json");
    const nlohmann::json key = {{"scene", ps::scene_to_json(scene)}, {"reference", reference_key}};
    if (const auto s = read_sample(cached, key)) {
      d.samples.push_back(*s);
      print_sample(seed, *s, " (reused)");
      return;
    }
    const double cpu0 = cpu_seconds();
    const ps::RunResult r = ps::run_scene(
        scene, progress_options(
                   "seed " + std::to_string(seed) + ", " +
                   (remesh == "off" ? "edge " + format_number(edge) + " mm" : "remesh " + remesh) +
                   ", step " + format_number(step) + " ms"));
    Sample s;
    s.remesh = remesh;
    s.edge_mm = edge, s.step_ms = step;
    s.cpu = cpu_seconds() - cpu0;
    s.vertices = r.mesh.num_vertices();
    s.vertices_max = r.sheet.vertices_max;
    s.steps = r.steps;
    s.newton = r.totals.newton_iterations;
    s.wall = r.wall_seconds;
    s.error = pv::compare_sheets(reference, geometry_of(r.mesh, as_rows(r.state.positions)));
    d.samples.push_back(s);
    write_sample(cached, key, s);
    print_sample(seed, s, "");
  };
  for (double e : edges)
    for (double h : steps) run_one(with_resolution(swept, e, h), "off", e, h);
  for (const RemeshSetting& m : remeshes)
    for (double h : steps)
      run_one(with_remesh(with_resolution(swept, remesh_start, h), m, remesh_start), m.label(),
              remesh_start, h);
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_runtime_error: wall time against error for a sweep of edge length and time step"};
  std::string out, scenario = "pull", seeds_text = "0,1,2,3,4,5,6,7", edges_text = "20,14,10,7",
                   steps_text = "20,10,5";
  double ref_edge = 5, ref_step = 2.5, target = 2;
  app.add_option("--out", out, "output folder (CSV, plot, reference runs)")->required();
  app.add_option("--scenario", scenario, "scenario name")->capture_default_str();
  app.add_option("--seeds", seeds_text, "scenario seeds (draws), comma separated")
      ->capture_default_str();
  app.add_option(
         "--edges", edges_text,
         "edge lengths of the uniform sweep [mm], comma separated (may be empty with --remesh)")
      ->capture_default_str();
  app.add_option("--steps", steps_text, "time steps of the sweep [ms], comma separated")
      ->capture_default_str();
  app.add_option("--reference-edge", ref_edge, "edge length of the references [mm]")
      ->capture_default_str();
  app.add_option("--reference-step", ref_step, "time step of the references [ms]")
      ->capture_default_str();
  app.add_option("--target", target, "RMS error to recommend a setting for [mm]")
      ->capture_default_str();
  double check_edge = 0;
  app.add_option(
      "--check-edge", check_edge,
      "also run each draw at this finer edge length [mm] (reference step) and compare it with its "
      "reference: a draw whose reference moves by more than the target is not converged and is "
      "left "
      "out of the recommendation; when no draw is converged, no setting is recommended and the "
      "exit "
      "status is 1");
  std::string remesh_text;
  double remesh_start = 21;
  app.add_option("--remesh", remesh_text,
                 "remeshing settings of the sweep, comma separated MIN:MAX[:ANGLE][@EVERY] "
                 "(remesh.size_min and size_max in mm, refine_angle in rad, remesh.every in "
                 "steps; run at every --steps, from a uniform start mesh of --remesh-start)");
  app.add_option("--remesh-start", remesh_start,
                 "edge length of the remeshed runs' start mesh [mm]")
      ->capture_default_str()
      ->check(papersim::common::positive());
  std::string mark_text;
  app.add_option("--mark", mark_text,
                 "EDGE:STEP: circle this uniform setting on the plot as the old default (mm, ms)");
  std::vector<std::string> set_pairs;
  app.add_option(
      "--set", set_pairs,
      "KEY=VALUE: set a scene key of the sweep's runs, not of the references (dotted, e.g. "
      "solver.trust_region_cg=20 or remesh.aspect_min=0.5; the value is JSON); repeatable. The "
      "sweep's "
      "own keys (time_step, sheet.edge_length, remesh.enabled, size_min, size_max, refine_angle, "
      "every) "
      "are refused");
  std::vector<std::string> all_pairs;
  app.add_option(
      "--set-all", all_pairs,
      "KEY=VALUE: set a scene key of every run, the references and their checks too (another "
      "physics, e.g. sheet.material.stretch_stiffness=5000: use a new OUT, as the references "
      "of another scene replace those in it); repeatable, the same keys refused as for --set");
  bool replot = false;
  app.add_flag("--replot", replot,
               "only redraw OUT/runtime_error.png from OUT/runtime_error_summary.csv");
  CLI11_PARSE(app, argc, argv);
  try {
    const std::vector<RemeshSetting> remeshes = parse_remesh(remesh_text);
    // With remeshing settings the uniform sweep may be empty (--edges "").
    const std::vector<double> edges = edges_text.empty() && !remeshes.empty()
                                          ? std::vector<double>{}
                                          : parse_list(edges_text, "edges");
    const std::vector<double> steps = parse_list(steps_text, "steps");
    std::pair<double, double> mark{0, 0};
    if (!mark_text.empty()) {
      const size_t colon = mark_text.find(':');
      const std::vector<double> e = parse_list(mark_text.substr(0, colon), "mark");
      const std::vector<double> h = colon == std::string::npos
                                        ? std::vector<double>{}
                                        : parse_list(mark_text.substr(colon + 1), "mark");
      if (e.size() != 1 || h.size() != 1)
        throw std::runtime_error("--mark: '" + mark_text +
                                 "' is not EDGE:STEP (mm and ms, e.g. 10:2)");
      mark = {e[0], h[0]};
    }
    std::vector<long long> seeds;
    for (double x : parse_list(seeds_text, "seeds", true))
      seeds.push_back(static_cast<long long>(x));
    // The plot's title names the draws it summarises (those whose reference holds).
    const auto title = [&](const std::string& used) {
      return scenario + ", seeds " + used + ": references edge " + format_number(ref_edge) +
             " mm, step " + format_number(ref_step) + " ms";
    };
    if (replot) {
      const fs::path summary = fs::path(out) / "runtime_error_summary.csv";
      std::ifstream in(summary);
      std::string header, row;
      if (!in || !std::getline(in, header) || !std::getline(in, row) ||
          row.rfind(',') == std::string::npos)
        throw std::runtime_error("--replot: no summary rows in " + summary.string());
      // The draws used: column "seeds" of the summary (the 11th).
      std::stringstream fields(row);
      std::string used;
      for (int k = 0; k < 11 && std::getline(fields, used, ','); ++k) {
      }
      write_plot(out, steps, title(used), mark);
      std::printf("wrote %s/runtime_error.png\n", out.c_str());
      return 0;
    }
    if (check_edge != 0 && !(check_edge > 0 && check_edge < ref_edge))
      throw std::runtime_error("--check-edge: " + format_number(check_edge) +
                               " mm is not a positive edge length finer than --reference-edge (" +
                               format_number(ref_edge) + " mm)");
    const nlohmann::json sets = ps::parse_overrides(set_pairs);
    const nlohmann::json all_sets = ps::parse_overrides(all_pairs);
    for (const auto& [option, keys] :
         {std::pair{"--set", &sets}, std::pair{"--set-all", &all_sets}})
      for (const auto& [key, value] : keys->items())
        if (key == "time_step" || key == "sheet.edge_length" || key == "remesh" ||
            key == "remesh.enabled" || key == "remesh.size_min" || key == "remesh.size_max" ||
            key == "remesh.refine_angle" || key == "remesh.every")
          throw std::runtime_error(std::string(option) + ": '" + key +
                                   "' is set by the sweep (--edges, --steps, --remesh)");
    // An unknown scenario or a bad --set / --set-all key fails here, before any run.
    ps::apply_overrides(
        ps::apply_overrides(ps::make_scenario(scenario, seeds.front()), all_sets, "--set-all"),
        sets, "--set");
    if (!sets.empty())
      std::printf("the sweep's runs with --set %s (not the references)\n", sets.dump().c_str());
    if (!all_sets.empty())
      std::printf("every run and reference with --set-all %s\n", all_sets.dump().c_str());
    fs::create_directories(out);
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<SeedResult> draws;
    for (long long seed : seeds) {
      draws.push_back(study_draw(scenario, seed, fs::path(out) / ("seed_" + std::to_string(seed)),
                                 edges, steps, ref_edge, ref_step, check_edge, target, remeshes,
                                 remesh_start, sets, all_sets));
      write_csv(fs::path(out) / "runtime_error.csv",
                draws);  // partial results survive an interruption
    }
    const std::vector<Aggregate> settings = aggregate(draws);
    const int held = static_cast<int>(
        std::count_if(draws.begin(), draws.end(), [](const SeedResult& d) { return d.converged; }));
    if (check_edge > 0)
      std::printf("\n%d of %zu draws have a reference that holds under refinement", held,
                  draws.size());
    else
      std::printf("\n%zu draws, their references not checked under refinement (no --check-edge)",
                  draws.size());
    for (const SeedResult& d : draws)
      if (!d.converged)
        std::printf("%s seed %lld left out", held < static_cast<int>(draws.size()) ? ";" : "",
                    d.seed);
    std::printf("\n");
    if (settings.empty()) {  // no summary: an older one in OUT must not stand in for it
      fs::remove(fs::path(out) / "runtime_error_summary.csv");
      fs::remove(fs::path(out) / "runtime_error.png");
    } else {
      write_summary_csv(fs::path(out) / "runtime_error_summary.csv", settings);
      write_plot(out, steps, title(settings.front().seeds), mark);
      std::printf("%10s %8s %8s %6s %14s %13s %9s %14s %13s %13s %16s %15s\n", "remesh", "edge_mm",
                  "step_ms", "draws", "median_wall_s", "median_cpu_s", "max_vert", "median_rms_mm",
                  "worst_rms_mm", "worst_max_mm", "median_shape_mm", "worst_shape_mm");
      for (const Aggregate& a : settings)
        std::printf("%10s %8g %8g %6d %14.2f %13.2f %9.0f %14.3f %13.3f %13.3f %16.3f %15.3f\n",
                    a.remesh.c_str(), a.edge_mm, a.step_ms, a.draws, a.median_wall, a.median_cpu,
                    a.median_vertices_max, 1e3 * a.median_rms, 1e3 * a.worst_rms, 1e3 * a.worst_max,
                    1e3 * a.median_rms_aligned, 1e3 * a.worst_rms_aligned);
      std::printf(
          "\nPareto front (no other setting is both faster and more accurate, worst RMS over the "
          "draws):\n");
      for (const Aggregate& a : settings) {
        const bool beaten = std::any_of(settings.begin(), settings.end(), [&](const Aggregate& o) {
          return o.median_cpu < a.median_cpu && o.worst_rms < a.worst_rms;
        });
        if (!beaten)
          std::printf("  %s, step %g ms: CPU %.2f s, worst RMS %.3f mm, worst max %.3f mm\n",
                      describe(a).c_str(), a.step_ms, a.median_cpu, 1e3 * a.worst_rms,
                      1e3 * a.worst_max);
      }
    }
    const Aggregate* best = nullptr;
    for (const Aggregate& a : settings)
      if (1e3 * a.worst_rms <= target && (!best || a.median_cpu < best->median_cpu)) best = &a;
    std::vector<double> ref_walls;
    for (const SeedResult& d : draws)
      if (d.converged) ref_walls.push_back(d.reference_wall);
    if (best)
      std::printf(
          "cheapest setting with RMS error <= %g mm on every draw: %s, step %g ms (median CPU %.2f "
          "s, wall "
          "%.2f s, worst RMS %.3f mm, worst max %.3f mm; %.1fx less wall time than the references' "
          "median)\n",
          target, describe(*best).c_str(), best->step_ms, best->median_cpu, best->median_wall,
          1e3 * best->worst_rms, 1e3 * best->worst_max, median(ref_walls) / best->median_wall);
    else if (held > 0)
      std::printf("no setting of the sweep reaches RMS error <= %g mm on every draw\n", target);
    else
      std::printf(
          "no setting recommended: every draw's reference moves by more than %g mm RMS under "
          "refinement\n",
          target);
    std::printf("wrote %s/runtime_error.csv%s (%.1f s in all)\n", out.c_str(),
                settings.empty() ? "" : ", runtime_error_summary.csv and runtime_error.png",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (held == 0) return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_runtime_error: %s\n", e.what());
    return 1;
  }
  return 0;
}
