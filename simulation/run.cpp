#include "simulation/run.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "collision/errors.hpp"
#include "collision/self_intersection.hpp"
#include "common/assert.hpp"
#include "common/clock.hpp"
#include "remesh/errors.hpp"
#include "remesh/sheet_io.hpp"
#include "remesh/sizing.hpp"
#include "simulation/energies/vertex_energies.hpp"
#include "simulation/errors.hpp"
#include "simulation/plasticity.hpp"
#include "simulation/remesh_veto.hpp"

namespace papersim::simulation {

Eigen::Matrix3d sheet_rotation(const Eigen::Vector3d& deg) {
  const Eigen::Vector3d a = deg * M_PI / 180;
  return (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

namespace {

bool inside(const Eigen::Vector4d& box, const Eigen::Vector2d& p) {
  return p.x() >= box[0] - 1e-12 && p.x() <= box[2] + 1e-12 && p.y() >= box[1] - 1e-12 &&
         p.y() <= box[3] + 1e-12;
}

/// The clamps of `setup` on `mesh`: a handle on every vertex inside a clamp's region, anchored
/// where its material point was at the start.
std::vector<AnchoredHandle> clamp_handles(const remesh::SheetMesh& mesh,
                                          const PhysicsSetup& setup) {
  std::vector<AnchoredHandle> handles;
  const Eigen::MatrixX2d X = mesh.material_coords();
  for (size_t c = 0; c < setup.clamps.size(); ++c) {
    const ClampSpec& clamp = setup.clamps[c];
    int held = 0;
    for (int v = 0; v < X.rows(); ++v) {
      if (!inside(clamp.region, X.row(v).transpose())) continue;
      AnchoredHandle h;
      h.spec.material_point = X.row(v).transpose();
      h.spec.release_time = clamp.release_time;
      h.spec.stiffness = clamp.stiffness;
      h.anchor = setup.placement(h.spec.material_point);
      handles.push_back(h);
      ++held;
    }
    if (held == 0)
      throw SceneError("clamps[" + std::to_string(c) +
                       "]: the region holds no vertex of the sheet");
  }
  return handles;
}

/// Faces held by clamps that are never released: they keep their slopes (Morley model).
std::vector<int> clamped_faces(const remesh::SheetMesh& mesh,
                               const std::vector<ClampSpec>& clamps) {
  std::vector<int> faces;
  for (const ClampSpec& c : clamps)
    if (std::isinf(c.release_time))
      for (int f : remesh::faces_inside(mesh, c.region)) faces.push_back(f);
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

void add_contact_terms(const remesh::SheetMesh& mesh, const PhysicsSetup& setup,
                       TermStatistics* stats, Terms& t) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  if (!setup.obstacles.empty()) {
    auto c = std::make_unique<ObstacleContactEnergy>(t.masses / setup.material.density,
                                                     setup.obstacles, setup.contact);
    if (setup.contact.faces) c->set_faces(F, X);
    if (setup.impact_rule) c->set_impact_density(setup.material.density);
    if (stats) c->set_statistics(&stats->contact);
    t.contact = c.get();
    t.list.push_back(std::move(c));
  }
  if (setup.self_contact) {
    auto c = std::make_unique<SelfContactEnergy>(X, F, setup.self_contact_params);
    if (stats) c->set_statistics(&stats->self_contact);
    t.self_contact = c.get();
    t.list.push_back(std::move(c));
  }
}

/// How errors about the key `sheet.mesh` begin: "SCENE_FILE: key 'sheet.mesh': ".
std::string sheet_mesh_key(const Scene& scene) {
  return (scene.source.empty() ? std::string("scene") : scene.source) + ": key 'sheet.mesh': ";
}

/// The error for a sheet read from a file (key `sheet.mesh`, a checkpoint) whose terms cannot be
/// built, e.g. a bending system that cannot be factored on faces far thinner or larger than the
/// rest: an input error naming the sheet and its thinnest face in material space.
SceneError unusable_sheet(const std::string& sheet, const remesh::SheetMesh& mesh,
                          const NumericError& e) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  double thinnest = INF;
  int face = -1;
  for (int f = 0; f < F.rows(); ++f) {
    const double a = remesh::aspect_ratio(X.row(F(f, 0)), X.row(F(f, 1)), X.row(F(f, 2)));
    if (a < thinnest) thinnest = a, face = f;
  }
  char what[160];
  std::snprintf(
      what, sizeof what,
      " (its thinnest face in material space is face %d, of aspect ratio %.3g; 1: equilateral)",
      face, thinnest);
  return SceneError(sheet + " cannot be simulated: " + e.what() + what);
}

}  // namespace

void initial_sheet(const Scene& scene, remesh::SheetMesh& mesh, SheetState& state) {
  const SheetSpec& sp = scene.sheet;
  Eigen::MatrixX3d x;
  if (!sp.mesh_path.empty()) {
    const std::string key = sheet_mesh_key(scene);
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
    const Eigen::Matrix3d R = sheet_rotation(sp.rotation_deg);
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

InitialPlacement::InitialPlacement(const remesh::SheetMesh& mesh, const Eigen::VectorXd& positions)
    : m_mesh(std::make_shared<const remesh::SheetMesh>(mesh)), m_positions(positions) {}

Eigen::Vector3d InitialPlacement::operator()(const Eigen::Vector2d& p) const {
  PAPERSIM_ASSERT(m_mesh != nullptr, "InitialPlacement: no mesh");
  HandleSpec point;
  point.material_point = p;
  return anchor_handles(*m_mesh, m_positions, {point}).front().anchor;
}

PhysicsSetup physics_setup(const Scene& scene, const remesh::SheetMesh& mesh,
                           const SheetState& initial) {
  PhysicsSetup s;
  s.material = scene.sheet.material;
  s.gravity = scene.gravity;
  s.handles = anchor_handles(mesh, initial.positions, scene.handles);
  s.clamps = scene.clamps;
  if (!s.clamps.empty()) s.placement = InitialPlacement(mesh, initial.positions);
  if (scene.ground) {
    auto ground = std::make_shared<collision::PlaneCollider>();
    ground->friction = scene.ground_friction;
    s.obstacles.push_back(ground);
  }
  for (size_t i = 0; i < scene.obstacles.size(); ++i) {
    try {
      std::shared_ptr<collision::Collider> c = collision::make_collider(scene.obstacles[i]);
      const collision::LiftSpec& lift = scene.obstacles[i].lift;
      if (lift.enabled() && lift.coupled && (scene.contact.faces || !(scene.gravity.norm() > 0)))
        throw collision::ColliderError(
            std::string("lift.coupled needs ") +
            (scene.contact.faces ? "vertex contact (contact.faces false)" : "gravity"));
      if (scene.obstacles[i].lift.enabled())
        s.lifts.push_back({static_cast<int>(s.obstacles.size()), static_cast<int>(i),
                           scene.obstacles[i].lift, c, c->motion});
      s.obstacles.push_back(std::move(c));
    } catch (const collision::ColliderError& e) {
      throw SceneError((scene.source.empty() ? std::string("scene") : scene.source) +
                       ": key 'obstacles[" + std::to_string(i) + "]': " + e.what());
    }
  }
  s.contact = scene.contact;
  if (s.contact.stiffness <= 0)
    s.contact.stiffness = s.material.density * std::max(scene.gravity.norm(), 1.0);
  s.self_contact = scene.self_contact.enabled;
  s.self_contact_params = scene.self_contact;
  if (s.self_contact_params.dhat <= 0) s.self_contact_params.dhat = s.contact.dhat;
  if (s.self_contact_params.stiffness <= 0) s.self_contact_params.stiffness = s.contact.stiffness;
  s.self_contact_params.eps_velocity = s.contact.eps_velocity;
  s.self_contact_params.static_whole_step = s.contact.static_whole_step;
  return s;
}

Terms build_terms(const remesh::SheetMesh& mesh, const PhysicsSetup& setup,
                  TermStatistics* statistics) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const Material& m = setup.material;
  Terms t;
  t.masses = lumped_masses(X, F, m.density);
  t.list.push_back(std::make_unique<InertiaEnergy>(t.masses));
  if (m.damping > 0) t.list.push_back(std::make_unique<DampingEnergy>(t.masses, m.damping));
  if (setup.gravity.squaredNorm() > 0)
    t.list.push_back(std::make_unique<GravityEnergy>(t.masses, setup.gravity));
  auto membrane = std::make_unique<MembraneEnergy>(mesh, m);
  t.membrane = membrane.get();
  t.list.push_back(std::move(membrane));
  auto bending =
      make_bending_energy(mesh, m, BendingHessian::gauss_newton, clamped_faces(mesh, setup.clamps));
  t.bending = bending.get();
  t.list.push_back(std::move(bending));
  std::vector<AnchoredHandle> handles = setup.handles;
  const std::vector<AnchoredHandle> clamps = clamp_handles(mesh, setup);
  handles.insert(handles.end(), clamps.begin(), clamps.end());
  if (!handles.empty()) {
    auto h = std::make_unique<HandleEnergy>(mesh, handles);
    t.handles = h.get();
    t.list.push_back(std::move(h));
  }
  add_contact_terms(mesh, setup, statistics, t);
  for (const PhysicsSetup::Lift& l : setup.lifts) {
    if (!l.lift.coupled) continue;
    const int block = mesh.num_vertices() + static_cast<int>(t.lift_bodies.size());
    t.contact->set_rigid_block(l.obstacle, block);
    auto body = std::make_unique<LiftBodyEnergy>(block, l.lift.load, setup.gravity);
    t.lift_bodies.push_back(body.get());
    t.list.push_back(std::move(body));
  }
  return t;
}

EnergyBreakdown energy_breakdown(const Terms& terms, const Eigen::Vector3d& gravity,
                                 const SheetState& s) {
  EnergyBreakdown e;
  for (int v = 0; v < s.num_vertices(); ++v) {
    e.kinetic += 0.5 * terms.masses[v] * s.velocities.segment<3>(3 * v).squaredNorm();
    e.gravity -= terms.masses[v] * gravity.dot(s.positions.segment<3>(3 * v));
  }
  e.stretch = terms.membrane->value(s.positions);
  e.bend = terms.bending->value(s.positions);
  return e;
}

Run::Run(const Scene& scene, const Trace& trace) : m_scene(scene), m_trace(trace) {
  initial_sheet(scene, m_mesh, m_state);
  m_setup = physics_setup(scene, m_mesh, m_state);
  m_setup.contact.trace = m_setup.self_contact_params.trace = trace;
  try {
    rebuild();
  } catch (const NumericError& e) {
    if (scene.sheet.mesh_path.empty()) throw;
    throw unusable_sheet(sheet_mesh_key(scene) + scene.sheet.mesh_path, m_mesh, e);
  }
  check_state("starts");
  m_steps = std::max(1, static_cast<int>(std::lround(scene.duration / scene.time_step)));
  m_h = scene.duration / m_steps;
  m_counts.vertices_start = m_counts.vertices_max = m_mesh.num_vertices();
  m_counts.faces_start = m_counts.faces_max = m_mesh.num_faces();
  m_quality.strain_limit = m_setup.material.strain_limit;
  for (const PhysicsSetup::Lift& l : m_setup.lifts) m_quality.lifts.push_back({l.spec, 0.0, 0.0});
  track();
}

Run::~Run() = default;

void Run::check_state(const std::string& what) const {
  if (m_terms.self_contact) {
    // The barrier keeps an intersection-free sheet so; it cannot undo an intersection.
    const int crossings =
        collision::count_self_intersections(m_state.positions_matrix(), m_mesh.faces());
    if (crossings > 0 || !(m_terms.self_contact->min_distance(
                               m_state.positions, m_setup.self_contact_params.dhat) > 0))
      throw SceneError("the sheet " + what + " intersecting itself (" + std::to_string(crossings) +
                       " triangle pairs); self-contact needs an intersection-free start");
  }
  for (size_t o = 0; o < m_setup.obstacles.size(); ++o)
    for (int v = 0; v < m_state.num_vertices(); ++v)
      if (m_setup.obstacles[o]->distance(m_state.positions.segment<3>(3 * v), m_state.time) <= 0)
        throw SceneError("the sheet " + what + " inside obstacle " + std::to_string(o) +
                         (m_scene.ground ? " (0 is the ground)" : ""));
}

std::vector<std::array<int, 3>> Run::self_contact_pattern() const {
  return m_terms.self_contact ? m_terms.self_contact->pattern_pairs()
                              : std::vector<std::array<int, 3>>{};
}

std::optional<ReusableFactor> Run::reusable_factor() const {
  return m_integrator->reusable_factor();
}

void Run::adopt_factor(const ReusableFactor& factor) {
  try {
    m_integrator->adopt_factor(factor);
  } catch (const std::invalid_argument& e) {
    throw SceneError(std::string("resume: ") + e.what());
  } catch (const NumericError& e) {  // CHOLMOD failed on it for another reason
    throw SceneError(std::string("resume: the saved factorisation's matrix: ") + e.what());
  }
}

void Run::resume(const remesh::SheetMesh& mesh, const SheetState& state, int step,
                 const Scene* saved, const RunTally* tally,
                 const std::vector<std::array<int, 3>>* self_contact_pattern) {
  if (state.positions.size() != 3 * mesh.num_vertices() ||
      state.velocities.size() != state.positions.size())
    throw SceneError("resume: the state has " + std::to_string(state.positions.size() / 3) +
                     " vertices, the mesh " + std::to_string(mesh.num_vertices()));
  if (step < 0 || step > m_steps)
    throw SceneError("resume: step " + std::to_string(step) + " is outside the run's 0.." +
                     std::to_string(m_steps));
  if (std::abs(state.time - step * m_h) > 1e-9 * std::max(1.0, m_scene.duration))
    throw SceneError("resume: the state's time does not match step " + std::to_string(step) +
                     " of this scene's time step (another time_step or duration?)");
  if (saved) {
    for (const PhysicsSetup::Lift& l : m_setup.lifts) {
      if (l.spec >= static_cast<int>(saved->obstacles.size()) ||
          !saved->obstacles[l.spec].lift.enabled())
        continue;
      // Times and translations as saved (exact in JSON), rotations and scales from the scene's
      // motion at those times, as the run that saved them made them (RigidMotion::translate_from).
      collision::RigidMotion m = l.keyframed;
      for (const collision::Keyframe& k : saved->obstacles[l.spec].keyframes)
        m.set_translation_at(k.time, k.translation, l.keyframed);
      l.collider->motion = m;
      m_scene.obstacles[l.spec].keyframes = m.keyframes();
    }
  }
  m_mesh = mesh;
  m_state = state;
  m_step = step;
  try {
    rebuild();
  } catch (const NumericError& e) {
    throw unusable_sheet("resume: the saved sheet", m_mesh, e);
  }
  // (A scene continued without self-contact has no use for the pattern.)
  if (self_contact_pattern && !self_contact_pattern->empty() && m_terms.self_contact) {
    try {
      m_terms.self_contact->restore_pattern(*self_contact_pattern);
    } catch (const std::invalid_argument& e) {
      throw SceneError(std::string("resume: ") + e.what());
    }
    m_integrator->adopt_dynamic_patterns();
  }
  check_state("resumes");
  m_counts.vertices_start = m_counts.vertices_max = m_mesh.num_vertices();
  m_counts.faces_start = m_counts.faces_max = m_mesh.num_faces();
  m_quality = RunQuality{};
  m_quality.strain_limit = m_setup.material.strain_limit;
  for (const PhysicsSetup::Lift& l : m_setup.lifts) m_quality.lifts.push_back({l.spec, 0.0, 0.0});
  track();
  if (!tally) return;
  const RunQuality& q = tally->quality;
  if (q.min_obstacle_distance.size() != m_quality.min_obstacle_distance.size() ||
      q.lifts.size() != m_quality.lifts.size())
    throw SceneError("resume: the saved run figures are for " +
                     std::to_string(q.min_obstacle_distance.size()) + " obstacles (" +
                     std::to_string(q.lifts.size()) + " lifting), this scene has " +
                     std::to_string(m_quality.min_obstacle_distance.size()) + " (" +
                     std::to_string(m_quality.lifts.size()) + ")");
  m_totals = tally->totals;
  m_pattern_changes_done = tally->pattern_changes;
  m_counts.vertices_start = tally->sheet.vertices_start;
  m_counts.faces_start = tally->sheet.faces_start;
  m_counts.vertices_max = std::max(m_counts.vertices_max, tally->sheet.vertices_max);
  m_counts.faces_max = std::max(m_counts.faces_max, tally->sheet.faces_max);
  m_term_stats = tally->terms;  // in place: the terms count into these
  m_quality.max_principal_stretch =
      std::max(m_quality.max_principal_stretch, q.max_principal_stretch);
  m_quality.min_principal_stretch =
      std::min(m_quality.min_principal_stretch, q.min_principal_stretch);
  m_quality.max_speed = std::max(m_quality.max_speed, q.max_speed);
  for (size_t o = 0; o < q.min_obstacle_distance.size(); ++o)
    m_quality.min_obstacle_distance[o] =
        std::min(m_quality.min_obstacle_distance[o], q.min_obstacle_distance[o]);
  for (size_t l = 0; l < q.lifts.size(); ++l) {
    m_quality.lifts[l].max_load = std::max(m_quality.lifts[l].max_load, q.lifts[l].max_load);
    m_quality.lifts[l].max_rise = std::max(m_quality.lifts[l].max_rise, q.lifts[l].max_rise);
  }
  m_remesh = tally->remesh;
  m_energy_min = std::min(m_energy_min, tally->energy_min);
  m_energy_max = std::max(m_energy_max, tally->energy_max);
}

namespace {

template <typename Map>
void add_counts(Map& into, const Map& from) {
  for (const auto& [key, n] : from) into[key] += n;
}

}  // namespace

void Run::rebuild() {
  if (m_integrator) m_pattern_changes_done += m_integrator->pattern_id();
  m_terms = build_terms(m_mesh, m_setup, &m_term_stats);
  m_integrator = std::make_unique<Integrator>(m_mesh.num_vertices(), std::move(m_terms.list),
                                              newton_params(), coupled_lifts());
}

NewtonParams Run::newton_params() const {
  NewtonParams p = m_scene.newton;
  p.trace = m_trace;
  return p;
}

int Run::coupled_lifts() const {
  return static_cast<int>(
      std::count_if(m_setup.lifts.begin(), m_setup.lifts.end(),
                    [](const PhysicsSetup::Lift& l) { return l.lift.coupled; }));
}

double Run::rise(const PhysicsSetup::Lift& l, double t) {
  return l.collider->motion.pose(t).translation().z() - l.keyframed.pose(t).translation().z();
}

void Run::begin_lift_bodies(Terms& terms, Integrator& integrator) const {
  if (terms.lift_bodies.empty()) return;
  const double t = m_state.time;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(3 * static_cast<int>(terms.lift_bodies.size()));
  size_t k = 0;
  for (const PhysicsSetup::Lift& l : m_setup.lifts) {
    if (!l.lift.coupled) continue;
    terms.lift_bodies[k]->set_rise(rise(l, t));
    // The last step's vertical velocity: the motion moves linearly over each step.
    if (t >= m_h) v[3 * k + 2] = (rise(l, t) - rise(l, t - m_h)) / m_h;
    ++k;
  }
  integrator.set_rigid_state(Eigen::VectorXd::Zero(v.size()), v);
}

void Run::track() {
  if (m_scene.remesh.enabled) {
    const double e = energies().mechanical();
    m_energy_min = std::min(m_energy_min, e);
    m_energy_max = std::max(m_energy_max, e);
  }
  const Eigen::MatrixX2d st = m_terms.membrane->principal_stretches(m_state.positions);
  m_step_stretch = st.col(0).maxCoeff();
  m_quality.max_principal_stretch = std::max(m_quality.max_principal_stretch, m_step_stretch);
  m_quality.min_principal_stretch = std::min(m_quality.min_principal_stretch, st.col(1).minCoeff());
  for (int v = 0; v < m_state.num_vertices(); ++v)
    m_quality.max_speed =
        std::max(m_quality.max_speed, m_state.velocities.segment<3>(3 * v).norm());
  const size_t n = m_setup.obstacles.size();
  m_quality.min_obstacle_distance.resize(n, INF);
  m_step_distance.assign(n, INF);
  for (size_t o = 0; o < n; ++o) {
    m_step_distance[o] =
        m_terms.contact->surface_distance(static_cast<int>(o), m_state.positions, m_state.time);
    m_quality.min_obstacle_distance[o] =
        std::min(m_quality.min_obstacle_distance[o], m_step_distance[o]);
  }
}

const StepStats& Run::step() {
  PAPERSIM_ASSERT(!finished(), "Run::step: the run is finished");
  const RemeshSpec& r = m_scene.remesh;
  if (r.enabled && m_step == 0) remesh_pass();
  begin_lift_bodies(m_terms, *m_integrator);
  const double t0 = m_state.time;
  // Rescue (RemeshSpec::rescue_distance): a remeshed step that has to be split finer than
  // h / 2^kRescueHalvings (a run with fewer failed solves is not affected) stops there, the
  // run turns on the obstacle criterion, remeshes from the step's start and takes the step
  // again with every split it may make. A mesh too coarse where the sheet meets an obstacle (a
  // face larger than a sphere it lands on) can leave Newton crawling at every step length.
  constexpr int kRescueHalvings = 6;
  const bool may_rescue = r.enabled && m_remesh.rescues == 0 && r.params.obstacle_distance <= 0 &&
                          r.rescue_distance > 0 && !m_setup.obstacles.empty() &&
                          m_scene.newton.max_halvings > kRescueHalvings;
  const SheetState start = may_rescue ? m_state : SheetState();
  try {
    m_last = StepStats();
    m_integrator->step(m_state, m_h, may_rescue ? kRescueHalvings : -1, m_last);
  } catch (const NumericError&) {
    if (!may_rescue) throw;
    m_totals += m_last;  // the work of the attempt
    m_state = start;
    ++m_remesh.rescues;
    remesh_pass();
    begin_lift_bodies(m_terms, *m_integrator);
    m_last = m_integrator->step(m_state, m_h);
  }
  // Plastic return mapping on the accepted step (simulation/plasticity.hpp).
  if (plasticity_enabled(m_setup.material))
    apply_plasticity(*m_terms.bending, m_state.positions, m_setup.material.yield_curvature, m_mesh);
  m_totals += m_last;
  ++m_step;
  lift_obstacles(t0);
  track();
  if (r.enabled && !finished() && (m_step == 1 || m_step % r.every == 0)) remesh_pass();
  return m_last;
}

void Run::lift_obstacles(double step_start) {
  int body = 0;
  for (size_t i = 0; i < m_setup.lifts.size(); ++i) {
    const PhysicsSetup::Lift& l = m_setup.lifts[i];
    const double t = m_state.time;
    double moved = 0;  // a coupled body's displacement over the step [m]
    if (l.lift.coupled) {
      // The step moved it with the sheet: its motion takes the displacement over the step.
      moved = m_integrator->rigid_positions()[3 * body++ + 2];
      if (std::abs(moved) >= 1e-12) {
        l.collider->motion.translate_from(step_start, t, Eigen::Vector3d(0, 0, moved), l.keyframed);
        m_scene.obstacles[l.spec].keyframes = l.collider->motion.keyframes();
      }
    }
    const Eigen::Vector3d force = m_terms.contact->obstacle_load(l.obstacle, m_state.positions);
    const double load = force.z();
    const double rise = Run::rise(l, t);
    RunQuality::LiftExtremes& q = m_quality.lifts[i];
    q.max_load = std::max(q.max_load, load);
    q.max_rise = std::max(q.max_rise, rise);
    if (l.lift.coupled) {
      m_trace(Trace::lift,
              "t %.4f lift: obstacle %d force (%.4g, %.4g, %.4g) N, rise %.4g m (coupled, %+.3g m "
              "in the step)",
              t, l.spec, force.x(), force.y(), force.z(), rise, moved);
      continue;
    }
    // Up or down at speed x clamp((F - load) / load, -1, 1) over the next step, never below the
    // keyframed path; changes below a nanometre are not made (they would only add keyframes).
    const double rate = l.lift.speed * std::clamp((load - l.lift.load) / l.lift.load, -1.0, 1.0);
    const double dz = std::max(rate * m_h, -std::max(rise, 0.0));
    m_trace(Trace::lift,
            "t %.4f lift: obstacle %d force (%.4g, %.4g, %.4g) N, rise %.4g m, next %+.3g m", t,
            l.spec, force.x(), force.y(), force.z(), rise, dz);
    if (std::abs(dz) < 1e-9) continue;
    l.collider->motion.translate_from(t, t + m_h, Eigen::Vector3d(0, 0, dz), l.keyframed);
    m_scene.obstacles[l.spec].keyframes = l.collider->motion.keyframes();
  }
}

Eigen::VectorXd Run::vertex_obstacle_distance() const {
  // The mesh a pass makes must already resolve the contact the sheet reaches before the pass
  // after next (a fall meets its obstacle at a few centimetres per step).
  return approach_distance(m_setup.obstacles, m_state.positions_matrix(),
                           m_state.velocities_matrix(), m_state.time,
                           2.0 * m_scene.remesh.every * m_h);
}

std::string Run::check_remeshed(const remesh::SheetMesh& mesh, const SheetState& state,
                                Terms& terms) {
  if (m_setup.self_contact &&
      collision::count_self_intersections(state.positions_matrix(), mesh.faces()) > 0)
    return "self-intersection";
  try {
    terms = build_terms(mesh, m_setup, &m_term_stats);
  } catch (const NumericError&) {
    // A term that cannot be built on the new mesh (a face too thin for the bending model).
    return "degenerate";
  }
  const Eigen::MatrixX2d stretches = terms.membrane->principal_stretches(state.positions);
  if (!(stretches.col(0).maxCoeff() < 1 + m_setup.material.strain_limit)) return "stretch";
  if (m_setup.material.compression_limit > 0 &&
      !(stretches.col(1).minCoeff() > 1 - m_setup.material.compression_limit))
    return "compression";
  // The veto samples a new face at its corners, edge midpoints and centroid; an obstacle's edge
  // or corner can still pass through the face between them (a gable's ridge under a large
  // face; the veto checks spheres, boxes and gables exactly, this catches the other shapes).
  // Against a polytope the barrier is finite on a pierced face, so the solver would keep it.
  if (terms.contact)
    for (int o = 0; o < static_cast<int>(m_setup.obstacles.size()); ++o)
      if (!(terms.contact->surface_distance(o, state.positions, state.time) > 0)) return "obstacle";
  return {};
}

remesh::RemeshParams Run::remesh_params() const {
  remesh::RemeshParams p = m_scene.remesh.params;
  if (m_remesh.rescues > 0 && p.obstacle_distance <= 0)
    p.obstacle_distance = m_scene.remesh.rescue_distance;
  return p;
}

remesh::RemeshState Run::remesh_state() const {
  remesh::RemeshState rs;
  rs.positions = m_state.positions_matrix();
  rs.velocities = m_state.velocities_matrix();
  if (!m_setup.obstacles.empty()) rs.obstacle_distance = vertex_obstacle_distance();
  if (m_terms.membrane->arc())
    rs.membrane_strain = m_terms.membrane->green_strains(m_state.positions);
  return rs;
}

void Run::remesh_pass() {
  auto t0 = std::chrono::steady_clock::now();
  remesh::SheetMesh mesh = m_mesh;  // a copy: the pass is undone when its result fails a check
  remesh::RemeshState rs = remesh_state();
  RemeshVetoParams vp;
  vp.strain_limit = m_setup.material.strain_limit;
  vp.obstacle_gap = 0.1 * m_setup.contact.dhat;
  vp.obstacle_reach = m_setup.contact.dhat;
  vp.self_gap = m_setup.self_contact ? 0.1 * m_setup.self_contact_params.dhat : 0.0;
  vp.time = m_state.time;
  RemeshVeto veto(m_setup.obstacles, m_mesh, rs.positions, vp);
  if (m_terms.membrane->arc())
    veto.set_vertex_curvatures(m_terms.membrane->vertex_curvatures(m_state.positions));
  const remesh::RemeshStats st = remesh::remesh(mesh, rs, remesh_params(), std::cref(veto));
  add_counts(m_remesh.refusals, st.refusals);
  m_remesh.seconds_remesh += seconds_since(t0);
  if (st.splits + st.flips + st.collapses == 0) return;
  t0 = std::chrono::steady_clock::now();
  // Renumbered as a checkpoint's reader numbers it, so that a run continued from a checkpoint
  // sums its terms in the same order as the uninterrupted run (the same state to the bit).
  std::string failure;
  try {
    mesh = mesh.rebuilt();
  } catch (const remesh::MeshError&) {
    failure = "unreadable";
  }
  SheetState state;
  state.positions = flatten(rs.positions);
  state.velocities = flatten(rs.velocities);
  state.time = m_state.time;
  state.contact_stiffness = m_state.contact_stiffness;
  state.self_contact_stiffness = m_state.self_contact_stiffness;
  Terms terms;
  if (failure.empty()) failure = check_remeshed(mesh, state, terms);
  std::unique_ptr<Integrator> integrator;
  if (failure.empty()) {
    integrator = std::make_unique<Integrator>(mesh.num_vertices(), std::move(terms.list),
                                              newton_params(), coupled_lifts());
    begin_lift_bodies(terms, *integrator);
    if (!std::isfinite(integrator->start_energy(state, m_h))) failure = "infeasible";
  }
  m_trace(Trace::remesh, "remesh t %.6f: %d splits, %d flips, %d collapses -> %d vertices%s%s",
          m_state.time, st.splits, st.flips, st.collapses, mesh.num_vertices(),
          failure.empty() ? "" : ", undone: ", failure.c_str());
  if (!failure.empty()) {
    ++m_remesh.rollbacks;
    ++m_remesh.rollback_reasons[failure];
    m_remesh.seconds_rebuild += seconds_since(t0);
    return;
  }
  const double before = energies().mechanical();
  m_pattern_changes_done += m_integrator->pattern_id();
  m_mesh = std::move(mesh);
  m_state = state;
  m_terms = std::move(terms);
  m_integrator = std::move(integrator);
  ++m_remesh.passes;
  m_remesh.splits += st.splits;
  m_remesh.flips += st.flips;
  m_remesh.collapses += st.collapses;
  const double after = energies().mechanical();
  m_remesh_energy_change += after - before;
  const double jump = std::abs(after - before);
  m_remesh.max_energy_jump = std::max(m_remesh.max_energy_jump, jump);
  const double range = m_energy_max - m_energy_min;
  if (range > 0)
    m_remesh.max_energy_jump_relative = std::max(m_remesh.max_energy_jump_relative, jump / range);
  m_trace(Trace::remesh,
          "remesh t %.6f: energy %.6g -> %.6g J (jump %.3g of the range so far, %.6g J)",
          m_state.time, before, after, range > 0 ? jump / range : 0.0, range);
  m_counts.vertices_max = std::max(m_counts.vertices_max, m_mesh.num_vertices());
  m_counts.faces_max = std::max(m_counts.faces_max, m_mesh.num_faces());
  m_remesh.seconds_rebuild += seconds_since(t0);
}

RunTally Run::tally(double wall_seconds) const {
  RunTally t;
  t.totals = m_totals;
  t.pattern_changes = m_pattern_changes_done + m_integrator->pattern_id();
  t.sheet = m_counts;
  t.terms = m_term_stats;
  t.quality = m_quality;
  t.remesh = m_remesh;
  t.energy_min = m_energy_min;
  t.energy_max = m_energy_max;
  t.wall_seconds = wall_seconds;
  return t;
}

RunResult Run::result(double wall_seconds) const {
  RunResult r;
  r.mesh = m_mesh;
  r.state = m_state;
  r.wall_seconds = wall_seconds;
  r.steps = m_step;
  r.time_step = m_h;
  r.totals = m_totals;
  r.pattern_changes = m_pattern_changes_done + m_integrator->pattern_id();
  r.sheet = m_counts;
  r.sheet.vertices = m_mesh.num_vertices();
  r.sheet.faces = m_mesh.num_faces();
  if (m_terms.contact) r.contact = m_term_stats.contact;
  if (m_terms.self_contact) r.self_contact = m_term_stats.self_contact;
  r.quality = m_quality;
  r.quality.self_intersections =
      collision::count_self_intersections(m_state.positions_matrix(), m_mesh.faces());
  if (m_terms.handles) {
    double worst = 0;
    for (int i = 0; i < m_terms.handles->size(); ++i)
      if (m_terms.handles->active(i, m_state.time - 1e-12))
        worst = std::max(worst, m_terms.handles->error(i, m_state.positions, m_state.time));
    r.quality.max_handle_error = worst;
  }
  r.energy = energies();
  if (m_scene.remesh.enabled) r.remesh = m_remesh;
  return r;
}

}  // namespace papersim::simulation
