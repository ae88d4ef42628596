// scenegen: POV-Ray scenes for the photo and every pixel-exact ground-truth pass of a sheet.
// Thin CLI: parse, call the library, report. Only main catches.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "batch/errors.hpp"
#include "common/atomic_file.hpp"
#include "common/cli_checks.hpp"
#include "common/exit_status.hpp"
#include "common/interrupt.hpp"
#include "scenegen/batch_command.hpp"
#include "scenegen/errors.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/job.hpp"
#include "scenegen/limits.hpp"

namespace sg = papersim::scenegen;
namespace common = papersim::common;

namespace {

struct Cli {
  sg::SampleOptions sample;
  std::string out, passes = "all", quality = "final", size = "1024x1440", backward_grid = "121x177";
  std::string job, povray = "povray", ground_truth = "raycast";
  bool exact16 = false, keep_job = false, quiet = false, no_contact = false, no_edge_lift = false;
  int parallel = 0, views = 1;
};

/// An unsigned decimal number, digits only (CLI11 would read -1 as 2^64 - 1).
CLI::Validator digits_only() {
  return CLI::Validator(
      [](std::string& v) {
        return !v.empty() && v.size() <= 19 &&
                       v.find_first_not_of("0123456789") == std::string::npos
                   ? std::string()
                   : "'" + v + "' is not a whole number from 0 to 9223372036854775807";
      },
      "UINT");
}

void add_sample_options(CLI::App* app, Cli& c) {
  app->add_option("mesh", c.sample.mesh_path, "sheet OBJ (v, vt = material UV, f)")
      ->required()
      ->check(common::non_empty());
  app->add_option("--document", c.sample.document,
                  "document page (PNG or JPEG); default: built-in generator");
  app->add_option("--documents", c.sample.documents_dir, "folder of PNG/JPEG pages to draw from");
  app->add_option("--backgrounds", c.sample.backgrounds_dir,
                  "folder of PNG/JPEG background images (added to the procedural ones)");
  app->add_option("--seed", c.sample.seed,
                  "sample seed (camera, lights, background, paper, document, edge curl)")
      ->capture_default_str()
      ->check(digits_only());
  app->add_option("--size", c.size, "image size WIDTHxHEIGHT [pixels], 8 to 8192 per side")
      ->capture_default_str();
  app->add_option("--passes", c.passes,
                  "comma list of image,shading,albedo,uv,coords,normal,mask,backward, or all")
      ->capture_default_str();
  app->add_option("--quality", c.quality,
                  "draft | final | best (final with 3 x 3 instead of 2 x 2 jittered area-light "
                  "samples: less grainy penumbrae; photo and shading pass only)")
      ->capture_default_str();
  app->add_option("--rig", c.sample.rig,
                  "light rig three-point|rim|softbox|natural (default: drawn)");
  app->add_option("--backward-grid", c.backward_grid,
                  "backward map grid WIDTHxHEIGHT over the page, or 'full' (image size)")
      ->capture_default_str();
  app->add_option("--ground-truth", c.ground_truth,
                  "uv, coords, normal, mask: raycast (scenegen casts the pixel rays on the "
                  "rendered triangles) | povray (emissive POV-Ray renders)")
      ->capture_default_str();
  app->add_flag("--exact16", c.exact16,
                "with --ground-truth povray: skip the fine uv/coords renders (16-bit precision "
                "instead of float32)");
  app->add_option("--dpi", c.sample.document_dpi, "built-in page resolution [dpi], up to 1200")
      ->capture_default_str()
      ->check(CLI::Range(1.0, sg::MAX_DPI));
  app->add_option("--threads", c.sample.threads,
                  "threads per POV-Ray process (1 keeps radiosity reproducible; 0: all cores)")
      ->capture_default_str()
      ->check(CLI::Range(0, sg::MAX_PROCESSES));
  app->add_option("--templates", c.sample.templates_dir,
                  "use POV-Ray templates from this folder instead of the built-in copy");
  app->add_option(
         "--subdivision", c.sample.surface.level,
         "butterfly subdivision steps of the rendered surface (0: the mesh as it is, at most 4)")
      ->capture_default_str();
  app->add_option(
         "--layout", c.sample.layout,
         "output names: scenegen | syntheticdoc (the reference dataset's names and conventions)")
      ->capture_default_str();
  app->add_flag("--no-contact-shadow", c.no_contact,
                "do not darken the table where the sheet hides its sky (contact shadow)");
  app->add_flag("--no-edge-lift", c.no_edge_lift,
                "render the sheet's resting edges flat on the table (no drawn edge curl)");
  app->add_flag("--flip", c.sample.flip,
                "render the sheet from its other side (mirror x, u -> 1 - u)");
}

void finalise(Cli& c) {
  sg::parse_image_size(c.size, c.sample.width, c.sample.height, "--size", false, 8);
  sg::parse_image_size(c.backward_grid, c.sample.backward.grid_width, c.sample.backward.grid_height,
                       "--backward-grid", true, 2);
  c.sample.passes = sg::parse_passes(c.passes);
  try {
    c.sample.quality = sg::parse_quality(c.quality);
  } catch (const sg::InputError& e) {
    throw sg::InputError(std::string("--quality: ") + e.what());
  }
  c.sample.fine_passes = !c.exact16;
  c.sample.contact_shadow = !c.no_contact;
  c.sample.edge_lift = !c.no_edge_lift;
  c.sample.ground_truth = sg::parse_ground_truth(c.ground_truth);
}

sg::RunOptions run_options(const Cli& c) {
  sg::RunOptions run;
  run.povray = c.povray;
  run.parallel = c.parallel;
  run.poll_stop = common::throw_if_stop_requested;
  if (!c.quiet)
    run.progress = [](const sg::PassProgress& p) {
      if (p.seconds < 0)
        std::cerr << "[" << p.index << "/" << p.total << "] rendering " << p.pass << " ..."
                  << std::endl;
      else
        std::fprintf(stderr, "[%d/%d] %s done in %.2f s\n", p.index, p.total, p.pass.c_str(),
                     p.seconds);
    };
  return run;
}

/// The exit status for the exception being handled, after printing its message.
int report(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const common::Interrupted& e) {
    std::cerr << "scenegen: " << e.what() << "; no output written\n";
    return common::exit_status_for_signal(e.signal);
  } catch (const sg::NoValidCameraError& e) {
    std::cerr << "scenegen: " << e.what() << " (recorded in meta.json)\n";
    return common::EXIT_NO_CAMERA;
  } catch (const common::OutputError& e) {
    std::cerr << "scenegen: cannot write output: " << e.what() << "\n";
    return common::EXIT_OUTPUT;
  } catch (const sg::RenderError& e) {
    std::cerr << "scenegen: " << e.what() << "\n";
    return common::EXIT_EXTERNAL;
  } catch (const papersim::batch::DatasetError& e) {
    std::cerr << "scenegen: bad dataset: " << e.what() << '\n';
    return common::EXIT_BAD_INPUT;
  } catch (const std::filesystem::filesystem_error& e) {
    std::cerr << "scenegen: cannot write output: " << e.what() << '\n';
    return common::EXIT_OUTPUT;
  } catch (const std::bad_alloc&) {
    std::cerr << "scenegen: out of memory\n";
    return common::EXIT_INTERNAL;
  } catch (const sg::InputError& e) {
    std::cerr << "scenegen: " << e.what() << "\n";
  } catch (const sg::IoError& e) {
    std::cerr << "scenegen: " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "scenegen: internal error: " << e.what() << "\n";
    return common::EXIT_INTERNAL;
  }
  return common::EXIT_BAD_INPUT;
}

}  // namespace

int main(int argc, char** argv) {
  common::install_interrupt_handling();
  CLI::App app{"scenegen: POV-Ray scenes and pixel-exact ground-truth passes for a sheet mesh"};
  app.footer(common::exit_status_help());
  app.require_subcommand(1);
  Cli c;
  auto* render =
      app.add_subcommand("render", "prepare + run POV-Ray + finish: a whole sample in --out");
  add_sample_options(render, c);
  render->add_option("--out", c.out, "sample folder")->required()->check(common::non_empty());
  render->add_option("--povray", c.povray, "POV-Ray 3.7 executable")->capture_default_str();
  render->add_option("--parallel", c.parallel, "POV-Ray processes at once (0: one per core)")
      ->capture_default_str()
      ->check(CLI::Range(0, sg::MAX_PROCESSES));
  render->add_flag("--keep-job", c.keep_job, "keep the POV-Ray job folder as OUT/job");
  render->add_flag("--quiet", c.quiet, "no progress on stderr");
  render
      ->add_option("--views", c.views,
                   "views of the mesh, each with its own camera, lights, background and paper, in "
                   "OUT/view_00 ... (1: OUT itself)")
      ->capture_default_str();
  auto* prepare = app.add_subcommand(
      "prepare", "write a self-contained POV-Ray job folder (run it with its run.sh)");
  add_sample_options(prepare, c);
  prepare->add_option("--out", c.out, "job folder")->required()->check(common::non_empty());
  auto* finish = app.add_subcommand(
      "finish",
      "decode a rendered job folder into the sample files (and cast the ground-truth rays)");
  finish->add_option("job", c.job, "job folder (rendered)")->required();
  finish->add_option("--out", c.out, "sample folder")->required()->check(common::non_empty());
  auto* run = app.add_subcommand("run", "render a prepared job folder with POV-Ray");
  run->add_option("job", c.job, "job folder")->required();
  run->add_option("--povray", c.povray, "POV-Ray 3.7 executable")->capture_default_str();
  run->add_option("--parallel", c.parallel, "POV-Ray processes at once (0: one per core)")
      ->capture_default_str()
      ->check(CLI::Range(0, sg::MAX_PROCESSES));
  std::string example_kind;
  auto* example =
      app.add_subcommand("example", "write a synthetic sheet OBJ (flat, cylinder, fold, bump)");
  example->add_option("kind", example_kind, "flat | cylinder | fold | bump")->required();
  example->add_option("--out", c.out, "OBJ file")->required()->check(common::non_empty());
  sg::RenderBatchCommand batch;
  sg::add_render_batch_subcommand(app, batch);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? common::EXIT_OK : common::EXIT_BAD_INPUT;
  }
  try {
    if (batch.app->parsed()) return sg::run_render_batch(batch, std::cout, std::cerr);
    if (render->parsed() || finish->parsed()) {
      // What a run killed with SIGKILL left goes first, whatever happens to this run.
      std::error_code ec;
      for (const auto& p : sg::render_staging_paths(c.out)) {
        std::filesystem::remove_all(p, ec);
        common::add_cleanup_path(p);
      }
      if (!std::filesystem::exists(c.out, ec)) common::add_cleanup_path(c.out);
    }
    if (render->parsed()) {
      finalise(c);
      sg::RunOptions run = run_options(c);
      const auto report = sg::render_views(c.sample, c.views, c.out, run, c.keep_job);
      std::printf("wrote %s (%.2f s of POV-Ray)\n", c.out.c_str(), report.total());
    } else if (prepare->parsed()) {
      finalise(c);
      common::add_cleanup_path(c.out + ".partial");
      sg::prepare_job(c.sample, c.out);
      std::printf("wrote job %s (render it with %s/run.sh, then scenegen finish)\n", c.out.c_str(),
                  c.out.c_str());
    } else if (run->parsed()) {
      const auto report = sg::run_job(c.job, run_options(c));
      std::printf("rendered %s (%.2f s)\n", c.job.c_str(), report.total());
    } else if (example->parsed()) {
      const sg::SheetMesh sheet = sg::make_example_sheet(example_kind);
      common::write_file_atomically(c.out,
                                    [&](std::ostream& out) { sg::write_sheet_obj(out, sheet); });
      std::printf("wrote %s\n", c.out.c_str());
    } else if (finish->parsed()) {
      sg::finish_job(c.job, c.out);
      std::printf("wrote %s\n", c.out.c_str());
    }
  } catch (...) {
    return report(std::current_exception());
  }
  return common::EXIT_OK;
}
