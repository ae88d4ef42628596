#pragma once
/// The `papersim batch` and `papersim dataset-stats` subcommands (CLI glue over
/// simulation/batch.hpp and batch/dataset_stats.hpp).
#include <iosfwd>
#include <string>
#include <vector>

#include "batch/cli.hpp"

namespace CLI {
class App;
}

namespace papersim::simulation {

/// Options of both subcommands, filled by CLI11.
struct BatchCommand {
  CLI::App* batch = nullptr;
  CLI::App* stats = nullptr;
  std::string out, scenarios, mix, seeds;
  std::vector<std::string> set;
  int checkpoint_every = 0;  ///< steps between a sample's checkpoints (0: none)
  batch::BatchCliOptions common;
  std::string dataset, plots;
  bool stats_quiet = false;  ///< dataset-stats: no progress lines
};

/// Register `batch` and `dataset-stats` on `app`.
void add_batch_subcommands(CLI::App& app, BatchCommand& command);

/// Run whichever of the two was parsed. `with_metrics`: also run `papersim metrics` per sample.
/// Bad options are reported on `err` naming the option (status 2) before any sample runs.
/// @return the exit status: 0 all done, 1 some samples failed or are left, 2 bad options,
///         130 interrupted
/// @throw std::runtime_error when the dataset cannot be written
int run_batch_subcommand(const BatchCommand& command, bool with_metrics, std::ostream& out,
                         std::ostream& err);

}  // namespace papersim::simulation
