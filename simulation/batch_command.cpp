#include "simulation/batch_command.hpp"

#include <CLI/CLI.hpp>
#include <ostream>
#include <sstream>

#include "batch/dataset_stats.hpp"
#include "batch/slurm.hpp"
#include "common/cli_checks.hpp"
#include "common/exit_status.hpp"
#include "simulation/batch.hpp"
#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"

namespace papersim::simulation {
namespace fs = std::filesystem;

namespace {

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  std::string part;
  while (std::getline(s, part, ','))
    if (!part.empty()) out.push_back(part);
  return out;
}

/// The same batch as a command line for the Slurm script: absolute paths, no --shard / --jobs.
std::vector<std::string> shard_command(const BatchCommand& c) {
  std::vector<std::string> cmd{batch::self_executable().string(),
                               "batch",
                               "--out",
                               fs::absolute(c.out).string(),
                               "--seeds",
                               c.seeds,
                               "--quiet"};
  if (!c.scenarios.empty()) cmd.insert(cmd.end(), {"--scenarios", c.scenarios});
  if (!c.mix.empty()) cmd.insert(cmd.end(), {"--mix", fs::absolute(c.mix).string()});
  for (const auto& s : c.set) cmd.insert(cmd.end(), {"--set", s});
  if (c.checkpoint_every > 0)
    cmd.insert(cmd.end(), {"--checkpoint-every", std::to_string(c.checkpoint_every)});
  if (c.common.time_limit > 0)
    cmd.insert(cmd.end(), {"--time-limit", std::to_string(c.common.time_limit)});
  if (c.common.retry_failed) cmd.push_back("--retry-failed");
  return cmd;
}

int run_mesh_batch(const BatchCommand& c, bool with_metrics, std::ostream& out, std::ostream& err) {
  batch::check_dataset_folder(c.out, "--out");
  MeshBatchSelection sel;
  sel.scenarios = split_commas(c.scenarios);
  sel.mix_path = c.mix;
  sel.seeds = parse_seeds(c.seeds);
  sel.overrides = parse_overrides(c.set);
  const batch::Shard shard = batch::cli_shard(c.common);  // a malformed --shard is refused here
  if (c.common.slurm_shards == 0) sel.shard = shard;      // the script's line counts them all
  if (c.common.slurm_shards > 0) {
    const std::size_t samples = count_samples(sel);  // checks every option first
    const batch::SlurmScript script =
        batch::write_slurm_script(c.out, "papersim-batch", shard_command(c), c.common, samples);
    out << batch::slurm_written_text(script, c.common, samples, "samples");
    return 0;
  }
  batch::keep_running_without_readers();
  // Checks every option first.
  const batch::TaskList tasks =
      mesh_tasks(sel, batch::cli_step_printer(c.common, err, "papersim batch"));
  const batch::BatchSpec spec =
      mesh_batch_spec(c.out, batch::self_executable(), with_metrics, c.checkpoint_every);
  const batch::BatchSummary s = batch::run_cli_batch(tasks, spec, c.common, err, "papersim batch");
  out << batch::summary_line(s, c.out, spec) << '\n';
  if (s.interrupted) return 130;
  return s.done == s.total ? 0 : 1;
}

/// A line on `err` every 5 s of reading a dataset's manifests (none for a shorter read): the
/// megabytes read of all, elapsed time and ETA (batch::step_printer).
batch::ReadProgress read_printer(std::ostream& err, bool quiet, const std::string& dataset) {
  if (quiet) return {};
  return [step = batch::step_printer(err, false, "papersim dataset-stats"),
          what = "reading " + dataset](std::uintmax_t read, std::uintmax_t total) {
    step(what, static_cast<double>(read) / 1e6, static_cast<double>(total) / 1e6, "MB");
  };
}

int run_stats(const BatchCommand& c, std::ostream& out, std::ostream& err) {
  try {
    const auto parts = batch::read_dataset(c.dataset, read_printer(err, c.stats_quiet, c.dataset));
    batch::write_dataset_report(out, parts);
    if (!c.plots.empty()) {
      const auto files = batch::write_dataset_plots(c.plots, parts);
      out << "wrote " << files.size() << " plots in " << c.plots << '\n';
    }
    return 0;
  } catch (const batch::DatasetError& e) {
    err << "papersim dataset-stats: " << e.what() << '\n';
    return common::EXIT_BAD_INPUT;
  } catch (const batch::PlotsOutputError& e) {
    err << "papersim dataset-stats: " << e.what() << '\n';
    return common::EXIT_OUTPUT;
  } catch (const batch::GnuplotError& e) {
    err << "papersim dataset-stats: " << e.what() << '\n';
    return common::EXIT_EXTERNAL;
  }
}

}  // namespace

void add_batch_subcommands(CLI::App& app, BatchCommand& c) {
  c.batch = app.add_subcommand(
      "batch",
      "Make a dataset: one child process per sample, --jobs at once; resumable (run the same "
      "command again), failures recorded and skipped, at most 10,000,000 samples per command. "
      "Writes "
      "DATASET/meshes/<scenario>/<seed/1000>/<seed>/, manifest.jsonl and failures.jsonl. Exit "
      "status 1 "
      "when a sample failed (failures.jsonl); a full disk stops the batch with status 5 and "
      "records nothing; a finished sample without its manifest row whose row cannot be made "
      "from its folder (meta.json missing or damaged) stops it with status 2, naming the folder "
      "(docs/batch.md).");
  c.batch->add_option("--out", c.out, "dataset folder")->required()->check(common::non_empty());
  c.batch->add_option(
      "--scenarios", c.scenarios, "comma list of scenarios; every one for every seed (" + [] {
        std::string s;
        for (const auto& n : scenario_names()) s += (s.empty() ? "" : ", ") + n;
        return s;
      }() + ")");
  c.batch->add_option("--mix", c.mix,
                      "JSON mix file instead: {\"scenarios\": {NAME: WEIGHT or {\"weight\": W, "
                      "\"set\": {...}}}, \"set\": {...}}; each seed draws one scenario");
  c.batch
      ->add_option(
          "--seeds", c.seeds,
          "seeds: a range A-B (inclusive), one seed A, or a comma list of both (e.g. 3,7,12-13)")
      ->required();
  c.batch->add_option("--set", c.set,
                      "scene override KEY=VALUE after the draw (dotted scene keys, e.g. "
                      "duration=0.2 sheet.edge_length=0.02); repeatable");
  c.batch
      ->add_option(
          "--checkpoint-every", c.checkpoint_every,
          "save each sample's state every K steps in DATASET/.checkpoints/ (0: never); a sample "
          "stopped by an interruption, --time-limit or a killed job continues from it when run "
          "again (with --retry-failed for a recorded failure), to the same mesh; the progress line "
          "then shows how far "
          "the running samples are, and an ETA from that before any sample has ended")
      ->check(CLI::Range(0, MAX_CHECKPOINT_EVERY))
      ->capture_default_str();
  batch::add_batch_cli_options(c.batch, c.common);
  c.stats =
      app.add_subcommand("dataset-stats",
                         "Counts per scenario, failure rate by reason, run-time and quality "
                         "distributions of a dataset, from its manifests (no mesh is opened).");
  c.stats->add_option("dataset", c.dataset, "dataset folder")->required();
  c.stats->add_option("--plots", c.plots, "also write histograms (SVG, gnuplot) into this folder");
  c.stats->add_flag("--quiet", c.stats_quiet,
                    "no progress on stderr (otherwise a line every 5 s while the manifests are "
                    "read: MB read, ETA)");
}

int run_batch_subcommand(const BatchCommand& c, bool with_metrics, std::ostream& out,
                         std::ostream& err) {
  if (c.stats->parsed()) return run_stats(c, out, err);
  try {
    return run_mesh_batch(c, with_metrics, out, err);
  } catch (const SceneError& e) {  // a bad option or override: name it, no sample has run
    err << "papersim batch: " << e.what() << '\n';
    return 2;
  } catch (const std::invalid_argument& e) {
    err << "papersim batch: " << e.what() << '\n';
    return 2;
  }
}

}  // namespace papersim::simulation
