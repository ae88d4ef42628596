// Crumple-and-unfold cycles (Gottesman, Andrejevic, Rycroft, Rubinstein 2018): the crumple
// scenario's sheet is crumpled in the shrinking cavity, released, opened by its corners and edges
// and laid on the ground, then crumpled again, K times; after each cycle the plastic crease
// network of the opened sheet is measured. Gottesman et al. find the total crease length growing
// like the logarithm of the number of cycles; Andresen et al. (2007) find ridge lengths log-normal.
//
// One cycle:
//  1. crumple: the scenario's cavity (held until 1 s, then shrunk to --end-radius at 5 s) around
//     the sheet, both scaled by --scale (a smaller sheet folds on fewer, finer edges at the same
//     yield curvature); cycle 1 is the scenario's draw itself, later cycles start from the
//     opened sheet of the cycle before, turned upright by the scenario's pose about its centre and
//     centred in the cavity, whose radius is enlarged when the sheet does not fit;
//  2. open: no cavity, the ground at z = 0; the crumpled sheet, moved so its lowest point is
//     --lift above the ground, is pulled by handles at its corners and edge midpoints
//     (--open-points 8; 4: corners only; soft springs, so a tangle meets a spring and not a hard
//     limit) to --spread times the flat sheet's positions of those points at --lift, in the
//     orientation (face up or down) closest to the ball's, in 2/3 of --open-time; then they
//     hold it there (or with --lay-down lower it to 1 mm above the ground) and let go at
//     --open-time, and it settles on the ground until --open-time + --settle;
//  3. with --press GAP, press: a plate (a plane, solid above) comes down from 3 mm above the
//     opened sheet to GAP above the ground in --press-time, holds 0.25 s, rises in 0.25 s,
//     and the sheet settles for --settle, as crumpled paper is flattened by hand or between
//     two plates before the next cycle (Gottesman et al.).
// Each phase is a run of its own scene whose sheet is the previous phase's state read back from
// its PLY (plastic state and damage included, velocities zero): DIR/cycle_K_crumpled.ply and
// DIR/cycle_K_open.ply (and DIR/cycle_K_pressed.ply). DIR/cycles.csv has one line per phase
// (rewritten after each).
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "collision/collider_factory.hpp"
#include "common/atomic_file.hpp"
#include "common/cli_checks.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/run.hpp"
#include "simulation/scenario.hpp"
#include "validation/metrics.hpp"

namespace ps = papersim::simulation;
namespace pv = papersim::validation;
namespace fs = std::filesystem;

namespace {

struct Options {
  int seed = 0;
  int cycles = 5;
  double edge = 0.0;        ///< [m]; 0: the scenario's
  double time_step = 0.0;   ///< [s]; 0: the scenario's
  double scale = 1.0;       ///< sheet size and cavity radii as a fraction of the scenario's
  double end_radius = 0.0;  ///< cavity radius at the end of each crumple [m]; 0: scale x 0.05
  int max_iterations = 0;   ///< Newton iterations per step; 0: the scenario's 200
  double strain_limit = 0;  ///< largest principal strain; 0: the scenario's
  int open_points = 8;      ///< handles that open the sheet: 4 (corners) or 8 (and edge midpoints)
  double spread = 0.8;      ///< handle targets as a fraction of the flat sheet's positions
  double lift = 0.02;       ///< height of the opened sheet's corners above the ground [m]
  double open_time = 1.5;   ///< handles pull until 2/3 of this and release at it [s]
  bool lay_down = false;    ///< lower the held points to the ground before the release
  double settle = 1.0;      ///< time on the ground after the release [s]
  double press = 0.0;       ///< gap under the pressing plate [m]; 0: no pressing
  double press_time = 1.0;  ///< the plate's way down [s]
  double press_friction = 0;     ///< Coulomb coefficient between the plate and the sheet [-]
  double press_stiffness = 1e4;  ///< contact and self-contact barrier pressure while pressing [Pa]
  double crease_angle = 30;      ///< [deg]
  double report = 0.5;           ///< simulated time between progress lines [s]
  std::string open_only;         ///< a crumpled sheet (PLY) to open, instead of the cycles
  std::string press_only;        ///< an opened sheet (PLY) to press, instead of the cycles
  std::string out;
};

/// One line of DIR/cycles.csv and of the summary.
struct PhaseFigures {
  int cycle = 0;
  std::string phase;
  double wall = 0, sim_time = 0;
  int vertices = 0, newton = 0, halved = 0, self_intersections = 0;
  double max_stretch = 0, min_gap = 0;
  pv::CreaseMetrics creases;
  double plastic_integral = 0;  ///< integral of the largest |principal plastic curvature| [m]
  double height = 0;            ///< highest minus lowest point at the end [m]
  double lowest_top = 0;        ///< lowest the highest point came during the phase [m]
};

/// Integral over the sheet (material area) of the largest absolute principal plastic curvature:
/// for a crease of rest angle theta along a line of length L it is theta L, whatever the mesh.
double plastic_integral(const papersim::remesh::SheetMesh& mesh) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const Eigen::MatrixX3d k = mesh.plastic_curvature();
  double sum = 0;
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector2d a = X.row(F(f, 1)) - X.row(F(f, 0)), b = X.row(F(f, 2)) - X.row(F(f, 0));
    const double area = 0.5 * std::abs(a.x() * b.y() - a.y() * b.x());
    const double mean = 0.5 * (k(f, 0) + k(f, 1));
    const double r = std::hypot(0.5 * (k(f, 0) - k(f, 1)), k(f, 2));
    sum += area * std::max(std::abs(mean + r), std::abs(mean - r));
  }
  return sum;
}

/// Runs `scene` to its end with progress lines; returns its figures and leaves the final state
/// in `mesh` / `positions`.
PhaseFigures run_phase(const ps::Scene& scene, int cycle, const std::string& phase,
                       const Options& o, papersim::remesh::SheetMesh& mesh,
                       Eigen::MatrixX3d& positions) {
  const auto start = std::chrono::steady_clock::now();
  const auto wall = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  ps::Run run(scene);
  double next = o.report, lowest_top = INFINITY;
  while (!run.finished()) {
    run.step();
    lowest_top = std::min(lowest_top, run.state().positions_matrix().col(2).maxCoeff());
    if (run.state().time + 1e-9 < next || run.finished()) continue;
    next += o.report;
    const double w = wall(), t = run.state().time;
    std::printf(
        "  cycle %d %-8s t %6.3f / %.3f s  wall %7.1f s  ETA %7.1f s  Newton %d  stretch %.5f\n",
        cycle, phase.c_str(), t, scene.duration, w, w * (scene.duration - t) / t,
        run.result(w).totals.newton_iterations, run.step_stretch());
    std::fflush(stdout);
  }
  const ps::RunResult r = run.result(wall());
  PhaseFigures p;
  p.cycle = cycle;
  p.phase = phase;
  p.wall = r.wall_seconds;
  p.sim_time = run.state().time;
  p.vertices = r.sheet.vertices;
  p.newton = r.totals.newton_iterations;
  p.halved = r.totals.failed_solves;
  p.self_intersections = r.quality.self_intersections;
  p.max_stretch = r.quality.max_principal_stretch;
  p.min_gap = INFINITY;
  for (double g : r.quality.min_obstacle_distance) p.min_gap = std::min(p.min_gap, g);
  mesh = run.mesh();
  positions = run.state().positions_matrix();
  pv::MetricsOptions mo;
  mo.crease_angle_deg = o.crease_angle;
  mo.self_intersections = false;  // counted by the run
  p.creases = pv::compute_metrics(mesh.material_coords(), positions, mesh.faces(),
                                  mesh.plastic_curvature(), mo)
                  .creases;
  p.plastic_integral = plastic_integral(mesh);
  p.height = positions.col(2).maxCoeff() - positions.col(2).minCoeff();
  p.lowest_top = lowest_top;
  return p;
}

std::string save(const std::string& dir, const std::string& name,
                 const papersim::remesh::SheetMesh& mesh, const Eigen::MatrixX3d& x,
                 const ps::Scene& scene) {
  std::string path = (fs::path(dir) / name).string();
  papersim::remesh::write_sheet_file(path, mesh, x, Eigen::MatrixX3d::Zero(x.rows(), 3),
                                     scene.sheet.width, scene.sheet.height);
  return path;
}

/// The crumple of cycle `k` (1-based): the scenario's scene; from cycle 2 on its sheet is the
/// opened sheet `flat_path` (positions `x`), turned by the scenario's pose about its centroid
/// into the cavity's centre; the cavity grows to hold it with a 10 mm margin when needed.
ps::Scene crumple_scene(const Options& o, int k, const std::string& flat_path,
                        const papersim::remesh::SheetMesh& mesh, const Eigen::MatrixX3d& x) {
  ps::Scene s = ps::make_scenario("crumple", static_cast<std::uint64_t>(o.seed));
  if (o.edge > 0) s.sheet.edge_length = o.edge;
  if (o.time_step > 0) s.time_step = o.time_step;
  if (o.max_iterations > 0) s.newton.max_iterations = o.max_iterations;
  if (o.strain_limit > 0) s.sheet.material.strain_limit = o.strain_limit;
  auto& cavity = s.obstacles.at(0);
  const Eigen::Vector3d centre = cavity.keyframes.front().translation;
  s.sheet.width *= o.scale;
  s.sheet.height *= o.scale;
  s.sheet.position = centre + o.scale * (s.sheet.position - centre);
  double radius = o.scale * cavity.radius;
  const double end_radius = o.end_radius > 0 ? o.end_radius : o.scale * 0.05;
  const double t_hold = 1.0, t_end = s.duration;
  if (k > 1) {
    // Turn the opened sheet (lying on the ground) as the scenario turns the flat sheet.
    const Eigen::Vector3d c = x.colwise().mean().transpose();
    const Eigen::Matrix3d R = ps::sheet_rotation(s.sheet.rotation_deg);
    Eigen::MatrixX3d y(x.rows(), 3);
    double reach = 0;
    for (int v = 0; v < x.rows(); ++v) {
      y.row(v) = (R * (x.row(v).transpose() - c) + centre).transpose();
      reach = std::max(reach, (y.row(v).transpose() - centre).norm());
    }
    radius = std::max(radius, reach + 0.01);
    const std::string turned = fs::path(flat_path).replace_extension(".upright.ply").string();
    papersim::remesh::write_sheet_file(turned, mesh, y, Eigen::MatrixX3d::Zero(y.rows(), 3),
                                       s.sheet.width, s.sheet.height);
    s.sheet.mesh_path = turned;
  }
  cavity = papersim::collision::shrinking_cavity(centre, radius, t_hold, t_end, end_radius / radius,
                                                 cavity.friction);
  return s;
}

/// A scene on the ground (friction 0.3) with the crumple's sheet, contact and solver settings
/// and nothing else.
ps::Scene ground_scene(const ps::Scene& crumple, const std::string& name) {
  ps::Scene s;
  s.name = name;
  s.gravity = crumple.gravity;
  s.time_step = crumple.time_step;
  s.sheet = crumple.sheet;
  s.ground = true;
  s.ground_friction = 0.3;
  s.contact = crumple.contact;
  s.self_contact = crumple.self_contact;
  s.newton = crumple.newton;
  return s;
}

/// The opening of a crumpled sheet (`crumpled_path`, positions `x`) on the ground.
ps::Scene open_scene(const Options& o, const ps::Scene& crumple, const std::string& crumpled_path,
                     const Eigen::MatrixX3d& x, const papersim::remesh::SheetMesh& mesh) {
  ps::Scene s = ground_scene(crumple, "crumple-open");
  s.duration = o.open_time + o.settle;
  // Lowest point to --lift above the ground, centre over the origin.
  const Eigen::Vector3d c = x.colwise().mean().transpose();
  const Eigen::Vector3d shift(-c.x(), -c.y(), o.lift - x.col(2).minCoeff());
  Eigen::MatrixX3d y = x.rowwise() + shift.transpose();
  const std::string lowered =
      (fs::path(o.out) / fs::path(crumpled_path).stem()).string() + ".lowered.ply";
  papersim::remesh::write_sheet_file(lowered, mesh, y, Eigen::MatrixX3d::Zero(y.rows(), 3),
                                     s.sheet.width, s.sheet.height);
  s.sheet.mesh_path = lowered;
  // The handles' material points: the corners, and with --open-points 8 the edges' midpoints.
  const double w = s.sheet.width, h = s.sheet.height;
  std::vector<Eigen::Vector2d> points = {{0, 0}, {w, 0}, {w, h}, {0, h}};
  if (o.open_points == 8)
    for (const Eigen::Vector2d& m : {Eigen::Vector2d(0.5 * w, 0), Eigen::Vector2d(w, 0.5 * h),
                                     Eigen::Vector2d(0.5 * w, h), Eigen::Vector2d(0, 0.5 * h)})
      points.push_back(m);
  const ps::InitialPlacement placement(mesh, ps::flatten(y));
  std::vector<Eigen::Vector3d> at;
  for (const auto& m : points) at.push_back(placement(m));
  // The orientation of the ball's material axes (from the corners), projected to the horizontal.
  Eigen::Vector3d ax = (at[1] - at[0]) + (at[2] - at[3]), ay = (at[3] - at[0]) + (at[2] - at[1]);
  ax.z() = 0;
  if (ax.norm() < 1e-9) ax = Eigen::Vector3d::UnitX();
  ax.normalize();
  Eigen::Vector3d by = Eigen::Vector3d::UnitZ().cross(ax);
  if (by.dot(ay) < 0) by = -by;  // face down: (ax, by, -z) is right-handed
  // Pull out at --lift until 2/3 of the opening time, then hold, or with --lay-down lower the held
  // points to 1 mm above the ground by 0.9 of it, so the sheet is laid down instead of dropped.
  const double t_pull = o.open_time * 2.0 / 3.0, t_lower = 0.9 * o.open_time;
  for (std::size_t i = 0; i < points.size(); ++i) {
    ps::HandleSpec hs;
    hs.material_point = points[i];
    hs.stiffness = 100.0;  // N/m: lags ~0.5 mm under the sheet's weight, yields to a tangle
    hs.release_time = o.open_time;
    const Eigen::Vector3d target =
        o.spread * ((points[i].x() - 0.5 * w) * ax + (points[i].y() - 0.5 * h) * by) +
        Eigen::Vector3d(0, 0, o.lift);
    hs.keyframes = {{0.0, Eigen::Vector3d::Zero()}, {t_pull, target - at[i]}};
    if (o.lay_down)
      hs.keyframes.push_back({t_lower, target - at[i] - Eigen::Vector3d(0, 0, o.lift - 1e-3)});
    s.handles.push_back(hs);
  }
  return s;
}

/// The pressing of an opened sheet (`open_path`, positions `x`) on the ground: a plate (the plane
/// turned over, solid above) from 3 mm above the sheet's highest point (or above --press) down
/// to --press above the ground in --press-time, held 0.25 s, raised in 0.25 s to 50 mm above
/// its start, out of the sheet's reach; then --settle.
ps::Scene press_scene(const Options& o, const ps::Scene& crumple, const std::string& open_path,
                      const Eigen::MatrixX3d& x) {
  ps::Scene s = ground_scene(crumple, "crumple-press");
  s.sheet.mesh_path = open_path;
  // The crumple's soft barriers (400 Pa) let pressed layers close to micrometre gaps, where the
  // self-contact's collision detection cuts every Newton step short and the press stalls.
  s.contact.stiffness = o.press_stiffness;
  s.self_contact.stiffness = o.press_stiffness;
  const double top = std::max(x.col(2).maxCoeff(), o.press) + 3e-3;
  const double t_down = o.press_time, t_up = t_down + 0.5;
  s.duration = t_up + o.settle;
  papersim::collision::ColliderSpec plate;
  plate.kind = papersim::collision::ColliderKind::plane;
  plate.friction = o.press_friction;
  papersim::collision::Keyframe k;
  k.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  for (const auto& [t, z] :
       {std::pair{0.0, top}, {t_down, o.press}, {t_down + 0.25, o.press}, {t_up, top + 0.05}}) {
    k.time = t;
    k.translation = Eigen::Vector3d(0, 0, z);
    plate.keyframes.push_back(k);
  }
  s.obstacles = {plate};
  return s;
}

void print_figures(const PhaseFigures& p) {
  const auto& c = p.creases;
  std::printf(
      "cycle %d %s: wall %.1f s, %d vertices, %d Newton, %d halved, %d intersecting pairs, max "
      "stretch %.5f, "
      "min gap %.2e m, height %.1f mm (top at least %.1f mm)\n",
      p.cycle, p.phase.c_str(), p.wall, p.vertices, p.newton, p.halved, p.self_intersections,
      p.max_stretch, p.min_gap, 1e3 * p.height, 1e3 * p.lowest_top);
  std::printf(
      "  creases (> %.0f deg): %d lines, %.4f m; plastic network: %d lines, %.4f m (mu %.3f sigma "
      "%.3f KS %.3f); "
      "plastic curvature integral %.4f m\n",
      c.threshold_deg, c.lines, c.total_length, c.plastic_network_lines, c.plastic_network_length,
      c.plastic_network_log_length_mean, c.plastic_network_log_length_std,
      c.plastic_network_log_normal_ks, p.plastic_integral);
  std::fflush(stdout);
}

/// Least-squares y = a + b ln(k) over k = 1..n; returns (a, b, R^2).
Eigen::Vector3d log_fit(const std::vector<double>& y) {
  const int n = static_cast<int>(y.size());
  Eigen::MatrixX2d A(n, 2);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    A(i, 0) = 1;
    A(i, 1) = std::log(i + 1.0);
    b(i) = y[static_cast<std::size_t>(i)];
  }
  const Eigen::Vector2d p = A.colPivHouseholderQr().solve(b);
  const double mean = b.mean();
  const double ss_res = (A * p - b).squaredNorm(), ss_tot = (b.array() - mean).square().sum();
  return {p(0), p(1), ss_tot > 0 ? 1 - ss_res / ss_tot : 1.0};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_crumple_cycles: crumple, open and lay down the crumple scenario's sheet K times; "
      "the "
      "plastic crease network after each cycle"};
  Options o;
  app.add_option("--seed", o.seed, "scenario seed")->check(papersim::common::non_negative());
  app.add_option("--cycles", o.cycles, "number of crumple-and-open cycles")
      ->check(CLI::Range(1, 50));
  app.add_option("--edge", o.edge, "edge length [m] (0: the scenario's 10 mm)")
      ->check(CLI::Range(0.0, 0.05));
  app.add_option("--time-step", o.time_step, "time step [s] (0: the scenario's 2 ms)")
      ->check(CLI::Range(0.0, 0.01));
  app.add_option("--scale", o.scale,
                 "sheet size and cavity radii as a fraction of the scenario's (A4, 0.2 -> 0.05 m)")
      ->check(CLI::Range(0.1, 1.0));
  app.add_option("--end-radius", o.end_radius,
                 "cavity radius at the end of each crumple [m] (0: 0.05 x --scale)")
      ->check(CLI::Range(0.0, 0.2));
  app.add_option("--max-iterations", o.max_iterations,
                 "Newton iterations per step (0: the scenario's 200)")
      ->check(CLI::Range(0, 10000));
  app.add_option("--strain-limit", o.strain_limit,
                 "largest principal strain of the sheet (0: the scenario's 0.005)")
      ->check(CLI::Range(0.0, 0.1));
  app.add_option("--open-points", o.open_points,
                 "handles that open the sheet: 4 (its corners) or 8 (and its edges' "
                 "midpoints)")
      ->check(CLI::IsMember({4, 8}));
  app.add_option("--spread", o.spread,
                 "opened handles' targets as a fraction of the flat sheet's positions")
      ->check(CLI::Range(0.3, 0.95));
  app.add_option("--lift", o.lift,
                 "height of the opened corners (and of the ball's lowest point) [m]")
      ->check(CLI::Range(0.002, 0.2));
  app.add_option("--open-time", o.open_time,
                 "the handles pull for 2/3 of it, hold the sheet (or lower it: "
                 "--lay-down), then let go [s]")
      ->check(CLI::Range(0.1, 10.0));
  app.add_flag("--lay-down", o.lay_down,
               "lower the held sheet to 1 mm above the ground before letting go (default: "
               "let go at --lift)");
  app.add_option("--settle", o.settle,
                 "time on the ground after the release (and after the press) [s]")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--press", o.press,
                 "after each opening, press the sheet flat under a plate down to this gap above "
                 "the ground [m] (0: no pressing)")
      ->check(CLI::Range(0.0, 0.05));
  app.add_option("--press-time", o.press_time, "the plate's way down [s]")
      ->check(CLI::Range(0.05, 10.0));
  app.add_option("--press-friction", o.press_friction,
                 "friction coefficient between the plate and the sheet")
      ->check(CLI::Range(0.0, 5.0));
  app.add_option("--press-stiffness", o.press_stiffness,
                 "contact and self-contact barrier pressure while pressing "
                 "[Pa] (the crumple's is 400)")
      ->check(CLI::Range(1.0, 1e7));
  app.add_option("--crease-angle", o.crease_angle, "crease threshold [deg]")
      ->check(CLI::Range(0.1, 179.0));
  app.add_option("--report", o.report, "simulated time between progress lines [s]")
      ->check(CLI::Range(1e-3, 100.0));
  app.add_option(
         "--open-only", o.open_only,
         "only open (and with --press press) this crumpled sheet (a cycle_K_crumpled.ply) into "
         "DIR/open.ply (and DIR/pressed.ply)")
      ->check(CLI::ExistingFile);
  app.add_option("--press-only", o.press_only,
                 "only press this opened sheet (a cycle_K_open.ply) into DIR/pressed.ply "
                 "(needs --press)")
      ->check(CLI::ExistingFile)
      ->excludes("--open-only");
  app.add_option("--out", o.out, "folder for each phase's sheet (PLY) and cycles.csv")->required();
  CLI11_PARSE(app, argc, argv);
  if (!o.press_only.empty() && o.press <= 0) {
    std::fprintf(stderr, "papersim_crumple_cycles: --press-only needs --press GAP\n");
    return 2;
  }
  try {
    fs::create_directories(o.out);
    std::vector<PhaseFigures> all;
    std::vector<double> plastic_length, plastic_integral_open;
    papersim::remesh::SheetMesh mesh;
    Eigen::MatrixX3d x;
    std::string flat_path;
    bool pass = true;
    const auto check = [&](const PhaseFigures& p, const ps::Scene& s) {
      const bool ok = p.self_intersections == 0 && p.min_gap > 0 && x.allFinite() &&
                      p.max_stretch <= 1 + s.sheet.material.strain_limit;
      if (!ok) std::printf("  FAIL cycle %d %s\n", p.cycle, p.phase.c_str());
      pass = pass && ok;
    };
    // DIR/cycles.csv, rewritten after every phase so a run stopped early leaves its figures.
    const auto write_csv = [&] {
      std::string csv =
          "cycle,phase,wall_s,sim_time_s,vertices,newton,halved,self_intersections,max_stretch,min_"
          "gap_m,crease_lines,"
          "crease_length_m,plastic_lines,plastic_length_m,plastic_log_mu,plastic_log_sigma,plastic_"
          "ks,"
          "plastic_curvature_integral_m,height_m,lowest_top_m\n";
      for (const auto& p : all) {
        char line[640];
        const auto& c = p.creases;
        std::snprintf(
            line, sizeof line,
            "%d,%s,%.2f,%.4f,%d,%d,%d,%d,%.6f,%.4e,%d,%.5f,%d,%.5f,%.4f,%.4f,%.4f,%.5f,%.5f,%.5f\n",
            p.cycle, p.phase.c_str(), p.wall, p.sim_time, p.vertices, p.newton, p.halved,
            p.self_intersections, p.max_stretch, p.min_gap, c.lines, c.total_length,
            c.plastic_network_lines, c.plastic_network_length, c.plastic_network_log_length_mean,
            c.plastic_network_log_length_std, c.plastic_network_log_normal_ks, p.plastic_integral,
            p.height, p.lowest_top);
        csv += line;
      }
      papersim::common::write_text_atomically(fs::path(o.out) / "cycles.csv", csv);
    };
    // Runs one phase, writes its sheet to DIR/`file` and its line of DIR/cycles.csv; returns
    // the sheet's path.
    const auto phase = [&](const ps::Scene& scene, int k, const std::string& name,
                           const std::string& file) {
      const PhaseFigures p = run_phase(scene, k, name, o, mesh, x);
      std::string written = save(o.out, file, mesh, x, scene);
      print_figures(p);
      check(p, scene);
      all.push_back(p);
      write_csv();
      return written;
    };
    if (!o.open_only.empty() || !o.press_only.empty()) {
      const std::string& path = o.open_only.empty() ? o.press_only : o.open_only;
      const std::string option = o.open_only.empty() ? "--press-only " : "--open-only ";
      const papersim::remesh::SheetData d = papersim::remesh::read_sheet(path);
      mesh = d.mesh;
      x = d.positions;
      const ps::Scene crumple = crumple_scene(o, 1, "", mesh, x);
      if (std::abs(d.width - crumple.sheet.width) > 1e-9 ||
          std::abs(d.height - crumple.sheet.height) > 1e-9)
        throw std::runtime_error(option + path + ": the sheet is " + std::to_string(d.width) +
                                 " x " + std::to_string(d.height) + " m, --scale gives " +
                                 std::to_string(crumple.sheet.width) + " x " +
                                 std::to_string(crumple.sheet.height) + " m");
      std::string open_path = path;
      if (!o.open_only.empty())
        open_path = phase(open_scene(o, crumple, o.open_only, x, mesh), 1, "open", "open.ply");
      if (o.press > 0) phase(press_scene(o, crumple, open_path, x), 1, "press", "pressed.ply");
      o.cycles = 0;
    }
    for (int k = 1; k <= o.cycles; ++k) {
      const std::string cycle = "cycle_" + std::to_string(k);
      const ps::Scene crumple = crumple_scene(o, k, flat_path, mesh, x);
      const std::string crumpled_path = phase(crumple, k, "crumple", cycle + "_crumpled.ply");
      flat_path =
          phase(open_scene(o, crumple, crumpled_path, x, mesh), k, "open", cycle + "_open.ply");
      if (o.press > 0)
        flat_path =
            phase(press_scene(o, crumple, flat_path, x), k, "press", cycle + "_pressed.ply");
      const PhaseFigures& po = all.back();
      plastic_length.push_back(po.creases.plastic_network_length);
      plastic_integral_open.push_back(po.plastic_integral);
    }
    if (o.cycles >= 2 && o.open_only.empty()) {
      const Eigen::Vector3d a = log_fit(plastic_length), b = log_fit(plastic_integral_open);
      std::printf(
          "plastic network length after cycle k = a + b ln k: a %.4f m, b %.4f m, R^2 %.3f\n", a(0),
          a(1), a(2));
      std::printf(
          "plastic curvature integral after cycle k = a + b ln k: a %.4f m, b %.4f m, R^2 %.3f\n",
          b(0), b(1), b(2));
    }
    std::printf("%s\n", pass
                            ? "PASS: no penetration, no self-intersection, stretch within the limit"
                            : "FAIL (lines above)");
    return pass ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_crumple_cycles: %s\n", e.what());
    return 2;
  }
}
