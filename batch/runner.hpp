#pragma once
/// A resumable, failure-isolated batch of samples run as child processes, one per core.
///
/// Dataset layout under the batch root (shared by `papersim batch` and `scenegen batch`):
///   ROOT/<key of each task>/         a finished sample: exists only when complete (renamed in)
///   ROOT/<manifest_name>             one JSON line per finished sample (appended atomically)
///   ROOT/<failures_name>             one JSON line per failed attempt (appended atomically)
///   ROOT/.locks/<task>.lock          flock held while a process works on the task
///   ROOT/.staging/<task>.<attempt>/  work folder of a running attempt; never counted
///
/// A task is finished exactly when its final folder exists: outputs are written into a
/// staging folder and renamed into place in one step after they were checked, so a crash at
/// any point leaves either nothing or the whole sample. Running again skips finished tasks,
/// appends a missing manifest row for a task finished just before a crash, and redoes the rest.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "batch/errors.hpp"
#include "batch/key_set.hpp"
#include "batch/task_list.hpp"

namespace papersim::batch {

/// One child process of a task: argv[0] is the executable path.
struct Command {
  std::vector<std::string> argv;
  std::filesystem::path stdout_path;  ///< where the child's stdout goes; empty: the task log
};

/// What a finished attempt reports to the caller's hooks.
struct Attempt {
  std::filesystem::path stage;  ///< the staging folder of the attempt
  double wall_seconds = 0.0;    ///< from the first command's start to the last one's end [s]
  /// user + system time of the commands (and children they waited for) [s]
  double cpu_seconds = 0.0;
};

/// A slice of a task list: the tasks whose position p has p % count == index (0 <= index <
/// count). The default is the whole list.
struct Shard {
  int index = 0;
  int count = 1;
  bool holds(std::size_t position) const {
    return position % static_cast<std::size_t>(count) == static_cast<std::size_t>(index);
  }
};

/// The slice `index` of `count` (0 <= index < count): tasks whose position p in the list has
/// p % count == index. Round robin, so every shard gets a similar mix of scenarios.
/// @throw std::invalid_argument when count < 1 or index is outside [0, count)
TaskList select_shard(const TaskList& tasks, int index, int count);

/// Parse "I/N" into (index, count) with 0 <= I < N.
/// @throw std::invalid_argument naming `option` when the text is not of that form
std::pair<int, int> parse_shard(const std::string& text, const std::string& option);

/// What the progress knows of one running task: its share done (0-1) and the rate at which
/// that share grew while this run watched it [1/s], <= 0 when not seen to grow yet.
struct RunningRate {
  double share = 0.0;
  double rate = 0.0;
};

/// Seconds until the batch ends, from its running tasks' shares and rates alone (before any task
/// has ended in this run): each running task with a known rate needs (1 - share) / rate more;
/// every other task left (`queued`, which counts the running ones without a rate too) the mean
/// of those tasks' whole durations 1 / rate; the work is shared by `jobs` processes, and the
/// batch lasts at least as long as its slowest running task. -1 when no rate is known.
double eta_from_running(const std::vector<RunningRate>& running, long long queued, int jobs);

/// Progress of a running batch.
struct Progress {
  long long total = 0;     ///< tasks of this batch (this shard)
  long long done = 0;      ///< finished, including those finished before this run
  long long failed = 0;    ///< failed (in this run, or recorded earlier and not retried)
  long long running = 0;   ///< child processes at work now
  long long waiting = 0;   ///< tasks held by another process (lock taken)
  long long done_now = 0;  ///< finished by this run
  double elapsed = 0.0;    ///< wall seconds since this run started [s]
  /// Tasks finished by this run per hour of wall time since its tasks were checked (checking a
  /// million done tasks against their dataset takes seconds and runs nothing); -1 while no task
  /// has ended in this run (unknown, not zero).
  double per_hour = -1.0;
  /// Seconds to finish the rest at that rate; before any task ended in this run, from the
  /// running tasks' shares (eta_from_running); -1 when unknown [s].
  double eta = -1.0;
  /// Per running task whose share done is known (BatchSpec::running_share), that share [0-1].
  std::vector<double> running_done;
};
using ProgressFn = std::function<void(const Progress&)>;

/// How far a step before the first task has come: `what` ("reading DATASET/manifest.jsonl"),
/// `done` of `total` in `unit` ("MB", "samples"). Called often (every few thousand items); the
/// receiver decides what to show (batch::step_printer).
using StepProgressFn = std::function<void(const std::string& what, double done, double total,
                                          const std::string& unit)>;

/// How a batch runs and what it does with each task.
struct BatchSpec {
  std::filesystem::path root;  ///< dataset folder (created if missing)
  std::string manifest_name = "manifest.jsonl";
  std::string failures_name = "failures.jsonl";
  std::string items = "samples";  ///< what a task is, for the progress and summary lines
  int jobs = 1;                   ///< child processes at once (>= 1)
  double time_limit = 0.0;        ///< per task, all its commands [s]; <= 0: none
  bool retry_failed = false;      ///< run tasks with a recorded failure again
  double progress_every = 1.0;    ///< seconds between progress calls [s]
  /// Write the inputs of a task into its (empty) staging folder; runs in this process, so
  /// keep it cheap. A throw is recorded as a failure with reason "prepare".
  std::function<void(const Task&, const std::filesystem::path& stage)> prepare;
  /// The commands of a task, run one after the other in the staging folder's context.
  std::function<std::vector<Command>(const Task&, const std::filesystem::path& stage)> commands;
  /// After every command succeeded: check the outputs and return the folder (inside the
  /// stage) that becomes the task's final folder. Throw to record a failure ("outputs").
  std::function<std::filesystem::path(const Task&, const Attempt&)> finalize;
  /// The manifest row of a finished task (its final folder given); the runner adds "key",
  /// "path", "cpu_seconds" (null when unknown) and the task's info. For a task found finished
  /// without a row, wall_seconds is unknown (negative) and the hook should read it from the
  /// outputs; a throw then stops the batch before any task runs (DatasetError naming the folder).
  std::function<nlohmann::json(const Task&, const std::filesystem::path& final_dir,
                               double wall_seconds)>
      manifest_row;
  /// The reason of a failed command from its exit status (>= 0) and last log line; empty
  /// means "exit status N".
  std::function<std::string(int exit_status, const std::string& last_line)> failure_reason;
  ProgressFn progress;  ///< called once the tasks are checked, every progress_every, and at the end
  /// Optional: the progress of checking the tasks against the dataset before the first starts
  /// (looking for the tasks' folders, reading the manifest and the failures file): about 2 s for
  /// a million done tasks, so tens of seconds for ten million.
  StepProgressFn step_progress;
  /// Optional: the share of a running task done so far (0-1), negative when unknown; asked for
  /// every running task before each progress call (Progress::running_done).
  std::function<double(const Task&)> running_share;
};

/// What a batch run did.
struct BatchSummary {
  long long total = 0, done = 0, failed = 0;
  long long done_now = 0, failed_now = 0, repaired = 0;  ///< repaired: manifest rows added
  bool interrupted = false;  ///< stopped by SIGINT or SIGTERM; unfinished tasks left as they were
  double elapsed = 0.0;      ///< [s]
};

/// Run every unfinished task of `tasks` under spec.root. SIGINT and SIGTERM stop the batch:
/// running children are killed (with their process groups) and their staging folders removed,
/// so the same call later resumes. Children die with this process (PR_SET_PDEATHSIG), and each
/// holds its task's lock, so a second batch on the same root never runs a task twice: it waits
/// for tasks another process holds and counts them when they appear.
/// A child that exits with status 5 (common::EXIT_OUTPUT: it cannot write its output) or a
/// sample whose outputs cannot be moved in stops the batch the same way, records nothing for that
/// sample, and throws.
/// @throw common::OutputError when a child or the batch cannot write (the manifest, the failures
/// file, a lock, a sample's folder)
/// @throw DatasetError when a finished task's missing row cannot be made from its folder
BatchSummary run_batch(const TaskList& tasks, const BatchSpec& spec);

/// Append one line (text + '\n') to `path` with a single write on an O_APPEND descriptor under
/// an exclusive flock, then fdatasync: concurrent writers never interleave inside a line, and a
/// line that cannot be written whole (a full disk) is cut off again, so the file keeps whole lines.
/// @throw common::OutputError naming the file when it cannot be opened or fully written
void append_line(const std::filesystem::path& path, const std::string& text);

/// Every JSON object of a JSON-lines file, in order; a missing file gives none. A line that is
/// not JSON (an incomplete last line after power loss) is skipped.
std::vector<nlohmann::json> read_json_lines(const std::filesystem::path& path);

/// The keys of `wanted` that are the "key" of a JSON object line of a JSON-lines file (a missing
/// file gives none; a line that is not JSON is skipped, as by read_json_lines). Streams the file
/// and parses only the lines that name a wanted key, so memory holds the matches alone: a batch
/// (or one shard of it) checks its tasks against a manifest of millions of rows this way.
/// `progress`, when given, hears every 4,096 lines the bytes read so far and the file's size.
/// `offset`, when given, is where the search starts (the end of a line, e.g. where an earlier
/// search of the same growing file ended) and becomes the end of the last whole line searched.
KeySet keys_in_json_lines(
    const std::filesystem::path& path, const KeySet& wanted,
    const std::function<void(std::uintmax_t read, std::uintmax_t size)>& progress = {},
    std::uintmax_t* offset = nullptr);

/// Write `text` to `path` through a temporary file in the same folder and a rename.
/// @throw common::OutputError naming the file when it cannot be written
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

/// A task key as one file name ('/' and ' ' become '_'), as in ROOT/.locks/<name>.lock.
std::string safe_name(const std::string& key);

/// The path of the running executable (/proc/self/exe).
std::filesystem::path self_executable();

}  // namespace papersim::batch
