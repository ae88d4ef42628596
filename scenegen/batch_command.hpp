#pragma once
/// The `scenegen batch` subcommand (CLI glue over scenegen/batch.hpp).
#include <iosfwd>
#include <string>

#include "batch/cli.hpp"
#include "scenegen/batch.hpp"

namespace CLI {
class App;
}

namespace papersim::scenegen {

/// Options of `scenegen batch`, filled by CLI11.
struct RenderBatchCommand {
  CLI::App* app = nullptr;
  std::string dataset;
  std::string
      mesh_list;  ///< --mesh-list: the meshes to render, instead of a walk over DATASET/meshes/
  RenderBatchOptions render;
  batch::BatchCliOptions common;
};

/// Register `batch` on `app`.
void add_render_batch_subcommand(CLI::App& app, RenderBatchCommand& command);

/// Run it. @return 0 all views done, 1 some failed or are left, 130 interrupted
/// @throw InputError for bad options (naming the option), std::runtime_error for I/O errors
int run_render_batch(const RenderBatchCommand& command, std::ostream& out, std::ostream& err);

}  // namespace papersim::scenegen
