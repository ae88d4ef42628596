#pragma once
/// One simulation run and the one place that composes the incremental potential.
///
/// A run owns the sheet (a mesh whose topology may change between steps), its state, the
/// obstacles (built once per scene, never per mesh), the handles (material points with world
/// anchors fixed at the start), the integrator and the run's statistics. The energy terms are
/// built for a given mesh by build_terms(), which the CLI, the validation programs and the tests
/// all use; a run rebuilds them whenever its mesh changes, and the statistics, kept in the run,
/// survive the rebuild.
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/energies/contact_energy.hpp"
#include "simulation/energies/handle_energy.hpp"
#include "simulation/energies/lift_body_energy.hpp"
#include "simulation/energies/membrane_energy.hpp"
#include "simulation/energies/self_contact_energy.hpp"
#include "simulation/integrator.hpp"
#include "simulation/scene.hpp"
#include "simulation/sheet_state.hpp"

namespace papersim::simulation {

/// World positions of the sheet at the start of a run as a function of the material point
/// (barycentric interpolation in the initial mesh), so that a clamp holds a vertex that
/// remeshing inserts where that point was at the start.
class InitialPlacement {
 public:
  InitialPlacement() = default;
  /// @param positions 3N world positions of `mesh`'s vertices [m]
  InitialPlacement(const remesh::SheetMesh& mesh, const Eigen::VectorXd& positions);
  /// World position of material point p at the start [m].
  /// @throw SceneError when p lies outside the sheet.
  Eigen::Vector3d operator()(const Eigen::Vector2d& p) const;

 private:
  std::shared_ptr<const remesh::SheetMesh> m_mesh;
  Eigen::VectorXd m_positions;
};

/// The rotation of SheetSpec::rotation_deg: x, y, z Euler angles [deg] applied in that order.
Eigen::Matrix3d sheet_rotation(const Eigen::Vector3d& deg);

/// The sheet of a scene in its initial pose.
/// @throw SceneError, remesh::IoError, remesh::MeshError
void initial_sheet(const Scene& scene, remesh::SheetMesh& mesh, SheetState& state);

/// Everything besides the mesh that the incremental potential is built from; fixed for a run.
struct PhysicsSetup {
  Material material;
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.8);  ///< [m/s^2]
  std::vector<AnchoredHandle> handles;
  /// Each clamp holds every vertex whose material point lies in its region at the world
  /// position that point had at the start (`placement`); a clamp never released also holds the
  /// slopes of the faces inside it (Morley model). Re-evaluated on every mesh.
  std::vector<ClampSpec> clamps;
  InitialPlacement placement;  ///< needed when there are clamps
  /// Obstacles, the ground first when there is one; shared by every rebuild of the terms.
  std::vector<std::shared_ptr<const collision::Collider>> obstacles;
  ContactParams contact;  ///< stiffness resolved (> 0)
  /// Raise the contact stiffness at each step start so an impact is stopped within the
  /// barrier (ObstacleContactEnergy::set_impact_density).
  bool impact_rule = true;
  bool self_contact = false;
  SelfContactParams self_contact_params;  ///< dhat and stiffness resolved (> 0)
  /// Obstacles that yield upwards (collision::LiftSpec). Their collider, shared with
  /// `obstacles`, is the one part of the setup a run changes: it extends the collider's motion
  /// after every step (Run::step).
  struct Lift {
    int obstacle = 0;  ///< index in `obstacles`
    int spec = 0;      ///< index in Scene::obstacles
    collision::LiftSpec lift;
    std::shared_ptr<collision::Collider> collider;
    collision::RigidMotion keyframed;  ///< the motion the scene gives it
  };
  std::vector<Lift> lifts;
};

/// The physics of a scene: obstacles built, contact stiffness resolved, handles anchored at the
/// sheet's initial world positions.
/// @throw SceneError for an obstacle that cannot be built or a handle outside the sheet.
PhysicsSetup physics_setup(const Scene& scene, const remesh::SheetMesh& mesh,
                           const SheetState& initial);

/// Counters kept by the terms of a run (owned by the run, see ContactStatistics).
struct TermStatistics {
  ContactStatistics contact;
  SelfContactStatistics self_contact;
};

/// The incremental potential of one mesh, and typed views of the terms the run reports on.
struct Terms {
  std::vector<std::unique_ptr<EnergyTerm>> list;  ///< handed to the Integrator
  Eigen::VectorXd masses;                         ///< lumped vertex masses (#V) [kg]
  MembraneEnergy* membrane = nullptr;
  BendingEnergy* bending = nullptr;
  HandleEnergy* handles = nullptr;            ///< null without handles or clamps
  ObstacleContactEnergy* contact = nullptr;   ///< null without obstacles
  SelfContactEnergy* self_contact = nullptr;  ///< null when self-contact is off
  /// Coupled lifting obstacles (collision::LiftSpec::coupled), in the order of PhysicsSetup::lifts
  /// that are coupled; the k-th is rigid block #V + k of the integrator.
  std::vector<LiftBodyEnergy*> lift_bodies;
};

/// Builds the terms (inertia, damping, gravity, stretching with the strain limit, bending,
/// handles and clamps, obstacle contact and friction, self-contact) for `mesh` under `setup`.
/// @param statistics where contact terms count; null: counters of their own
/// @throw SceneError when a clamp holds no vertex or a handle lies outside the sheet.
Terms build_terms(const remesh::SheetMesh& mesh, const PhysicsSetup& setup,
                  TermStatistics* statistics = nullptr);

/// Energies of a state [J]: kinetic, gravity, stretching (with the strain-limit barrier) and
/// bending; contact and handle potentials are not included.
struct EnergyBreakdown {
  double stretch = 0, bend = 0, gravity = 0, kinetic = 0;
  double mechanical() const { return stretch + bend + gravity + kinetic; }
};
EnergyBreakdown energy_breakdown(const Terms& terms, const Eigen::Vector3d& gravity,
                                 const SheetState& state);

/// Quality figures of a run (running extremes over every step, self-intersections at the end).
struct RunQuality {
  double max_principal_stretch = 1.0;  ///< [-]
  double min_principal_stretch = 1.0;  ///< [-]
  double strain_limit = 0.0;           ///< the material's limit [-]
  double max_speed = 0.0;              ///< largest vertex speed [m/s]
  /// Smallest signed distance of the sheet's surface to each obstacle (the ground first) [m].
  std::vector<double> min_obstacle_distance;
  int self_intersections = 0;              ///< intersecting non-adjacent triangle pairs at the end
  std::optional<double> max_handle_error;  ///< [m], when the scene has handles
  /// Per obstacle that yields upwards (PhysicsSetup::lifts, in that order): the largest upward
  /// load the sheet pressed it with after a step [N] and the largest height it rose above its
  /// keyframed path [m].
  struct LiftExtremes {
    int obstacle = 0;  ///< index in Scene::obstacles
    double max_load = 0.0, max_rise = 0.0;
  };
  std::vector<LiftExtremes> lifts;
};

/// Vertex and face counts of the sheet over a run.
struct MeshCounts {
  int vertices_start = 0, faces_start = 0;
  int vertices = 0, faces = 0;  ///< at the end
  int vertices_max = 0, faces_max = 0;
};

/// Remeshing over a run (Scene::remesh).
struct RemeshTotals {
  int passes = 0;     ///< remeshing passes that changed the mesh and were kept
  int rollbacks = 0;  ///< passes undone because their result failed a check (by reason below)
  /// Failed steps taken again after a pass with the obstacle criterion turned on
  /// (RemeshSpec::rescue_distance, Run::step): 0 or 1; after one, the criterion stays on.
  int rescues = 0;
  std::map<std::string, int> rollback_reasons;
  int splits = 0, flips = 0, collapses = 0;  ///< edits of the kept passes
  std::map<std::string, int> refusals;  ///< edits refused, by reason ("veto: ..." from the run)
  double seconds_remesh = 0.0;          ///< wall time in the remeshing passes [s]
  double seconds_rebuild = 0.0;  ///< wall time in checking the result and rebuilding the terms [s]
  /// Largest change of the mechanical energy (EnergyBreakdown) across a kept pass [J], and that
  /// change relative to the range the mechanical energy spanned over the run until then [-].
  double max_energy_jump = 0.0;
  double max_energy_jump_relative = 0.0;
};

/// What a finished run measured; turned into meta.json only at the edge (meta_json).
struct RunResult {
  remesh::SheetMesh mesh;
  SheetState state;
  double wall_seconds = 0.0;
  int steps = 0;
  double time_step = 0.0;    ///< [s]
  StepStats totals;          ///< summed over the steps
  long pattern_changes = 0;  ///< Hessian pattern rebuilds (dynamic terms)
  MeshCounts sheet;
  std::optional<ContactStatistics> contact;
  std::optional<SelfContactStatistics> self_contact;
  RunQuality quality;
  EnergyBreakdown energy;              ///< at the end
  std::optional<RemeshTotals> remesh;  ///< when the scene remeshes
};

/// What a run has counted and measured over its steps so far: the sums and running extremes of
/// RunResult, without the figures measured at the end (self-intersections, handle error,
/// energies). Saved with a checkpoint (save_checkpoint) so that a run continued from it reports
/// the whole run.
struct RunTally {
  StepStats totals;
  long pattern_changes = 0;
  MeshCounts sheet;  ///< at the start and at most
  TermStatistics terms;
  RunQuality quality;  ///< the running extremes
  RemeshTotals remesh;
  double energy_min = INF, energy_max = -INF;  ///< mechanical energy's range over the run [J]
  double wall_seconds = 0.0;                   ///< wall time of the run so far [s]
};

/// One run of a scene, advanced a step at a time.
class Run {
 public:
  /// Builds the sheet in its initial pose, the obstacles and the terms; checks that the sheet
  /// starts outside every obstacle and, with self-contact, outside itself.
  /// @throw SceneError (also for a sheet read from `sheet.mesh` on which the terms cannot be
  ///        built, such as a bending system that cannot be factored), remesh::IoError,
  ///        remesh::MeshError
  /// `trace`: what the run and its parts tell when asked (Trace; off by default).
  explicit Run(const Scene& scene, const Trace& trace = {});
  ~Run();
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;

  /// Continue from a saved state (a checkpoint of a run of this scene): the mesh with its
  /// plastic state, positions, velocities and time after `step` steps. The handles keep their
  /// anchors from the scene's initial sheet. The run's statistics and quality extremes continue
  /// from `tally` (what the saved run had counted, Run::tally), else they count from here on.
  /// Checked like a start (outside every obstacle, free of self-intersection).
  /// @throw SceneError when the state does not fit the mesh, the step is out of range or its
  ///        time is not step x time_step, the terms cannot be built on the mesh, the state
  ///        fails a check, or `tally` is for another number of obstacles
  /// `saved`: the scene the checkpoint was saved with (Run::scene() of that run); obstacles that
  /// yield upwards continue on the motion saved there. `self_contact_pattern`: the saved run's
  /// (self_contact_pattern()), so that the continued run factors the matrices it would have.
  void resume(const remesh::SheetMesh& mesh, const SheetState& state, int step,
              const Scene* saved = nullptr, const RunTally* tally = nullptr,
              const std::vector<std::array<int, 3>>* self_contact_pattern = nullptr);
  /// The self-contact term's Hessian pattern pairs (SelfContactEnergy::pattern_pairs; empty
  /// without self-contact), for a checkpoint.
  std::vector<std::array<int, 3>> self_contact_pattern() const;
  /// The factorisation the next step may start from (Integrator::reusable_factor), for a
  /// checkpoint; none unless the scene reuses factorisations (`solver.max_factor_reuse`) and the
  /// last step was quiet.
  std::optional<ReusableFactor> reusable_factor() const;
  /// After resume(): lets the next step start from the saved run's factorisation, so a run of
  /// the same scene continued from a checkpoint takes the steps the uninterrupted run takes.
  /// @throw SceneError when it does not fit this run's matrix or cannot be factored
  ///        (Integrator::adopt_factor)
  void adopt_factor(const ReusableFactor& factor);

  /// Advance by one time step of the scene, remeshing before the first step, after it and then
  /// after every `remesh.every` steps when the scene remeshes. A remeshed run whose step fails
  /// at h / 64 while the obstacle criterion is off turns it on (`remesh.rescue_distance`),
  /// remeshes and takes the step again from its start with every split the solver allows, once
  /// per run (RemeshTotals::rescues).
  /// @throw NumericError when the step fails (again).
  const StepStats& step();
  bool finished() const { return m_step >= m_steps; }
  int steps_done() const { return m_step; }
  int steps_total() const { return m_steps; }
  double time_step() const { return m_h; }

  /// The scene; the keyframes of obstacles that yield upwards include their rises so far.
  const Scene& scene() const { return m_scene; }
  const remesh::SheetMesh& mesh() const { return m_mesh; }
  const SheetState& state() const { return m_state; }
  const Terms& terms() const { return m_terms; }
  EnergyBreakdown energies() const { return energy_breakdown(m_terms, m_setup.gravity, m_state); }
  /// Largest principal stretch at the current state [-].
  double step_stretch() const { return m_step_stretch; }
  /// Smallest surface distance to each obstacle at the current state [m].
  const std::vector<double>& step_obstacle_distance() const { return m_step_distance; }
  /// Sum of the signed changes of the mechanical energy across the remeshing passes this Run
  /// kept (after - before) [J]: the mechanical energy less it is what the steps alone changed.
  double remesh_energy_change() const { return m_remesh_energy_change; }

  /// What a remeshing pass sizes the current mesh by: positions, velocities, each vertex's
  /// obstacle distance (with obstacles) and, under the arc membrane, the strain it measures (a
  /// face bent smoothly is not compressed although its chords are shorter).
  remesh::RemeshState remesh_state() const;

  /// The result so far (final figures measured at the current state).
  RunResult result(double wall_seconds) const;
  /// The counts and extremes so far, with `wall_seconds` of wall time (the run's so far).
  RunTally tally(double wall_seconds) const;

 private:
  /// Builds the terms and the integrator for the current mesh.
  void rebuild();
  /// @throw SceneError when the current state is inside an obstacle or, with self-contact,
  ///        intersects itself (`what`: "starts" or "resumes")
  void check_state(const std::string& what) const;
  void track();
  /// Moves each obstacle that yields upwards over the next step by the load the sheet presses it
  /// with now (collision::LiftSpec); a coupled one by the displacement the step solved for
  /// (`step_start`: the time the step began [s]). Records the loads and rises.
  void lift_obstacles(double step_start);
  /// Rise of lift l above its keyframed path at time t [m].
  static double rise(const PhysicsSetup::Lift& l, double t);
  /// Readies the coupled lifting obstacles of `terms` for a step from the current state: their
  /// rises, and their displacement (zero: the motion holds it) and vertical velocity (that of
  /// the last step) as the integrator's rigid state.
  void begin_lift_bodies(Terms& terms, Integrator& integrator) const;
  /// Number of coupled lifting obstacles (rigid blocks of the integrator).
  int coupled_lifts() const;
  /// One remeshing pass: kept when the new mesh passes every check (no self-intersection,
  /// stretch within the limit, finite energy), undone otherwise.
  void remesh_pass();
  /// The sizing parameters of a pass: the scene's, with the obstacle criterion on at
  /// `remesh.rescue_distance` after a rescue (Run::step).
  remesh::RemeshParams remesh_params() const;
  /// Why a remeshed sheet cannot be used (empty when it can); builds its terms into `terms`.
  std::string check_remeshed(const remesh::SheetMesh& mesh, const SheetState& state, Terms& terms);
  /// Smallest distance of each vertex to any obstacle at the current state, less the distance it
  /// closes in 2 `remesh.every` steps at its current speed towards the obstacle [m] (#V): what
  /// the obstacle-proximity sizing refines by.
  Eigen::VectorXd vertex_obstacle_distance() const;
  /// The scene's solver parameters with the run's trace.
  NewtonParams newton_params() const;

  Scene m_scene;
  Trace m_trace;
  remesh::SheetMesh m_mesh;
  SheetState m_state;
  PhysicsSetup m_setup;
  Terms m_terms;
  std::unique_ptr<Integrator> m_integrator;
  TermStatistics m_term_stats;
  StepStats m_totals, m_last;
  long m_pattern_changes_done = 0;  // by integrators already replaced
  MeshCounts m_counts;
  RunQuality m_quality;
  RemeshTotals m_remesh;
  double m_energy_min = INF, m_energy_max = -INF;  // mechanical energy's range over the run [J]
  double m_remesh_energy_change = 0.0;             // remesh_energy_change() [J]
  double m_step_stretch = 1.0;
  std::vector<double> m_step_distance;
  int m_step = 0, m_steps = 0;
  double m_h = 0.0;
};

}  // namespace papersim::simulation
