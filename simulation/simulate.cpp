#include "simulation/simulate.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <sstream>

#include "collision/errors.hpp"
#include "common/atomic_file.hpp"
#include "collision/self_intersection.hpp"
#include "remesh/errors.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/energies/membrane_energy.hpp"
#include "simulation/energies/vertex_energies.hpp"
#include "simulation/errors.hpp"
#include "simulation/integrator.hpp"
#include "simulation/output_files.hpp"

#ifndef PAPERSIM_VERSION_STRING
#define PAPERSIM_VERSION_STRING "unknown"
#endif

namespace papersim::simulation {

namespace fs = std::filesystem;
using nlohmann::json;

const char* version() { return PAPERSIM_VERSION_STRING; }

namespace {

Eigen::Matrix3d rotation(const Eigen::Vector3d& deg) {
  const Eigen::Vector3d a = deg * M_PI / 180;
  return (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

std::vector<HandleSpec> all_handles(const Scene& scene, const remesh::SheetMesh& mesh) {
  std::vector<HandleSpec> handles = scene.handles;
  const Eigen::MatrixX2d X = mesh.material_coords();
  for (const ClampSpec& c : scene.clamps) {
    int held = 0;
    for (int v = 0; v < X.rows(); ++v)
      if (X(v, 0) >= c.region[0] - 1e-12 && X(v, 0) <= c.region[2] + 1e-12 &&
          X(v, 1) >= c.region[1] - 1e-12 && X(v, 1) <= c.region[3] + 1e-12) {
        HandleSpec h;
        h.material_point = X.row(v).transpose();
        h.release_time = c.release_time;
        h.stiffness = c.stiffness;
        handles.push_back(h);
        ++held;
      }
    if (held == 0) throw SceneError("clamp region holds no vertex of the sheet");
  }
  return handles;
}

/// Faces held by clamps that are never released: they keep their slopes (Morley model).
std::vector<int> clamped_faces(const Scene& scene, const remesh::SheetMesh& mesh) {
  std::vector<int> faces;
  for (const ClampSpec& c : scene.clamps)
    if (std::isinf(c.release_time))
      for (int f : remesh::faces_inside(mesh, c.region)) faces.push_back(f);
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

struct Built {
  std::unique_ptr<Integrator> integrator;
  MembraneEnergy* membrane = nullptr;
  BendingEnergy* bending = nullptr;
  HandleEnergy* handles = nullptr;
  ObstacleContactEnergy* contact = nullptr;
  SelfContactEnergy* self_contact = nullptr;
  std::vector<std::shared_ptr<const collision::Collider>> obstacles;
  Eigen::VectorXd masses;
};

Built build(const Scene& scene, const remesh::SheetMesh& mesh, const SheetState& state) {
  Built b;
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const Material& m = scene.sheet.material;
  b.masses = lumped_masses(X, F, m.density);
  std::vector<std::unique_ptr<EnergyTerm>> terms;
  terms.push_back(std::make_unique<InertiaEnergy>(b.masses));
  if (m.damping > 0) terms.push_back(std::make_unique<DampingEnergy>(b.masses, m.damping));
  terms.push_back(std::make_unique<GravityEnergy>(b.masses, scene.gravity));
  auto membrane = std::make_unique<MembraneEnergy>(X, F, m);
  b.membrane = membrane.get();
  terms.push_back(std::move(membrane));
  auto bending = make_bending_energy(mesh, m, BendingHessian::gauss_newton, clamped_faces(scene, mesh));
  b.bending = bending.get();
  terms.push_back(std::move(bending));
  const std::vector<HandleSpec> handles = all_handles(scene, mesh);
  if (!handles.empty()) {
    auto h = std::make_unique<HandleEnergy>(mesh, state.positions, handles);
    b.handles = h.get();
    terms.push_back(std::move(h));
  }
  if (scene.ground) {
    auto ground = std::make_shared<collision::PlaneCollider>();
    ground->friction = scene.ground_friction;
    b.obstacles.push_back(ground);
  }
  for (size_t i = 0; i < scene.obstacles.size(); ++i) {
    try {
      b.obstacles.push_back(collision::make_collider(scene.obstacles[i]));
    } catch (const collision::ColliderError& e) {
      throw SceneError((scene.source.empty() ? std::string("scene") : scene.source) +
                       ": key 'obstacles[" + std::to_string(i) + "]': " + e.what());
    }
  }
  ContactParams p = scene.contact;
  if (p.stiffness <= 0) p.stiffness = m.density * std::max(scene.gravity.norm(), 1.0);
  if (!b.obstacles.empty()) {
    Eigen::VectorXd areas = b.masses / m.density;
    auto c = std::make_unique<ObstacleContactEnergy>(areas, b.obstacles, p);
    if (p.faces) c->set_faces(mesh.faces(), mesh.material_coords());
    c->set_impact_density(m.density);
    b.contact = c.get();
    terms.push_back(std::move(c));
  }
  if (scene.self_contact.enabled) {
    SelfContactParams sp = scene.self_contact;
    if (sp.dhat <= 0) sp.dhat = p.dhat;
    if (sp.stiffness <= 0) sp.stiffness = p.stiffness;
    sp.eps_velocity = p.eps_velocity;
    auto c = std::make_unique<SelfContactEnergy>(X, F, sp);
    b.self_contact = c.get();
    terms.push_back(std::move(c));
  }
  b.integrator = std::make_unique<Integrator>(mesh.num_vertices(), std::move(terms), scene.newton);
  return b;
}

/// Running extremes over the run, for meta.json.
struct Tracker {
  double max_stretch = 1.0, min_compression = 1.0, max_speed = 0.0;
  std::vector<double> min_distance;
  // This step's values (the last update).
  double step_stretch = 1.0;
  std::vector<double> step_distance;
  void update(const Built& b, const SheetState& s) {
    const Eigen::MatrixX2d st = b.membrane->principal_stretches(s.positions);
    step_stretch = st.col(0).maxCoeff();
    max_stretch = std::max(max_stretch, step_stretch);
    min_compression = std::min(min_compression, st.col(1).minCoeff());
    for (int v = 0; v < s.num_vertices(); ++v)
      max_speed = std::max(max_speed, s.velocities.segment<3>(3 * v).norm());
    min_distance.resize(b.obstacles.size(), INF);
    step_distance.assign(b.obstacles.size(), INF);
    for (size_t o = 0; o < b.obstacles.size(); ++o) {
      step_distance[o] = b.contact->surface_distance(static_cast<int>(o), s.positions, s.time);
      min_distance[o] = std::min(min_distance[o], step_distance[o]);
    }
  }
};

struct Energies {
  double stretch = 0, bend = 0, gravity = 0, kinetic = 0;
  double mechanical() const { return stretch + bend + gravity + kinetic; }
};

Energies energies(const Built& b, const Scene& scene, const SheetState& s) {
  Energies e;
  for (int v = 0; v < s.num_vertices(); ++v) {
    e.kinetic += 0.5 * b.masses[v] * s.velocities.segment<3>(3 * v).squaredNorm();
    e.gravity -= b.masses[v] * scene.gravity.dot(s.positions.segment<3>(3 * v));
  }
  e.stretch = b.membrane->value(s.positions);
  e.bend = b.bending->value(s.positions);
  return e;
}

}  // namespace

void initial_sheet(const Scene& scene, remesh::SheetMesh& mesh, SheetState& state) {
  const SheetSpec& sp = scene.sheet;
  Eigen::MatrixX3d x;
  if (!sp.mesh_path.empty()) {
    const std::string key = (scene.source.empty() ? std::string("scene") : scene.source) +
                            ": key 'sheet.mesh': ";
    remesh::SheetData d;
    try {
      d = remesh::read_sheet(sp.mesh_path);
    } catch (const std::runtime_error& e) {  // remesh::IoError, remesh::MeshError
      throw SceneError(key + e.what());
    }
    if (d.positions.cwiseAbs().maxCoeff() > MAX_SCENE_COORDINATE)
      throw SceneError(key + "a vertex coordinate beyond the limit of 1000 m");
    mesh = d.mesh;
    x = d.positions;
  } else {
    const Eigen::Vector2i n = remesh::grid_for_edge_length(sp.width, sp.height, sp.edge_length);
    remesh::RectangleOptions o;
    o.width = sp.width;
    o.height = sp.height;
    o.nx = n.x();
    o.ny = n.y();
    o.triangulation = sp.triangulation;
    o.seed = scene.seed >= 0 ? static_cast<std::uint64_t>(scene.seed) : 0;
    mesh = remesh::make_rectangle(o);
    const Eigen::MatrixX2d X = mesh.material_coords();
    const Eigen::Matrix3d R = rotation(sp.rotation_deg);
    x.resize(X.rows(), 3);
    for (int v = 0; v < X.rows(); ++v) {
      const Eigen::Vector3d local(X(v, 0) - 0.5 * sp.width, X(v, 1) - 0.5 * sp.height, 0.0);
      x.row(v) = (R * local + sp.position).transpose();
    }
  }
  state.positions = flatten(x);
  state.velocities = Eigen::VectorXd::Zero(state.positions.size());
  state.time = 0.0;
}

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  const auto t_start = std::chrono::steady_clock::now();
  RunResult r;
  initial_sheet(scene, r.mesh, r.state);
  Built b = build(scene, r.mesh, r.state);
  if (b.self_contact) {
    // The barrier keeps an intersection-free sheet so; it cannot undo an intersection.
    const int crossings = collision::count_self_intersections(r.state.positions_matrix(), r.mesh.faces());
    if (crossings > 0 || !(b.self_contact->min_distance(r.state.positions, b.self_contact->params().dhat) > 0))
      throw SceneError("the sheet starts intersecting itself (" + std::to_string(crossings) +
                       " triangle pairs); self-contact needs an intersection-free start");
  }
  if (b.contact) {
    for (size_t o = 0; o < b.obstacles.size(); ++o)
      for (int v = 0; v < r.state.num_vertices(); ++v)
        if (b.obstacles[o]->distance(r.state.positions.segment<3>(3 * v), 0.0) <= 0)
          throw SceneError("the sheet starts inside obstacle " + std::to_string(o) +
                           (scene.ground ? " (0 is the ground)" : ""));
  }
  Staging staging(options.out_dir);
  const int frames_every = options.frames_every >= 0 ? options.frames_every : scene.output.frames_every;
  if (staging.active() && frames_every > 0) fs::create_directories(staging.dir() / "frames");
  const int steps = std::max(1, static_cast<int>(std::lround(scene.duration / scene.time_step)));
  const double h = scene.duration / steps;
  Tracker track;
  track.update(b, r.state);
  StepStats total;
  int last_percent = -1;
  for (int k = 1; k <= steps; ++k) {
    const StepStats s = b.integrator->step(r.state, h);
    total.substeps += s.substeps;
    total.failed_solves += s.failed_solves;
    total.newton_iterations += s.newton_iterations;
    total.projected_hessians += s.projected_hessians;
    total.line_search_evaluations += s.line_search_evaluations;
    total.extrapolations += s.extrapolations;
    total.seconds_assembly += s.seconds_assembly;
    total.seconds_solve += s.seconds_solve;
    total.seconds_line_search += s.seconds_line_search;
    if (options.poll_stop) options.poll_stop();
    track.update(b, r.state);
    if (options.on_step) {
      StepReport report;
      report.step = k;
      report.state = &r.state;
      report.mechanical_energy = energies(b, scene, r.state).mechanical();
      report.max_stretch = track.step_stretch;
      report.obstacle_distance = track.step_distance;
      options.on_step(report);
    }
    if (staging.active() && frames_every > 0 && k % frames_every == 0) {
      std::ostringstream name;
      name << "frame_" << std::setw(6) << std::setfill('0') << k << ".obj";
      remesh::write_sheet_file((staging.dir() / "frames" / name.str()).string(), r.mesh,
                               r.state.positions_matrix(), r.state.velocities_matrix(),
                               scene.sheet.width, scene.sheet.height);
    }
    const int percent = static_cast<int>(100.0 * k / steps);
    if (options.progress && percent != last_percent) {
      last_percent = percent;
      options.progress(double(k) / steps,
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  json& m = r.meta;
  m["program"] = "papersim";
  m["version"] = version();
  m["scene"] = scene_to_json(scene);
  if (!scene.scenario.empty()) m["scenario"] = scene.scenario;
  if (scene.seed >= 0) m["seed"] = scene.seed;
  m["sheet"] = {{"width", scene.sheet.width},
                {"height", scene.sheet.height},
                {"vertices", r.mesh.num_vertices()},
                {"faces", r.mesh.num_faces()}};
  m["run"] = {{"wall_seconds", wall},
              {"steps", steps},
              {"time_step", h},
              {"substeps", total.substeps},
              {"failed_solves", total.failed_solves},
              {"newton_iterations", total.newton_iterations},
              {"projected_hessians", total.projected_hessians},
              {"line_search_evaluations", total.line_search_evaluations},
              {"extrapolations", total.extrapolations},
              {"seconds_assembly", total.seconds_assembly},
              {"seconds_solve", total.seconds_solve},
              {"seconds_line_search", total.seconds_line_search},
              {"pattern_changes", b.integrator->pattern_id()}};
  if (b.contact)
    m["run"]["contact"] = {{"seconds", b.contact->seconds()},
                           {"max_friction_points", b.contact->max_friction_points()},
                           {"max_normal_force", b.contact->max_normal_force()}};
  if (b.self_contact)
    m["run"]["self_contact"] = {{"seconds", b.self_contact->seconds()},
                                {"max_active_pairs", b.self_contact->max_active_pairs()},
                                {"pattern_changes", b.self_contact->pattern_changes()}};
  json quality = {{"max_principal_stretch", track.max_stretch},
                  {"min_principal_stretch", track.min_compression},
                  {"strain_limit", scene.sheet.material.strain_limit},
                  {"max_speed", track.max_speed}};
  json distances = json::array();
  for (double d : track.min_distance) distances.push_back(d);
  quality["min_obstacle_distance"] = distances;
  quality["self_intersections"] =
      collision::count_self_intersections(r.state.positions_matrix(), r.mesh.faces());
  if (b.handles) {
    double worst = 0;
    for (int i = 0; i < b.handles->size(); ++i)
      if (b.handles->active(i, r.state.time - 1e-12))
        worst = std::max(worst, b.handles->error(i, r.state.positions, r.state.time));
    quality["max_handle_error"] = worst;
  }
  m["quality"] = quality;
  const Energies end = energies(b, scene, r.state);
  m["energy"] = {{"stretch", end.stretch}, {"bend", end.bend}, {"gravity", end.gravity}, {"kinetic", end.kinetic}};
  for (auto it = options.extra_meta.begin(); it != options.extra_meta.end(); ++it) m[it.key()] = it.value();
  if (staging.active()) {
    write_outputs(staging.dir(), scene, r.mesh, r.state);
    for (const auto& [name, text] : options.extra_files)
      common::write_text_atomically(staging.dir() / name, text);
    write_json(staging.dir() / "meta.json", m);
    staging.commit();
  }
  return r;
}

}  // namespace papersim::simulation
