// Stability stress suite (VALIDATION.md section 8; issue 5 item 2): scenes at the edges of what
// the simulator must survive, each run through the product's run_scene, with the same checks on
// every case:
//   nan        every position finite at every step;
//   vertices   no sheet vertex at a negative signed distance from any obstacle, at any step;
//   faces      no obstacle point inside a sheet triangle (minimum of each obstacle's field over
//              every triangle within 1 mm, at every step; for non-planar obstacles only: over
//              a plane the minimum is at a vertex);
//   strain     largest principal stretch <= 1 + strain limit at every step;
//   self       zero intersecting triangle pairs at the end (exact predicates);
//   energy     the mechanical energy (kinetic + gravity + stretching + bending) never exceeds
//              its value after the first step by more than 0.1% of the energy scale m |g| (z0 + L)
//              of the case: the scenes have no driven handles or moving obstacles (or are measured
//              only once these hold still), so nothing does work on the sheet, contact and friction
//              only take energy out, and backward Euler dissipates; the tolerance covers the Newton
//              stopping test (at 1e-4 m/s the energy error per step is far below it).
// With --remesh every case remeshes (remesh.size_min half the case's edge, size_max four times
// it): the face check follows the changing mesh, every kept pass was checked exactly by the run
// for self-intersection and stretch (a pass that fails is undone and counted), and the energy
// check measures what the steps changed (the signed jumps across the kept passes taken out;
// the largest jump is reported beside it, relative to the energy scale). --refuse-thin-splits
// turns remesh.refuse_thin_splits on as well.
// A case that cannot run yet is listed as not run, with the reason (none today).
// Exit status 1 when a case fails.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "collision/collider_factory.hpp"
#include "collision/self_intersection.hpp"
#include "collision/triangle_sdf.hpp"
#include "remesh/sheet_generator.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/simulate.hpp"
#include "validation/fold_scene.hpp"
#include "validation/study_table.hpp"

namespace fs = std::filesystem;
namespace ps = papersim::simulation;
namespace pc = papersim::collision;
namespace rm = papersim::remesh;

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

struct Case {
  std::string name;
  std::string what;  ///< one line: what is stressed
  ps::Scene scene;
  std::string not_run_reason;  ///< non-empty: listed, not run
  /// Time from which no external work is done (handles at rest) [s]: energy growth is
  /// measured from the first step after it.
  double work_free_from = 0.0;
};

struct Outcome {
  bool finished = false;
  std::string error;
  bool finite = true;
  double min_vertex_distance = INF;  ///< [m]
  double min_face_distance = INF;    ///< [m], non-planar obstacles
  double max_stretch = 1.0;
  int self_intersections = -1;
  double energy_growth = 0.0;  ///< max_k E_k - E_0 [J]
  double energy_scale = 0.0;   ///< m |g| (z0 + L) [J]
  double seconds = 0.0;
  int steps = 0;
  // With remeshing:
  int vertices_start = 0, vertices_max = 0, vertices_end = 0;
  int passes = 0, rollbacks = 0;
  double max_energy_jump = 0.0;  ///< largest |change| of the mechanical energy across a pass [J]
};

/// A 10 x 10 cm sheet with 5 mm edges, flat at height z0 above the ground, under gravity g.
ps::Scene drop_scene(double z0, double g, double duration, double h) {
  ps::Scene s;
  s.sheet.width = s.sheet.height = 0.1;
  s.sheet.edge_length = 5e-3;
  s.sheet.position = Eigen::Vector3d(0, 0, z0);
  s.gravity = Eigen::Vector3d(0, 0, -g);
  s.duration = duration;
  s.time_step = h;
  s.ground = true;
  return s;
}

pc::ColliderSpec sphere_at(const Eigen::Vector3d& centre, double radius) {
  pc::ColliderSpec c;
  c.kind = pc::ColliderKind::sphere;
  c.radius = radius;
  pc::Keyframe k;
  k.translation = centre;
  c.keyframes = {k};
  return c;
}

/// The CI-sized crumple (case 8): the crumple scenario's set-up at a twentieth of its cost.
ps::Scene shrinking_sphere_scene() {
  ps::Scene s;
  s.sheet.width = s.sheet.height = 0.08;
  s.sheet.edge_length = 8e-3;
  s.sheet.material.yield_curvature = 200.0;
  s.sheet.material.weakening = 2.0;
  s.sheet.material.damping = 1e-3;
  // Standing nearly upright at the centre, tilted 5 deg as the crumple scenario starts it; the
  // corners are 5.7 cm from the centre.
  s.sheet.position = Eigen::Vector3d(0, 0, 0.1);
  s.sheet.rotation_deg = Eigen::Vector3d(85, 2, 30);
  s.gravity = Eigen::Vector3d(0, 0, -9.8);
  s.duration = 0.95;
  s.time_step = 2e-3;  // the wall moves 0.09 mm per step, less than the sheet's gap to it
  s.ground = false;
  s.self_contact.enabled = true;
  s.contact.stiffness = 400.0;  // as the crumple scenario (simulation/scenario.cpp says why)
  const pc::ColliderSpec cavity = pc::shrinking_cavity(s.sheet.position, 0.06, 0.15, 0.85, 0.5);
  s.obstacles.push_back(cavity);
  return s;
}

std::vector<Case> make_cases(const fs::path& work) {
  std::vector<Case> cases;
  // 1. Time step from 0.1 ms to 40 ms: a drop of 1 cm onto the ground (impact at 0.44 m/s).
  for (double h : {1e-4, 1e-3, 1e-2, 2e-2, 4e-2}) {
    const double duration = h < 5e-4 ? 0.06 : h < 5e-3 ? 0.3 : 1.0;
    char name[64];
    std::snprintf(name, sizeof(name), "step %g ms", 1e3 * h);
    cases.push_back({name, "drop 1 cm onto the ground", drop_scene(0.01, 9.8, duration, h), ""});
  }
  // 2. Young's modulus 1e6 .. 1e11 Pa at 0.1 mm thickness.
  for (double E : {1e6, 1e8, 1e10, 1e11}) {
    ps::Scene s = drop_scene(0.01, 9.8, 0.3, 5e-3);
    s.sheet.material.stretch_stiffness = E * s.sheet.material.thickness;
    char name[64];
    std::snprintf(name, sizeof(name), "E %.0e Pa", E);
    cases.push_back({name, "drop 1 cm, Eh = E x 0.1 mm", s, ""});
  }
  // 3. Impact on a sphere of radius 2 cm at 1 and 10 m/s (v^2 = 2 g z over the gap).
  for (double v : {1.0, 10.0}) {
    const double g = v < 5 ? 100.0 : 1000.0, gap = v * v / (2 * g), r = 0.02;
    ps::Scene s = drop_scene(2 * r + gap, g, std::sqrt(2 * gap / g) + 0.02, 1e-3);
    s.obstacles.push_back(sphere_at(Eigen::Vector3d(0, 0, r), r));
    s.contact.faces = true;
    char name[64];
    std::snprintf(name, sizeof(name), "sphere impact %g m/s", v);
    cases.push_back({name, "sheet onto a 2 cm sphere, h = 1 ms", s, ""});
  }
  {  // The large step against a curved obstacle: 20 ms steps, the sheet drapes over the sphere.
    const double r = 0.02;
    ps::Scene s = drop_scene(2 * r + 0.01, 9.8, 1.0, 2e-2);
    s.obstacles.push_back(sphere_at(Eigen::Vector3d(0, 0, r), r));
    s.contact.faces = true;
    cases.push_back({"sphere step 20 ms", "drop 1 cm onto a 2 cm sphere, h = 20 ms", s, ""});
  }
  // 4. Knife edges: a gable with a 30 degree ridge, and a 1 mm plate hit edge-on.
  {
    const double height = 0.03;
    ps::Scene s = drop_scene(height + 0.01, 1000.0, std::sqrt(2 * 0.01 / 1000.0) + 0.02, 1e-3);
    pc::ColliderSpec gable;
    gable.kind = pc::ColliderKind::gable;
    gable.length = 0.15;
    gable.height = height;
    gable.half_width = height * std::tan(15 * M_PI / 180);
    s.obstacles.push_back(gable);
    s.contact.faces = true;  // the ridge is sharper than the edges
    cases.push_back({"gable ridge 30 deg", "onto a sharp ridge at 4.5 m/s", s, ""});
  }
  {
    ps::Scene s = drop_scene(0.05 + 0.01, 1000.0, std::sqrt(2 * 0.01 / 1000.0) + 0.02, 1e-3);
    pc::ColliderSpec plate;
    plate.kind = pc::ColliderKind::box;
    plate.half_extents = Eigen::Vector3d(0.075, 0.0005, 0.025);
    pc::Keyframe k;
    k.translation = Eigen::Vector3d(0, 0, 0.025);
    plate.keyframes = {k};
    s.obstacles.push_back(plate);
    s.contact.faces = true;  // 1 mm against 5 mm edges
    cases.push_back({"plate 1 mm edge-on", "onto the edge of a 1 mm plate at 4.5 m/s", s, ""});
  }
  // 5. Slivers: one row of vertices moved to 1% of a spacing from the next row.
  {
    rm::RectangleOptions o;
    o.width = o.height = 0.1;
    o.nx = o.ny = 21;
    rm::SheetMesh mesh = rm::make_rectangle(o);
    Eigen::MatrixX2d X = mesh.material_coords();
    const double dy = o.height / (o.ny - 1);
    for (int v = 0; v < X.rows(); ++v)
      if (std::abs(X(v, 1) - 10 * dy) < 1e-9) X(v, 1) = 11 * dy - 0.01 * dy;
    const rm::SheetMesh slivers(X, mesh.faces());
    const fs::path path = work / "slivers.obj";
    Eigen::MatrixX3d P(X.rows(), 3);
    P << X, Eigen::VectorXd::Constant(X.rows(), 0.01);  // world positions: 1 cm above the ground
    rm::write_sheet_file(path.string(), slivers, P, Eigen::MatrixX3d::Zero(X.rows(), 3), o.width,
                         o.height);
    ps::Scene s = drop_scene(0.01, 9.8, 0.3, 5e-3);
    s.sheet.mesh_path = path.string();  // starts where the file puts it
    cases.push_back(
        {"slivers aspect 0.01", "a row of triangles of aspect ratio 0.01, drop 1 cm", s, ""});
  }
  // 6. Gravity 5000 m/s^2 onto the ground (impact at 10 m/s).
  cases.push_back(
      {"gravity 5000", "drop 1 cm at 5000 m/s^2", drop_scene(0.01, 5000.0, 0.02, 1e-3), ""});
  // 7. A 180 degree fold with self-contact (validation/fold_scene.hpp).
  cases.push_back({"fold 180 deg", "right edge carried over onto the left half, self-contact",
                   papersim::validation::fold_180_scene(), "", 0.5});
  // 8. A shrinking-sphere crumple, CI-sized: an 8 x 8 cm sheet (8 mm edges) falls onto the wall
  // of a spherical cavity of radius 6 cm, which shrinks to 3 cm between 0.15 and 0.85 s (its
  // wall moves at 4.3 cm/s, the crumple scenario's speed is 3.75 cm/s) and then holds until
  // 0.95 s; self-contact on. The shrinking wall does work on the sheet, so energy growth is
  // measured once it holds still.
  cases.push_back({"shrinking sphere", "8 cm sheet crumpled in a cavity shrinking from 6 to 3 cm",
                   shrinking_sphere_scene(), "", 0.85});
  return cases;
}

/// Remeshing on in every case (--remesh): edges from half the case's edge length, flat regions
/// coarsened up to four times it.
void enable_remeshing(Case& c, bool refuse_thin_splits) {
  const double edge = c.scene.sheet.edge_length;
  c.scene.remesh.enabled = true;
  c.scene.remesh.params.size_min = 0.5 * edge;
  c.scene.remesh.params.size_max = 4.0 * edge;
  c.scene.remesh.params.refuse_thin_splits = refuse_thin_splits;
}

Outcome run_case(const Case& c, const std::string& keep) {
  Outcome out;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::unique_ptr<pc::Collider>> solids;  // non-planar obstacles, for the face check
  for (const auto& spec : c.scene.obstacles)
    if (spec.kind != pc::ColliderKind::plane) solids.push_back(pc::make_collider(spec));
  double e0 = NAN, e_max = -INF;
  rm::SheetMesh mesh;
  ps::SheetState initial;
  ps::initial_sheet(c.scene, mesh, initial);
  std::vector<Eigen::Vector3i> faces;
  double mass = c.scene.sheet.material.density * c.scene.sheet.width * c.scene.sheet.height;
  out.energy_scale =
      mass * c.scene.gravity.norm() *
      (c.scene.sheet.position.z() + std::max(c.scene.sheet.width, c.scene.sheet.height));
  pc::TriangleSdfParams params;
  params.cutoff = 1e-3;
  params.resolution = 2.5e-4;
  ps::RunOptions options;
  if (!keep.empty()) {
    std::string folder = c.name;
    for (char& ch : folder)
      if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    options.out_dir = (fs::path(keep) / folder).string();
  }
  options.on_step = [&](const ps::StepReport& r) {
    const ps::SheetState& s = *r.state;
    ++out.steps;
    if (!s.positions.allFinite()) out.finite = false;
    if (s.time >= c.work_free_from - 1e-12) {
      // What the steps changed: the jumps across remeshing passes are not work on the sheet.
      const double e = r.mechanical_energy - r.remesh_energy_change;
      if (std::isnan(e0)) e0 = e;  // after the first step (no work done yet)
      e_max = std::max(e_max, e);
    }
    out.max_stretch = std::max(out.max_stretch, r.max_stretch);
    for (double d : r.obstacle_distance)
      out.min_vertex_distance = std::min(out.min_vertex_distance, d);
    if (solids.empty() || !s.positions.allFinite()) return;
    faces.clear();  // the mesh of this state (remeshing changes it)
    for (int f = 0; f < r.mesh->num_faces(); ++f)
      faces.emplace_back(r.mesh->faces().row(f).transpose());
    std::vector<Eigen::Vector3d> x(static_cast<size_t>(s.num_vertices()));
    for (int v = 0; v < s.num_vertices(); ++v)
      x[static_cast<size_t>(v)] = s.positions.segment<3>(3 * v);
    for (const auto& solid : solids)
      for (const auto& hit :
           pc::mesh_edges_faces_vs_sdf(*solid, x, faces, solid->motion.pose(s.time), params))
        out.min_face_distance = std::min(out.min_face_distance, hit.result.distance);
  };
  try {
    const ps::RunResult r = ps::run_scene(c.scene, options);
    out.finished = true;
    out.vertices_start = r.sheet.vertices_start;
    out.vertices_max = r.sheet.vertices_max;
    out.vertices_end = r.sheet.vertices;
    if (r.remesh) {
      out.passes = r.remesh->passes;
      out.rollbacks = r.remesh->rollbacks;
      out.max_energy_jump = r.remesh->max_energy_jump;
    }
    if (r.state.positions.allFinite())
      out.self_intersections =
          pc::count_self_intersections(r.state.positions_matrix(), r.mesh.faces());
  } catch (const std::exception& e) {
    out.error = e.what();
  }
  out.energy_growth = std::isnan(e0) ? 0.0 : e_max - e0;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_stress_suite: the stability stress cases of VALIDATION.md section 8; every case "
      "reports NaN, penetration (vertices and faces), strain, self-intersection and energy growth. "
      "Exit status 1 when a case fails."};
  std::string csv;
  std::vector<std::string> only;
  app.add_option("--csv", csv, "also write the rows as CSV to this file");
  app.add_option("--only", only, "run only the cases whose name starts with one of these");
  std::string keep;
  app.add_option("--keep", keep, "write each case's outputs (sheet.obj, meta.json) to KEEP/<case>");
  bool remesh = false;
  app.add_flag(
      "--remesh", remesh,
      "every case remeshes (remesh.size_min half its edge, size_max four times it); reports the "
      "vertices, the passes kept and undone and the largest energy jump across a pass");
  bool thin = false;
  app.add_flag("--refuse-thin-splits", thin,
               "with --remesh: remesh.refuse_thin_splits on in every case")
      ->needs("--remesh");
  CLI11_PARSE(app, argc, argv);
  const fs::path work =
      fs::temp_directory_path() / ("papersim_stress_" + std::to_string(::getpid()));
  fs::create_directories(work);
  std::vector<Case> cases;
  try {
    cases = make_cases(work);
    if (remesh)
      for (Case& c : cases) enable_remeshing(c, thin);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_stress_suite: %s\n", e.what());
    return 2;
  }
  const auto wanted = [&](const std::string& name) {
    if (only.empty()) return true;
    return std::any_of(only.begin(), only.end(),
                       [&](const std::string& p) { return name.rfind(p, 0) == 0; });
  };
  for (const std::string& p : only)
    if (std::none_of(cases.begin(), cases.end(),
                     [&](const Case& c) { return c.name.rfind(p, 0) == 0; })) {
      std::string names;
      for (const Case& c : cases) names += (names.empty() ? "" : ", ") + c.name;
      std::fprintf(stderr,
                   "papersim_stress_suite: --only '%s' starts no case's name (the cases: %s)\n",
                   p.c_str(), names.c_str());
      fs::remove_all(work);
      return 2;
    }
  std::printf("%-22s %-5s %-6s %-22s %-22s %-18s %-8s %-20s %7s %s\n", "case", "steps", "nan",
              "vertices min d [m]", "faces min d [m]", "strain max s1", "self",
              "energy growth/scale", "wall s", "verdict");
  if (remesh)
    std::printf(
        "%-22s remeshed: vertices start / largest / end, passes kept (undone), largest energy jump "
        "across "
        "a pass / scale\n",
        "");
  std::unique_ptr<papersim::validation::StudyTable> table;
  try {
    table = std::make_unique<papersim::validation::StudyTable>(
        csv,
        std::string("case,what,steps,finite,min_vertex_distance,min_face_distance,max_stretch,"
                    "self_intersections,energy_growth_ratio,seconds,verdict,failed_checks") +
            (remesh ? ",vertices_start,vertices_max,vertices_end,remesh_passes,remesh_rollbacks,"
                      "max_energy_jump_ratio"
                    : ""));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_stress_suite: %s\n", e.what());
    fs::remove_all(work);
    return 5;
  }
  // false (and said) when the CSV cannot be written
  const auto add_row = [&](const std::string& row) {
    try {
      table->add(row);
      return true;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "papersim_stress_suite: %s\n", e.what());
      return false;
    }
  };
  int failures = 0, run = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (const Case& c : cases) {
    if (!wanted(c.name)) continue;
    if (!c.not_run_reason.empty()) {
      std::printf("%-22s not run: %s\n", c.name.c_str(), c.not_run_reason.c_str());
      if (!add_row('"' + c.name + "\",\"" + c.what + "\",,,,,,,,,not run,\"" + c.not_run_reason +
                   '"')) {
        fs::remove_all(work);
        return 5;
      }
      continue;
    }
    ++run;
    const Outcome o = run_case(c, keep);
    const double limit = 1 + c.scene.sheet.material.strain_limit;
    const double growth = o.energy_scale > 0 ? o.energy_growth / o.energy_scale : 0.0;
    std::vector<std::string> failed;
    if (!o.finished) failed.push_back("did not finish: " + o.error);
    if (!o.finite) failed.push_back("nan");
    if (o.min_vertex_distance < 0) failed.push_back("vertex penetration");
    if (o.min_face_distance < 0) failed.push_back("obstacle through a face");
    if (o.max_stretch > limit + 1e-12) failed.push_back("strain");
    if (o.finished && o.self_intersections != 0) failed.push_back("self-intersection");
    if (growth > 1e-3) failed.push_back("energy growth");
    std::string verdict = failed.empty() ? "PASS" : "FAIL";
    std::string reasons;
    for (const auto& f : failed) reasons += (reasons.empty() ? "" : "; ") + f;
    failures += !failed.empty();
    char faces_text[32];
    if (std::isinf(o.min_face_distance))
      std::snprintf(faces_text, sizeof(faces_text), "-");
    else
      std::snprintf(faces_text, sizeof(faces_text), "%.3g", o.min_face_distance);
    std::printf("%-22s %-5d %-6s %-22.3g %-22s %-18.6f %-8d %-20.2e %7.1f %s%s%s\n", c.name.c_str(),
                o.steps, o.finite ? "none" : "NaN", o.min_vertex_distance, faces_text,
                o.max_stretch, o.self_intersections, growth, o.seconds, verdict.c_str(),
                reasons.empty() ? "" : ": ", reasons.c_str());
    const double jump = o.energy_scale > 0 ? o.max_energy_jump / o.energy_scale : 0.0;
    if (remesh)
      std::printf("%-22s remeshed: %d / %d / %d vertices, %d passes (%d undone), jump %.2e\n", "",
                  o.vertices_start, o.vertices_max, o.vertices_end, o.passes, o.rollbacks, jump);
    std::fflush(stdout);
    if (table->enabled()) {
      std::ostringstream row;
      row << '"' << c.name << "\",\"" << c.what << "\"," << o.steps << ',' << o.finite << ','
          << o.min_vertex_distance << ',' << o.min_face_distance << ',' << o.max_stretch << ','
          << o.self_intersections << ',' << growth << ',' << o.seconds << ',' << verdict << ",\""
          << reasons << '"';
      if (remesh)
        row << ',' << o.vertices_start << ',' << o.vertices_max << ',' << o.vertices_end << ','
            << o.passes << ',' << o.rollbacks << ',' << jump;
      if (!add_row(row.str())) {
        fs::remove_all(work);
        return 5;
      }
    }
  }
  fs::remove_all(work);
  std::printf("\n%d cases run, %d failed; wall time %.1f s\n", run, failures,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return failures == 0 ? 0 : 1;
}
