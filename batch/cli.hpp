#pragma once
/// The options every batch command shares (--jobs, --time-limit, --shard, --retry-failed,
/// --slurm ...), its progress line and the Slurm script it can write instead of running.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "batch/runner.hpp"
#include "batch/slurm.hpp"

namespace CLI {
class App;
}

namespace papersim::batch {

/// splitmix64's finaliser (Steele et al. 2014): a well-mixed 64-bit hash of x, used to draw a
/// sample's scenario and view seeds from its seed identically on every machine.
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// Parsed shared options.
struct BatchCliOptions {
  int jobs = 0;             ///< 0: one per core
  double time_limit = 0.0;  ///< per sample [s]; 0: none
  std::string shard;        ///< "I/N" or empty
  bool retry_failed = false;
  bool quiet = false;
  int slurm_shards = 0;  ///< > 0: write the sbatch script instead of running
  SlurmOptions slurm;
};

/// Register the shared options on `app`; their help names a task `item` ("sample", "view").
void add_batch_cli_options(CLI::App* app, BatchCliOptions& options,
                           const std::string& item = "sample");

/// A progress printer: "done D/T  failed F  running R  S samples/h  ETA ..." (`items` for
/// "samples"), redrawn on a terminal, one line per `every_seconds` otherwise.
ProgressFn progress_printer(std::ostream& out, bool tty, const std::string& label,
                            const std::string& items = "samples");

/// A printer of the steps before a batch's first task (drawing the samples, reading the
/// manifest): "LABEL: WHAT: D of T UNIT, S s, ETA E s", S and E of the step WHAT, once its first
/// second has passed; redrawn every second on a terminal, a line every 5 s otherwise. Steps
/// shorter than that print nothing.
StepProgressFn step_printer(std::ostream& out, bool tty, const std::string& label);

/// step_printer on `out` for a batch command's options: none with --quiet.
StepProgressFn cli_step_printer(const BatchCliOptions& options, std::ostream& out,
                                const std::string& label);

/// Whether the dataset folder `root` (given as `option`) exists or can be made: refused when it
/// or the nearest of its parents that exists is not a folder, before a long draw of samples.
/// @throw common::OutputError naming the option, the folder and the part that is a file
void check_dataset_folder(const std::filesystem::path& root, const std::string& option);

/// A batch's work is its dataset, not the lines it prints: from the call on, a write to a pipe
/// whose reader has ended (`papersim batch ... 2>&1 | tee log`, tee stopped) fails without
/// stopping the process (SIGPIPE ignored), and the batch goes on without its lines. The samples'
/// programs get the default action back (run_batch).
void keep_running_without_readers();

/// The slice of --shard, or the whole list when it was not given.
/// @throw std::invalid_argument naming --shard when it is malformed
Shard cli_shard(const BatchCliOptions& options);

/// Fill jobs / time limit / retry / progress into the spec and run `tasks`, which are the
/// shard's alone: the caller makes only the tasks cli_shard() holds (an array task of a large
/// dataset then holds 1/N of its tasks in memory). --jobs 0 means one per core.
BatchSummary run_cli_batch(const TaskList& tasks, BatchSpec spec, const BatchCliOptions& options,
                           std::ostream& progress_out, const std::string& label);

/// A job-array script written by write_slurm_script.
struct SlurmScript {
  std::filesystem::path path;
  int array_tasks = 0;  ///< --slurm N, or one per task when the batch has fewer than N
};

/// Write ROOT/slurm/NAME.sbatch for `command` (the batch command line without --shard and
/// --jobs; absolute paths) over `tasks` tasks (samples, or views). The array has --slurm N tasks,
/// or `tasks` when that is fewer (a task given an empty shard would start, find nothing and
/// end), at least one. The script is made before anything is written.
/// @throw std::invalid_argument as check_slurm_script; std::runtime_error when the file cannot
/// be written
SlurmScript write_slurm_script(const std::filesystem::path& root, const std::string& name,
                               const std::vector<std::string>& command,
                               const BatchCliOptions& options, std::size_t tasks);

/// What a command prints after writing `script` for `tasks` tasks counted in `unit` ("samples",
/// "views"): the array's size, how to submit it and how to run a task that died again, and a note
/// when --slurm asked for more tasks than there are, or for more than Slurm's default
/// MaxArraySize (1001) takes.
std::string slurm_written_text(const SlurmScript& script, const BatchCliOptions& options,
                               std::size_t tasks, const std::string& unit);

/// Whether write_slurm_script(root, name, ...) can write its script, for a command to check
/// before it writes anything else.
/// @throw std::invalid_argument naming the option or folder whose text no #SBATCH line can hold
/// (a line break)
void check_slurm_script(const std::filesystem::path& root, const std::string& name,
                        const BatchCliOptions& options);

/// One line: "N of T samples done (M in this run, R manifest rows restored), F failed; ..." for
/// the end of a run (spec.items for "samples").
std::string summary_line(const BatchSummary& summary, const std::filesystem::path& root,
                         const BatchSpec& spec);

}  // namespace papersim::batch
