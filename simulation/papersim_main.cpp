// papersim: simulate paper. Thin front end: parse, load, call the library, report.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "batch/errors.hpp"
#include "collision/errors.hpp"
#include "common/atomic_file.hpp"
#include "common/cli_checks.hpp"
#include "common/eta.hpp"
#include "common/exit_status.hpp"
#include "common/interrupt.hpp"
#include "remesh/errors.hpp"
#include "simulation/batch_command.hpp"
#include "simulation/errors.hpp"
#include "simulation/output_files.hpp"
#include "simulation/scenario.hpp"
#include "simulation/scene.hpp"
#include "simulation/simulate.hpp"
#include "validation/metrics_command.hpp"

namespace ps = papersim::simulation;
namespace common = papersim::common;
namespace fs = std::filesystem;

namespace {

/// Progress with an ETA on stderr: a redrawn line on a terminal; otherwise a line per 10%, and
/// one every 5 minutes of wall time while a run's steps are slow (with the percent to a tenth).
/// The ETA is the rest of the steps at the rate of the last tenth of them (common::RecentRateEta).
ps::ProgressFn progress_printer(const std::string& label) {
  const bool tty = isatty(fileno(stderr));
  return [label, tty, last = -1, printed = 0.0, rate = common::RecentRateEta()](
             double f, double seconds) mutable {
    const double eta = rate.update(f, seconds);
    const int percent = static_cast<int>(100 * f);
    const bool slow = seconds - printed >= 300.0;
    if (!tty && percent / 10 == last / 10 && percent != 100 && !slow) return;
    const bool tenth =
        !tty && percent / 10 == last / 10 && percent != 100;  // a line for the time only
    last = percent;
    printed = seconds;
    char amount[16];
    if (tenth)
      std::snprintf(amount, sizeof amount, "%5.1f", 100 * f);
    else
      std::snprintf(amount, sizeof amount, "%3d", percent);
    std::fprintf(stderr, "%s%s %s%%  elapsed %.1f s  ETA %.1f s%s", tty ? "\r" : "", label.c_str(),
                 amount, seconds, eta, tty && percent < 100 ? "" : "\n");
    std::fflush(stderr);
  };
}

/// Files a run publishes, for the closing message.
std::string written_files(const ps::Scene& scene, int frames, bool with_scene_json) {
  std::string files = "sheet.obj";
  if (scene.output.write_ply) files += ", sheet.ply";
  if ((frames >= 0 ? frames : scene.output.frames_every) > 0) files += ", frames/";
  if (with_scene_json) files += ", scene.json";
  return files + " and meta.json";
}

/// Remove what a run killed with SIGKILL left in `out`, and have the stop handler remove this
/// run's staging folder (and `out`, when this run creates it) if it must end the process.
void prepare_output(const std::string& out) {
  std::error_code ec;
  const fs::path staging = ps::Staging::path_for(out);
  fs::remove_all(staging, ec);
  common::add_cleanup_path(staging);
  if (!fs::exists(out, ec)) common::add_cleanup_path(out);
}

/// Checkpoint options of `run` and `scenario`.
struct CheckpointOptions {
  std::string dir, resume;
  int every = 0;
};

void add_checkpoint_options(CLI::App* app, CheckpointOptions& c) {
  auto* dir =
      app->add_option("--checkpoint", c.dir,
                      "Save the state every --checkpoint-every steps in DIR, a folder "
                      "outside --out (kept when the run fails; continue with --resume DIR)");
  app->add_option("--checkpoint-every", c.every, "Steps between checkpoints (default 100)")
      ->check(CLI::Range(1, ps::MAX_CHECKPOINT_EVERY))
      ->needs(dir);
  dir->check(common::non_empty());
  app->add_option("--resume", c.resume,
                  "Continue from the checkpoint in DIR (same duration; another time step only if "
                  "the checkpoint's time is a whole number of its steps; other scene keys may "
                  "differ, listed in meta.json's `resumed`); meta.json reports the whole run")
      ->check(CLI::ExistingDirectory);
}

/// `--trace TOPICS` of `run` and `scenario`: a comma list of ps::Trace's topics, or "all".
void add_trace_option(CLI::App* app, std::string& topics) {
  std::string names = "all";
  for (const auto& [n, t] : ps::Trace::names()) names += ", " + n;
  app->add_option("--trace", topics,
                  "Tell how the solver works, by topic (a comma list of " + names +
                      "): lines on stderr, e.g. one per Newton iteration or remeshing pass "
                      "(README, Tracing a run)")
      ->check(CLI::Validator(
          [](std::string& value) {
            try {
              ps::Trace::parse(value);
              return std::string();
            } catch (const std::invalid_argument& e) {
              return std::string(e.what());
            }
          },
          "TOPICS"));
}

int simulate(const ps::Scene& scene, const std::string& out, int frames, bool quiet,
             const std::string& trace, const std::string& label, const std::string& scene_json,
             const CheckpointOptions& checkpoint) {
  if (!checkpoint.dir.empty()) {
    // A folder the failed run created is removed with everything in it.
    const fs::path c = fs::weakly_canonical(checkpoint.dir), o = fs::weakly_canonical(out);
    const auto [end, _] = std::mismatch(o.begin(), o.end(), c.begin(), c.end());
    if (end == o.end())
      throw ps::SceneError("--checkpoint " + checkpoint.dir + " lies inside --out " + out +
                           ", which a failed run removes: choose a folder outside it");
  }
  ps::RunOptions options;
  options.checkpoint_dir = checkpoint.dir;
  options.checkpoint_every =
      checkpoint.dir.empty() ? 0 : (checkpoint.every > 0 ? checkpoint.every : 100);
  options.resume_from = checkpoint.resume;
  options.out_dir = out;
  options.frames_every = frames;
  options.poll_stop = common::throw_if_stop_requested;
  if (!trace.empty()) options.trace = ps::Trace(ps::Trace::parse(trace));
  if (!scene_json.empty()) options.extra_files.emplace_back("scene.json", scene_json);
  if (!quiet) options.progress = progress_printer(label);
  const ps::RunResult r = ps::run_scene(scene, options);
  std::cout << "wrote " << out << ": " << written_files(scene, frames, !scene_json.empty()) << " ("
            << r.sheet.vertices << " vertices, " << r.steps << " steps, " << std::setprecision(3)
            << r.wall_seconds << " s; max stretch " << std::setprecision(6)
            << r.quality.max_principal_stretch << ")\n";
  return 0;
}

/// Publish OUT/scene.json alone (the outputs of an earlier run in OUT are removed with it).
void write_scene_only(const std::string& out, const std::string& scene_json) {
  ps::Staging staging(out);
  common::write_text_atomically(staging.dir() / "scene.json", scene_json);
  staging.commit();
}

/// The exit status for the exception being handled, after printing its message.
int report(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const common::Interrupted& e) {
    std::cerr << "papersim: " << e.what() << "; no output written\n";
    return common::exit_status_for_signal(e.signal);
  } catch (const ps::SceneError& e) {
    std::cerr << "papersim: bad scene: " << e.what() << '\n';
  } catch (const ps::NumericError& e) {
    std::cerr << "papersim: simulation failed: " << e.what() << '\n';
    return common::EXIT_NUMERIC;
  } catch (const common::OutputError& e) {
    std::cerr << "papersim: cannot write output: " << e.what() << '\n';
    return common::EXIT_OUTPUT;
  } catch (const papersim::remesh::IoError& e) {
    std::cerr << "papersim: " << e.what() << '\n';
  } catch (const papersim::remesh::MeshError& e) {
    std::cerr << "papersim: bad mesh: " << e.what() << '\n';
  } catch (const papersim::collision::ColliderError& e) {
    std::cerr << "papersim: bad obstacle: " << e.what() << '\n';
  } catch (const papersim::batch::DatasetError& e) {
    std::cerr << "papersim: bad dataset: " << e.what() << '\n';
    return common::EXIT_BAD_INPUT;
  } catch (const std::filesystem::filesystem_error& e) {
    std::cerr << "papersim: cannot write output: " << e.what() << '\n';
    return common::EXIT_OUTPUT;
  } catch (const std::bad_alloc&) {
    std::cerr << "papersim: out of memory\n";
    return common::EXIT_INTERNAL;
  } catch (const std::exception& e) {
    std::cerr << "papersim: internal error: " << e.what() << '\n';
    return common::EXIT_INTERNAL;
  }
  return common::EXIT_BAD_INPUT;
}

}  // namespace

int main(int argc, char** argv) {
  common::install_interrupt_handling();
  CLI::App app{"papersim " + std::string(ps::version()) +
               ": simulate sheets of paper (bending, creasing, contact) and measure them."};
  app.footer(common::exit_status_help());
  app.require_subcommand(1);

  std::string scene_path, out_dir;
  int frames = -1;
  bool quiet = false;
  auto* run = app.add_subcommand("run", "Simulate a scene file (JSON; see docs/scene.md).");
  run->add_option("scene", scene_path, "Scene file (JSON)")->required();
  run->add_option("--out", out_dir, "Output folder: sheet.obj, sheet.ply, meta.json")
      ->required()
      ->check(common::non_empty());
  run->add_option("--frames", frames, "Write every K-th step to OUT/frames/ (0: none)")
      ->check(CLI::Range(0, 1 << 30));
  run->add_flag("--quiet", quiet,
                "No progress on stderr (otherwise a redrawn line on a terminal, else a line per "
                "10% of the steps and one every 5 minutes while they are slow)");
  CheckpointOptions checkpoint;
  add_checkpoint_options(run, checkpoint);
  std::string trace;
  add_trace_option(run, trace);

  std::string name;
  long long seed = 0;
  auto* scen = app.add_subcommand(
      "scenario",
      "Draw the scene of a named scenario for a seed, write it as OUT/scene.json and "
      "simulate it. Same name and seed: same scene, same mesh.");
  scen->add_option("name", name, "Scenario name")
      ->required()
      ->check(CLI::IsMember(ps::scenario_names()));
  scen->add_option("--seed", seed, "Random seed, 0 to 2147483647")
      ->required()
      ->check(CLI::Range(0LL, 2147483647LL));
  scen->add_option("--out", out_dir, "Output folder")->required()->check(common::non_empty());
  scen->add_option("--frames", frames, "Write every K-th step to OUT/frames/ (0: none)")
      ->check(CLI::Range(0, 1 << 30));
  scen->add_flag("--quiet", quiet,
                 "No progress on stderr (otherwise a redrawn line on a terminal, else a line per "
                 "10% of the steps and one every 5 minutes while they are slow)");
  add_checkpoint_options(scen, checkpoint);
  add_trace_option(scen, trace);
  bool draw_only = false;
  scen->add_flag("--draw-only", draw_only,
                 "Only write OUT/scene.json (edit it, then: papersim run)");

  ps::BatchCommand batch_command;
  ps::add_batch_subcommands(app, batch_command);

  int metrics_code = 0;
  papersim::validation::add_metrics_subcommand(app, metrics_code, std::cout, std::cerr);

  try {
    // The metrics subcommand runs inside parse (its callback).
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? common::EXIT_OK : common::EXIT_BAD_INPUT;
  } catch (...) {
    return report(std::current_exception());
  }
  try {
    // What a run killed with SIGKILL left goes first, whatever happens to this run.
    if (run->parsed() || scen->parsed()) prepare_output(out_dir);
    if (batch_command.batch->parsed() || batch_command.stats->parsed())
      return ps::run_batch_subcommand(batch_command, true, std::cout, std::cerr);
    if (run->parsed()) {
      const ps::Scene scene = ps::load_scene(scene_path);
      return simulate(scene, out_dir, frames, quiet, trace, "run", "", checkpoint);
    }
    if (scen->parsed()) {
      const ps::Scene scene = ps::make_scenario(name, static_cast<std::uint64_t>(seed));
      std::ostringstream text;
      text << std::setw(2) << ps::scene_to_json(scene) << '\n';
      if (draw_only) {
        write_scene_only(out_dir, text.str());
        std::cout << "wrote " << (fs::path(out_dir) / "scene.json").string() << '\n';
        return 0;
      }
      return simulate(scene, out_dir, frames, quiet, trace, name + " seed " + std::to_string(seed),
                      text.str(), checkpoint);
    }
    return metrics_code;
  } catch (...) {
    return report(std::current_exception());
  }
}
