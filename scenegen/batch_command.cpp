#include "scenegen/batch_command.hpp"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <ostream>
#include <tuple>

#include "batch/slurm.hpp"
#include "common/cli_checks.hpp"
#include "common/errors.hpp"
#include "scenegen/errors.hpp"
#include "scenegen/job.hpp"
#include "scenegen/limits.hpp"
#include "scenegen/passes.hpp"
#include "scenegen/pov_writer.hpp"

namespace papersim::scenegen {
namespace fs = std::filesystem;

namespace {

/// The same batch as a command line for the Slurm script: absolute paths, no --shard / --jobs, the
/// meshes from `mesh_list`.
std::vector<std::string> shard_command(const RenderBatchCommand& c, const fs::path& mesh_list) {
  const RenderBatchOptions& r = c.render;
  std::vector<std::string> cmd{batch::self_executable().string(),
                               "batch",
                               fs::absolute(c.dataset).string(),
                               "--mesh-list",
                               fs::absolute(mesh_list).string(),
                               "--views",
                               std::to_string(r.views),
                               "--size",
                               r.size,
                               "--quality",
                               r.quality,
                               "--passes",
                               r.passes,
                               "--threads",
                               std::to_string(r.threads),
                               "--quiet"};
  if (r.flip) cmd.push_back("--flip");
  if (r.dpi > 0) cmd.insert(cmd.end(), {"--dpi", std::to_string(r.dpi)});
  if (!r.documents_dir.empty())
    cmd.insert(cmd.end(), {"--documents", fs::absolute(r.documents_dir).string()});
  if (!r.backgrounds_dir.empty())
    cmd.insert(cmd.end(), {"--backgrounds", fs::absolute(r.backgrounds_dir).string()});
  if (c.common.time_limit > 0)
    cmd.insert(cmd.end(), {"--time-limit", std::to_string(c.common.time_limit)});
  if (c.common.retry_failed) cmd.push_back("--retry-failed");
  return cmd;
}

/// A line on `err` every 5 s of a walk over the dataset's mesh folders (none for a shorter one):
/// folders done, meshes found, elapsed time and ETA.
ListProgress walk_printer(std::ostream& err, bool quiet, const std::string& dataset) {
  if (quiet) return {};
  const auto start = std::chrono::steady_clock::now();
  auto last = start;
  return [&err, dataset, start, last](std::size_t done, std::size_t buckets,
                                      std::size_t meshes) mutable {
    const auto now = std::chrono::steady_clock::now();
    if (now - last < std::chrono::seconds(5)) return;
    last = now;
    const double t = std::chrono::duration<double>(now - start).count();
    err << "scenegen batch: listing " << (fs::path(dataset) / "meshes").string() << ": " << done
        << " of " << buckets << " folders, " << meshes << " meshes, " << std::lround(t)
        << " s, ETA "
        << std::lround(t / static_cast<double>(done) * static_cast<double>(buckets - done)) << " s"
        << std::endl;
  };
}

/// Bad values fail here, before any view runs (scenegen render would reject them per view).
void check_options(const RenderBatchCommand& c) {
  if (!fs::is_directory(c.dataset)) throw InputError("dataset '" + c.dataset + "' is not a folder");
  if (!fs::is_directory(fs::path(c.dataset) / "meshes"))
    throw InputError("dataset '" + c.dataset +
                     "' has no meshes/ folder (run papersim batch --out " + c.dataset + " first)");
  try {
    parse_passes(c.render.passes);
  } catch (const InputError& e) {
    throw InputError(std::string("--passes: ") + e.what());
  }
  try {
    parse_quality(c.render.quality);
  } catch (const InputError& e) {
    throw InputError(std::string("--quality: ") + e.what());
  }
  int width = 0, height = 0;  // the limits scenegen render checks, so that no view fails on them
  parse_image_size(c.render.size, width, height, "--size", false, 8);
  if (!c.mesh_list.empty() && !fs::is_regular_file(c.mesh_list))
    throw InputError("--mesh-list '" + c.mesh_list + "' is not a file");
  for (const auto& [opt, dir, what] : {std::tuple<const char*, std::string, const char*>{
                                           "--documents", c.render.documents_dir, "documents"},
                                       {"--backgrounds", c.render.backgrounds_dir, "backgrounds"}})
    if (!dir.empty()) {
      if (!fs::is_directory(dir))
        throw InputError(std::string(opt) + " '" + dir + "' is not a folder");
      (void)image_files(dir, what);  // one with no image would fail every view
    }
  if (!c.common.shard.empty()) {
    try {
      batch::parse_shard(c.common.shard, "--shard");
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
  }
  if (c.common.slurm_shards > 0) {
    try {
      batch::check_slurm_script(c.dataset, "scenegen-batch", c.common);
    } catch (const std::invalid_argument& e) {
      throw InputError(std::string("--slurm: ") + e.what());
    }
  }
}

}  // namespace

void add_render_batch_subcommand(CLI::App& app, RenderBatchCommand& c) {
  c.app = app.add_subcommand(
      "batch",
      "Render every finished mesh of a dataset (DATASET/meshes/, from papersim batch) --views "
      "times, one "
      "child scenegen render per view, --jobs at once; resumable (run the same command again), "
      "failures "
      "recorded and skipped. Writes DATASET/renders/.../view<k>/, renders.jsonl, "
      "renders_failures.jsonl. "
      "Exit status 1 when a view failed (renders_failures.jsonl); a full disk stops the batch with "
      "status 5 "
      "and records nothing. With --slurm it also lists the meshes it finds in "
      "DATASET/slurm/scenegen-batch.meshes, which every array task reads instead of the folders "
      "(docs/batch.md).");
  c.app->add_option("dataset", c.dataset, "dataset folder")->required();
  c.app
      ->add_option("--mesh-list", c.mesh_list,
                   "render the meshes listed in FILE (as --slurm writes it: "
                   "DATASET/slurm/scenegen-batch.meshes) "
                   "instead of those found in DATASET/meshes/ now; no folder of the list is looked "
                   "at before its "
                   "views run")
      ->type_name("FILE");
  c.app
      ->add_option("--views", c.render.views,
                   "renders per mesh, each with its own seed (at most 1000)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  c.app->add_flag("--flip", c.render.flip,
                  "odd views show the sheet turned over (u -> 1 - u, printed side up)");
  c.app->add_option("--size", c.render.size, "image size WIDTHxHEIGHT [pixels]")
      ->capture_default_str();
  c.app
      ->add_option("--quality", c.render.quality,
                   "draft | final | best (final with smooth penumbrae)")
      ->capture_default_str();
  c.app->add_option("--passes", c.render.passes, "as scenegen render --passes")
      ->capture_default_str();
  c.app->add_option("--documents", c.render.documents_dir, "folder of PNG/JPEG pages to draw from");
  c.app->add_option("--backgrounds", c.render.backgrounds_dir,
                    "folder of PNG/JPEG background images");
  c.app
      ->add_option("--dpi", c.render.dpi,
                   "built-in page resolution [dpi] (0: scenegen render's default; at most 1200)")
      ->check(CLI::Range(0, static_cast<int>(MAX_DPI)))
      ->capture_default_str();
  c.app
      ->add_option("--threads", c.render.threads,
                   "POV-Ray threads per view (1 keeps radiosity reproducible; at most 1024)")
      ->check(CLI::Range(1, MAX_PROCESSES))
      ->capture_default_str();
  batch::add_batch_cli_options(c.app, c.common, "view");
}

int run_render_batch(const RenderBatchCommand& c, std::ostream& out, std::ostream& err) {
  check_options(c);
  if (c.common.slurm_shards > 0) {
    // The walk happens once, here: every array task reads the same list (no walk over the
    // dataset per task, and the same shards even when meshes are added after this).
    fs::path list = c.mesh_list;
    std::size_t meshes = 0;
    if (list.empty()) {
      list = fs::path(c.dataset) / "slurm" / "scenegen-batch.meshes";
      std::error_code ec;
      fs::create_directories(list.parent_path(), ec);
      if (ec)
        throw common::OutputError("cannot create '" + list.parent_path().string() +
                                  "': " + ec.message());
      meshes = write_mesh_list(c.dataset, list, walk_printer(err, c.common.quiet, c.dataset));
    } else {
      meshes = mesh_list_size(list);
    }
    const std::size_t views = meshes * static_cast<std::size_t>(c.render.views);
    const batch::SlurmScript script = batch::write_slurm_script(
        c.dataset, "scenegen-batch", shard_command(c, list), c.common, views);
    out << "wrote " << list.string() << " (" << meshes << " meshes)\n"
        << batch::slurm_written_text(script, c.common, views, "views");
    return 0;
  }
  batch::keep_running_without_readers();
  // Only the shard's tasks are made (an array task holds 1/N of the list in memory).
  const batch::TaskList tasks =
      render_tasks(c.dataset, c.render, batch::cli_shard(c.common), c.mesh_list,
                   walk_printer(err, c.common.quiet, c.dataset));
  const batch::BatchSpec spec = render_batch_spec(c.dataset, batch::self_executable(), c.render);
  const batch::BatchSummary s = batch::run_cli_batch(tasks, spec, c.common, err, "scenegen batch");
  out << batch::summary_line(s, c.dataset, spec) << '\n';
  if (s.interrupted) return 130;
  return s.done == s.total ? 0 : 1;
}

}  // namespace papersim::scenegen
