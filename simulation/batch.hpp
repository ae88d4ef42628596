#pragma once
/// `papersim batch`: a dataset of simulated sheets, one child `papersim run` per sample.
///
/// Layout under DATASET: meshes/<scenario>/<seed / 1000>/<seed>/ holds scene.json, sheet.obj,
/// sheet.ply, meta.json and (when the metrics command is built) metrics.json; manifest.jsonl
/// has one row per finished sample, failures.jsonl one per failed attempt (batch/runner.hpp).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "batch/runner.hpp"
#include "simulation/scene.hpp"

namespace papersim::simulation {

/// One sample to draw: a scenario, a seed and scene overrides applied after the draw.
struct SampleDraw {
  std::string scenario;
  std::uint64_t seed = 0;
  /// Dotted scene keys to values, e.g. {"duration": 0.1, "sheet.edge_length": 0.02}; shared by
  /// the draws of one scenario (a batch draws up to ten million); null: none.
  std::shared_ptr<const nlohmann::json> overrides;
};

/// A mix of scenarios: each seed draws one scenario with probability weight / sum of weights.
struct Mix {
  std::vector<std::string> scenarios;
  std::vector<double> weights;                       ///< > 0 each [-]
  std::vector<nlohmann::json> overrides;             ///< per scenario, over `common`
  nlohmann::json common = nlohmann::json::object();  ///< overrides for every scenario
};

/// Parse a mix file:
///   {"scenarios": {"pull": 2, "fall-sphere": {"weight": 1, "set": {"duration": 0.5}}},
///    "set": {"sheet.edge_length": 0.01}}
/// @throw SceneError naming the file and the key (unknown key or scenario, weight <= 0)
Mix mix_from_json(const nlohmann::json& j, const std::string& source);
/// @throw SceneError when the file is missing or not JSON, or as mix_from_json
Mix load_mix(const std::string& path);

/// The scenario a mix gives `seed` (a fixed hash of the seed, so any shard agrees).
std::size_t mix_pick(const Mix& mix, std::uint64_t seed);

/// "key=value" pairs into {key: value}; the value is read as JSON, else taken as a string.
/// @throw SceneError naming the pair when it has no '=' or an empty key
nlohmann::json parse_overrides(const std::vector<std::string>& pairs);

/// `scene` with dotted-key overrides applied ("sheet.edge_length", "obstacles.0.radius"),
/// checked like a scene file. `source` names where the overrides come from in errors.
/// @throw SceneError naming the key when it is not a key of the scene, or a value is invalid
Scene apply_overrides(const Scene& scene, const nlohmann::json& overrides,
                      const std::string& source);

/// Which samples a batch makes.
struct MeshBatchSelection {
  std::vector<std::string> scenarios;  ///< every scenario for every seed (when no mix)
  std::string mix_path;                ///< or one scenario per seed from this mix file
  /// Inclusive seed ranges, drawn in this order (parse_seeds); none may overlap another.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> seeds;
  nlohmann::json overrides = nlohmann::json::object();  ///< --set, over the mix's
  batch::Shard shard;  ///< only the samples at these positions of the whole selection are made
};

/// The most samples one batch command draws (a batch holds each in about 110 bytes; ten million
/// start in 4.4-5.2 s, docs/batch.md).
inline constexpr std::uint64_t MAX_BATCH_SAMPLES = 10'000'000;

/// The samples of a selection, seeds in order (and scenarios in the given order per seed), those
/// of `selection.shard` alone. Checks every distinct scenario and override set once by drawing
/// its first seed (also when it falls in another shard).
/// @throw SceneError for an unknown scenario, a bad mix file, an invalid override or more than
/// MAX_BATCH_SAMPLES samples
std::vector<SampleDraw> draw_samples(const MeshBatchSelection& selection);

/// draw_samples(selection).size(), without keeping the draws (for a Slurm script).
/// @throw SceneError as draw_samples
std::size_t count_samples(const MeshBatchSelection& selection);

/// The runner tasks of `draws`: key and folder meshes/<scenario>/<seed/1000>/<seed>.
batch::TaskList mesh_tasks(const std::vector<SampleDraw>& draws);
/// The same as mesh_tasks(draw_samples(selection)), without keeping the draws (ten million of
/// them are 0.59 GB). `progress`, when given, hears the samples drawn every 65,536 ("drawing
/// the samples"; ten million take seconds).
/// @throw SceneError as draw_samples
batch::TaskList mesh_tasks(const MeshBatchSelection& selection,
                           const batch::StepProgressFn& progress = {});

/// Hooks of a mesh batch: prepare writes scene.json, the commands are `papersim run` (and
/// `papersim metrics --json` into metrics.json when with_metrics), the manifest row carries
/// the run and quality figures of meta.json and metrics.json.
/// @param papersim the papersim executable the children run
/// @param checkpoint_every > 0: each run saves a checkpoint every this many steps in
///        ROOT/.checkpoints/<task>/ (checkpoint_folder), and an attempt of a sample whose
///        checkpoint is there continues from it when the sample's scene.json is the one the
///        checkpoint was started with (else the checkpoint is discarded and the run starts
///        over); the folder is removed once the sample's outputs passed their checks (with or
///        without checkpoint_every, so one an earlier run left does not stay). A run
///        continued so ends in the uninterrupted run's state to the bit (remeshed runs too), so
///        the sample's files equal an uninterrupted one's but for meta.json's wall times and its
///        `resumed` record.
batch::BatchSpec mesh_batch_spec(const std::filesystem::path& root,
                                 const std::filesystem::path& papersim, bool with_metrics,
                                 int checkpoint_every = 0);

/// ROOT/.checkpoints/<task key as a file name>/: where a mesh batch keeps a sample's checkpoint.
std::filesystem::path checkpoint_folder(const std::filesystem::path& root, const batch::Task& task);

/// The manifest fields of a finished sample folder: vertices, Newton iterations, steps,
/// simulation wall time, largest stretch, closest obstacle distance, self-intersections and,
/// from metrics.json, crease length and the integral of |K|.
/// @throw std::runtime_error naming the file when meta.json cannot be read, is not JSON or lacks
///        its "run", "quality" or "sheet" object, or metrics.json is not the metrics' JSON
nlohmann::json mesh_manifest_fields(const std::filesystem::path& sample_dir);

/// Parse "A-B" or "A" into an inclusive seed range; a seed has at most 18 digits.
/// @throw SceneError naming --seeds when the text is not of that form, a seed is longer or B < A
std::pair<std::uint64_t, std::uint64_t> parse_seed_range(const std::string& text);

/// Parse a comma list of "A-B" or "A" (e.g. "3,7,12-13") into inclusive seed ranges, in order.
/// @throw SceneError naming --seeds when a part is not of that form or two parts overlap
std::vector<std::pair<std::uint64_t, std::uint64_t>> parse_seeds(const std::string& text);

}  // namespace papersim::simulation
