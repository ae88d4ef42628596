#pragma once
/// Running a scene end to end: build the sheet and the incremental potential, integrate, and
/// write sheet.obj, sheet.ply, meta.json (and frames) into an output folder.
#include <array>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/run.hpp"
#include "simulation/scene.hpp"
#include "simulation/sheet_state.hpp"

namespace papersim::simulation {

/// Progress report: fraction done in [0, 1] of the steps this call runs (a resumed run counts
/// from its checkpoint) and wall seconds so far.
using ProgressFn = std::function<void(double fraction, double seconds)>;

/// What a step observer sees after each accepted step.
struct StepReport {
  int step = 0;                             ///< 1-based
  const SheetState* state = nullptr;        ///< the state after the step
  const remesh::SheetMesh* mesh = nullptr;  ///< the mesh of that state (it may change during a run)
  /// Kinetic + gravity + stretching (with the strain-limit barrier) + bending energy [J];
  /// contact and handle potentials are not included.
  double mechanical_energy = 0.0;
  /// Sum of the signed changes of the mechanical energy across the remeshing passes so far
  /// (after - before; 0 without remeshing) [J]: `mechanical_energy` less it is what the steps
  /// alone changed. Counted from the start of this process's run (not across a resume).
  double remesh_energy_change = 0.0;
  double max_stretch = 1.0;  ///< largest principal stretch at this step [-]
  /// Smallest signed distance of a sheet vertex to each obstacle (0 is the ground when the
  /// scene has one) at this step [m].
  std::vector<double> obstacle_distance;
};
using StepObserver = std::function<void(const StepReport&)>;

struct RunOptions {
  std::string out_dir;    ///< created if missing; files appear only when the run succeeds
  int frames_every = -1;  ///< overrides scene.output.frames_every when >= 0
  /// Called about once per percent of the steps, and after a step at least every
  /// `progress_every` seconds of wall time (so a run whose steps slow down still reports).
  ProgressFn progress;
  double progress_every = 30.0;                          ///< [s]
  nlohmann::json extra_meta = nlohmann::json::object();  ///< merged into meta.json
  /// Called after every step (costs one energy evaluation per step; none when unset).
  StepObserver on_step;
  /// Called after every step; may throw (e.g. common::Interrupted) to stop the run, which then
  /// leaves no output behind.
  std::function<void()> poll_stop;
  /// More files to publish with the run: name in out_dir -> content (e.g. the scene.json of a
  /// scenario). Names should be among run_output_names().
  std::vector<std::pair<std::string, std::string>> extra_files;
  /// Every `checkpoint_every` steps (0: never) the state is saved in `checkpoint_dir`
  /// (save_checkpoint), which is outside the run's output and stays when the run fails, so a
  /// run can be continued from its last checkpoint or a failure studied from just before it.
  std::string checkpoint_dir;
  int checkpoint_every = 0;  ///< at most MAX_CHECKPOINT_EVERY on the command line
  /// Continue from the checkpoint in this folder (load_checkpoint) instead of the start. The
  /// scene may differ from the checkpoint's (e.g. other solver settings at a hard spot) but not
  /// in time step or duration; meta.json's `resumed` lists what differs.
  std::string resume_from;
  /// What the run tells on stderr about its inner workings (`--trace`; off by default).
  Trace trace;
};

/// The most steps between checkpoints `papersim run --checkpoint-every` and `papersim batch
/// --checkpoint-every` take (2^30; a batch passes its value on to every sample's run).
constexpr int MAX_CHECKPOINT_EVERY = 1 << 30;

/// A saved state of a run: DIR/checkpoint.json (format, step, time, the sheet file's name, the
/// scene, what the run had counted) and the sheet file it names (PLY, doubles: positions,
/// velocities, material coordinates, plastic curvature, damage), so a continued run starts from
/// the same numbers and reports the whole run.
struct Checkpoint {
  int step = 0;
  double time = 0.0;  ///< [s]
  remesh::SheetMesh mesh;
  SheetState state;
  nlohmann::json scene;           ///< scene_to_json of the run that saved it
  std::optional<RunTally> tally;  ///< absent in checkpoints that do not have `run`
  /// The self-contact term's Hessian pattern pairs (Run::self_contact_pattern); empty when it
  /// had none, or in checkpoints written before it was saved.
  std::vector<std::array<int, 3>> self_contact_pattern;
  /// The factorisation the next step may start from (Run::reusable_factor), from the file
  /// `reusable_factor.file` names; absent when the run had none to pass on, or in checkpoints
  /// written before it was saved.
  std::optional<ReusableFactor> factor;
};

/// Writes the checkpoint atomically: the sheet file (and the factorisation's matrix, when
/// `factor` is given: checkpoint_NNNNNNNN.factor, the entries as raw doubles after a header) under
/// new names, then checkpoint.json naming them, then the previous ones are removed; a run
/// stopped at any moment leaves a complete checkpoint (the new or the previous one).
/// @throw common::OutputError when a file cannot be written
void save_checkpoint(const std::string& dir, const Scene& scene, int step,
                     const remesh::SheetMesh& mesh, const SheetState& state,
                     const RunTally* tally = nullptr,
                     const std::vector<std::array<int, 3>>* self_contact_pattern = nullptr,
                     const ReusableFactor* factor = nullptr);

/// The checkpoint's `run` object, and back (non-finite extremes are written as null).
/// @throw nlohmann::json::exception for a malformed object
nlohmann::json tally_to_json(const RunTally& t);
RunTally tally_from_json(const nlohmann::json& j);

/// @throw SceneError naming the file and what is wrong (missing, not a checkpoint, bad sheet)
Checkpoint load_checkpoint(const std::string& dir);

/// meta.json of a finished run: the scene, provenance, run statistics, quality and energies,
/// with `extra` merged in at the top level.
nlohmann::json meta_json(const Scene& scene, const RunResult& result,
                         const nlohmann::json& extra = nlohmann::json::object());

/// Simulate `scene`; with a non-empty out_dir, write the outputs there (published together:
/// the folder then holds the files of this run only, see run_output_names()).
/// @throw SceneError for a scene that cannot be built, NumericError when a step fails,
///        common::OutputError when outputs cannot be written, and whatever poll_stop throws.
///        On failure nothing is left in out_dir.
RunResult run_scene(const Scene& scene, const RunOptions& options);

/// Program version (the CMake project version).
const char* version();

}  // namespace papersim::simulation
