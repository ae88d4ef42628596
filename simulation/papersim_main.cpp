// papersim: simulate paper. Thin front end: parse, load, call the library, report.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "collision/errors.hpp"
#include "remesh/errors.hpp"
#include "simulation/batch_command.hpp"
#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"
#include "simulation/scene.hpp"
#include "simulation/simulate.hpp"

#ifdef PAPERSIM_WITH_METRICS
#include "validation/metrics_command.hpp"
#define PAPERSIM_HAS_METRICS true
#else
#define PAPERSIM_HAS_METRICS false
#endif

namespace ps = papersim::simulation;
namespace fs = std::filesystem;

namespace {

/// Progress with an ETA on stderr: a redrawn line on a terminal, a line per 10% otherwise.
ps::ProgressFn progress_printer(const std::string& label) {
  const bool tty = isatty(fileno(stderr));
  return [label, tty, last = -1](double f, double seconds) mutable {
    const int percent = static_cast<int>(100 * f);
    if (!tty && percent / 10 == last / 10 && percent != 100) return;
    last = percent;
    const double eta = f > 0 ? seconds * (1 - f) / f : 0;
    std::fprintf(stderr, "%s%s %3d%%  elapsed %.1f s  ETA %.1f s%s", tty ? "\r" : "", label.c_str(),
                 percent, seconds, eta, tty && percent < 100 ? "" : "\n");
    std::fflush(stderr);
  };
}

int simulate(const ps::Scene& scene, const std::string& out, int frames, bool quiet,
             const std::string& label) {
  ps::RunOptions options;
  options.out_dir = out;
  options.frames_every = frames;
  if (!quiet) options.progress = progress_printer(label);
  const ps::RunResult r = ps::run_scene(scene, options);
  std::cout << "wrote " << (fs::path(out) / "sheet.obj").string() << ", sheet.ply and meta.json ("
            << r.sheet.vertices << " vertices, " << r.steps << " steps, " << std::setprecision(3)
            << r.wall_seconds << " s; max stretch " << std::setprecision(6)
            << r.quality.max_principal_stretch << ")\n";
  return 0;
}

void write_scene_file(const fs::path& path, const ps::Scene& scene) {
  fs::create_directories(path.parent_path());
  const fs::path tmp = path.string() + ".tmp";
  std::ofstream(tmp) << std::setw(2) << ps::scene_to_json(scene) << '\n';
  fs::rename(tmp, path);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"papersim " + std::string(ps::version()) +
               ": simulate sheets of paper (bending, creasing, contact) and measure them."};
  app.require_subcommand(1);

  std::string scene_path, out_dir;
  int frames = -1;
  bool quiet = false;
  auto* run = app.add_subcommand("run", "Simulate a scene file (JSON; see docs/scene.md).");
  run->add_option("scene", scene_path, "Scene file (JSON)")->required();
  run->add_option("--out", out_dir, "Output folder: sheet.obj, sheet.ply, meta.json")->required();
  run->add_option("--frames", frames, "Write every K-th step to OUT/frames/ (0: none)")
      ->check(CLI::NonNegativeNumber);
  run->add_flag("--quiet", quiet, "No progress on stderr");

  std::string name;
  long long seed = 0;
  auto* scen = app.add_subcommand(
      "scenario", "Draw the scene of a named scenario for a seed, write it as OUT/scene.json and "
                  "simulate it. Same name and seed: same scene, same mesh.");
  scen->add_option("name", name, "Scenario name")->required()->check(
      CLI::IsMember(ps::scenario_names()));
  scen->add_option("--seed", seed, "Random seed (>= 0)")->required()->check(CLI::NonNegativeNumber);
  scen->add_option("--out", out_dir, "Output folder")->required();
  scen->add_option("--frames", frames, "Write every K-th step to OUT/frames/ (0: none)")
      ->check(CLI::NonNegativeNumber);
  scen->add_flag("--quiet", quiet, "No progress on stderr");
  bool draw_only = false;
  scen->add_flag("--draw-only", draw_only, "Only write OUT/scene.json (edit it, then: papersim run)");

  ps::BatchCommand batch_command;
  ps::add_batch_subcommands(app, batch_command);

#ifdef PAPERSIM_WITH_METRICS
  int metrics_code = 0;
  papersim::validation::add_metrics_subcommand(app, metrics_code, std::cout, std::cerr);
#endif

  CLI11_PARSE(app, argc, argv);
  try {
    if (batch_command.batch->parsed() || batch_command.stats->parsed())
      return ps::run_batch_subcommand(batch_command, PAPERSIM_HAS_METRICS, std::cout, std::cerr);
    if (run->parsed()) {
      const ps::Scene scene = ps::load_scene(scene_path);
      return simulate(scene, out_dir, frames, quiet, "run");
    }
    if (scen->parsed()) {
      const ps::Scene scene = ps::make_scenario(name, static_cast<std::uint64_t>(seed));
      if (draw_only) {
        write_scene_file(fs::path(out_dir) / "scene.json", scene);
        std::cout << "wrote " << (fs::path(out_dir) / "scene.json").string() << '\n';
        return 0;
      }
      const int code = simulate(scene, out_dir, frames, quiet, name + " seed " + std::to_string(seed));
      write_scene_file(fs::path(out_dir) / "scene.json", scene);
      return code;
    }
#ifdef PAPERSIM_WITH_METRICS
    return metrics_code;
#endif
  } catch (const ps::SceneError& e) {
    std::cerr << "papersim: bad scene: " << e.what() << '\n';
    return 2;
  } catch (const ps::NumericError& e) {
    std::cerr << "papersim: simulation failed: " << e.what() << '\n';
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "papersim: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
