#pragma once
/// Slurm job-array scripts for a sharded batch: array task I runs shard I/N of the same batch.
/// Slurm is the scheduler; nothing here schedules.
#include <filesystem>
#include <string>
#include <vector>

namespace papersim::batch {

/// What the `sbatch` script asks for, per array task.
struct SlurmOptions {
  int shards = 1;          ///< array tasks (0 .. shards-1), each one shard I/N
  int cpus_per_task = 1;   ///< cores per array task; the shard runs this many samples at once
  std::string mem = "2G";  ///< memory per array task (sbatch --mem syntax)
  std::string time = "24:00:00";  ///< wall-time limit per array task (sbatch --time syntax)
  std::string partition;          ///< sbatch --partition; empty: the cluster's default
  std::string job_name = "papersim";
  int max_running = 0;  ///< at most this many array tasks at once (%M); 0: no limit
};

/// Slurm's default MaxArraySize (slurm.conf): array indices must be below it, so a default
/// cluster takes arrays of at most this many tasks (0 .. 1000).
inline constexpr int SLURM_DEFAULT_MAX_ARRAY_SIZE = 1001;

/// A bash word in single quotes.
std::string shell_quote(const std::string& word);

/// `word` as it may be pasted into bash: unchanged when it holds only letters, digits and
/// "%+,-./:=@_", else in single quotes (a script path in the "submit it with" line).
std::string shell_word(const std::string& word);

/// `word` as the value of a #SBATCH line: in double quotes, a '"' in it as \". sbatch 22.05
/// reads a directive's value up to white space or '#' unless quoted ("my data#2" is one value
/// only in quotes) and takes a backslash as an escape.
/// @throw std::invalid_argument naming `what` when `word` is empty, has a line break (no line
/// holds it) or a backslash
std::string directive_word(const std::string& word, const std::string& what);

/// The script: #SBATCH lines (--array, --cpus-per-task, --mem, --time, --output, --error,
/// --job-name, --partition), then `command` with "--shard ${SLURM_ARRAY_TASK_ID}/N --jobs C"
/// appended. Logs go to LOG_DIR/%A_%a.out and .err.
/// @throw std::invalid_argument when shards or cpus_per_task < 1, when a directive's value (the
/// options' texts, LOG_DIR) is empty or has a line break or a backslash, or LOG_DIR has a '%'
/// (sbatch reads it as a file name pattern: the task could not open its log and would not start)
std::string slurm_script(const std::vector<std::string>& command, const SlurmOptions& options,
                         const std::filesystem::path& log_dir);

}  // namespace papersim::batch
