#include "batch/cli.hpp"

#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <ostream>
#include <sstream>
#include <thread>

#include "common/cli_checks.hpp"
#include "common/errors.hpp"

namespace papersim::batch {
namespace fs = std::filesystem;

namespace {

std::string duration_text(double s) {
  if (s < 0) return "?";
  char buf[32];
  if (s < 120)
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 7200)
    std::snprintf(buf, sizeof buf, "%.1f min", s / 60);
  else
    std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  return buf;
}

/// Whether `out` is standard error on a terminal (progress redrawn in place).
bool on_terminal(const std::ostream& out) { return &out == &std::cerr && isatty(2); }

}  // namespace

void add_batch_cli_options(CLI::App* app, BatchCliOptions& o, const std::string& item) {
  const std::string items = item + "s";
  app->add_option("--jobs,-j", o.jobs,
                  items + " at once, one child process each (0: one per core; at most 1024)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  app->add_option("--time-limit", o.time_limit,
                  "seconds per " + item + "; a " + item +
                      " over it is killed and recorded as failed (0: none)")
      ->check(papersim::common::non_negative())
      ->capture_default_str();
  app->add_option(
      "--shard", o.shard,
      "run only slice I of N (0 <= I < N): the " + items + " at positions p with p % N == I");
  app->add_flag("--retry-failed", o.retry_failed,
                "run " + items + " recorded in the failures file again");
  app->add_flag("--quiet", o.quiet, "no progress lines on stderr");
  app->add_option(
         "--slurm", o.slurm_shards,
         "write DATASET/slurm/*.sbatch, a job array of this many shards (at most one per " + item +
             "), and print how to submit it (nothing runs)")
      ->check(papersim::common::positive());
  app->add_option("--slurm-cpus", o.slurm.cpus_per_task,
                  "cores per array task (= " + items + " at once in it; at most 1024)")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app->add_option("--slurm-mem", o.slurm.mem, "memory per array task (sbatch --mem)")
      ->capture_default_str();
  app->add_option("--slurm-time", o.slurm.time, "time limit per array task (sbatch --time)")
      ->capture_default_str();
  app->add_option("--slurm-partition", o.slurm.partition,
                  "sbatch --partition (default: the cluster's)");
  app->add_option("--slurm-max-running", o.slurm.max_running,
                  "at most this many array tasks at once (0: no limit)")
      ->check(papersim::common::non_negative())
      ->capture_default_str();
}

ProgressFn progress_printer(std::ostream& out, bool tty, const std::string& label,
                            const std::string& items) {
  return [&out, tty, label, items](const Progress& p) {
    char rate[32] = "?";
    if (p.per_hour >= 0) std::snprintf(rate, sizeof rate, "%.1f", p.per_hour);
    char line[256];
    std::snprintf(line, sizeof line,
                  "%s: done %lld/%lld  failed %lld  running %lld%s  %s %s/h  ETA %s", label.c_str(),
                  p.done, p.total, p.failed, p.running,
                  p.waiting > 0 ? ("  held elsewhere " + std::to_string(p.waiting)).c_str() : "",
                  rate, items.c_str(), duration_text(p.eta).c_str());
    std::string shares;  // "  running at 41%, 17%": the first four running tasks that tell it
    for (std::size_t i = 0; i < p.running_done.size() && i < 4; ++i)
      shares +=
          (i ? ", " : "  running at ") + std::to_string(std::lround(100 * p.running_done[i])) + "%";
    if (p.running_done.size() > 4) shares += ", ...";
    out << (tty ? "\r\033[K" : "") << line << shares << (tty ? "" : "\n") << std::flush;
  };
}

StepProgressFn step_printer(std::ostream& out, bool tty, const std::string& label) {
  using Clock = std::chrono::steady_clock;
  struct State {
    std::string what;
    Clock::time_point start = Clock::now(), last = Clock::now();
  };
  auto state = std::make_shared<State>();
  const auto every = std::chrono::seconds(tty ? 1 : 5);
  return [&out, tty, label, state, every](const std::string& what, double done, double total,
                                          const std::string& unit) {
    const auto now = Clock::now();
    if (what != state->what) {
      state->what = what;
      state->start = now;
    }
    if (now - state->last < every || now - state->start < std::chrono::seconds(1)) return;
    state->last = now;
    const double t = std::chrono::duration<double>(now - state->start).count();
    const double eta = done > 0 && total >= done ? t / done * (total - done) : -1.0;
    char line[128];
    std::snprintf(line, sizeof line, ": %.0f of %.0f %s, %.0f s, ETA %s", done, total, unit.c_str(),
                  t, duration_text(eta).c_str());
    out << (tty ? "\r\033[K" : "") << label << ": " << what << line << (tty ? "" : "\n")
        << std::flush;
  };
}

StepProgressFn cli_step_printer(const BatchCliOptions& o, std::ostream& out,
                                const std::string& label) {
  if (o.quiet) return {};
  return step_printer(out, on_terminal(out), label);
}

void check_dataset_folder(const fs::path& root, const std::string& option) {
  std::error_code ec;
  for (fs::path p = fs::absolute(root, ec); !ec && !p.empty(); p = p.parent_path()) {
    const fs::file_status st = fs::status(p, ec);
    if (ec && st.type() != fs::file_type::not_found) break;  // cannot tell: creating it says why
    ec.clear();
    if (st.type() == fs::file_type::not_found) {
      if (p == p.parent_path()) break;
      continue;
    }
    if (st.type() != fs::file_type::directory)
      throw common::OutputError("cannot make the dataset folder " + option + " '" + root.string() +
                                "': '" + p.string() + "' is not a folder");
    return;
  }
}

void keep_running_without_readers() {
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, nullptr);
}

Shard cli_shard(const BatchCliOptions& o) {
  if (o.shard.empty()) return {};
  const auto [index, count] = parse_shard(o.shard, "--shard");
  return {index, count};
}

BatchSummary run_cli_batch(const TaskList& tasks, BatchSpec spec, const BatchCliOptions& o,
                           std::ostream& progress_out, const std::string& label) {
  spec.jobs =
      o.jobs > 0 ? o.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  spec.time_limit = o.time_limit;
  spec.retry_failed = o.retry_failed;
  const bool tty = on_terminal(progress_out);
  spec.progress_every = tty ? 1.0 : 30.0;
  if (!o.quiet) {
    spec.progress = progress_printer(progress_out, tty, label, spec.items);
    spec.step_progress = step_printer(progress_out, tty, label);
  }
  BatchSummary s = run_batch(tasks, spec);
  if (!o.quiet && tty) progress_out << '\n';
  return s;
}

namespace {

std::string script_text(const fs::path& root, const std::string& name,
                        const std::vector<std::string>& command, const BatchCliOptions& o) {
  SlurmOptions so = o.slurm;
  so.shards = o.slurm_shards;
  so.job_name = name;
  return slurm_script(command, so, fs::absolute(root) / "slurm");
}

}  // namespace

void check_slurm_script(const fs::path& root, const std::string& name, const BatchCliOptions& o) {
  (void)script_text(root, name, {}, o);
}

SlurmScript write_slurm_script(const fs::path& root, const std::string& name,
                               const std::vector<std::string>& command, const BatchCliOptions& o,
                               std::size_t tasks) {
  BatchCliOptions used = o;
  used.slurm_shards = static_cast<int>(std::min<std::size_t>(
      static_cast<std::size_t>(o.slurm_shards), std::max<std::size_t>(tasks, 1)));
  const std::string text = script_text(root, name, command, used);
  const fs::path dir = fs::absolute(root) / "slurm";
  fs::create_directories(dir);
  fs::path file = dir / (name + ".sbatch");
  write_file_atomically(file, text);
  fs::permissions(file, fs::perms::owner_exec, fs::perm_options::add);
  return {file, used.slurm_shards};
}

std::string slurm_written_text(const SlurmScript& script, const BatchCliOptions& o,
                               std::size_t tasks, const std::string& unit) {
  std::ostringstream out;
  const std::string file = shell_word(script.path.string());
  out << "wrote " << script.path.string() << " (" << script.array_tasks << " array task"
      << (script.array_tasks == 1 ? "" : "s") << " over " << tasks << ' ' << unit << ")\n";
  if (tasks == 0)
    out << "note: there are no " << unit << " to run; the array's one task ends at once\n";
  else if (script.array_tasks < o.slurm_shards)
    out << "note: --slurm " << o.slurm_shards << " is more than the " << tasks << ' ' << unit
        << ": one array task per " << unit.substr(0, unit.size() - 1) << "\n";
  if (script.array_tasks > SLURM_DEFAULT_MAX_ARRAY_SIZE)
    out << "note: Slurm takes array indices below MaxArraySize, " << SLURM_DEFAULT_MAX_ARRAY_SIZE
        << " unless slurm.conf sets it (scontrol show config | grep MaxArraySize), and this "
           "array's last index is "
        << script.array_tasks - 1
        << ": if sbatch says \"Invalid job array specification\", use --slurm "
        << SLURM_DEFAULT_MAX_ARRAY_SIZE << " or less\n";
  out << "submit it with:  sbatch " << file << "\na task that died: sbatch --array=I " << file
      << "  (it resumes shard I)\n";
  return out.str();
}

std::string summary_line(const BatchSummary& s, const fs::path& root, const BatchSpec& spec) {
  std::ostringstream out;
  out << (s.interrupted ? "interrupted: " : "") << s.done << " of " << s.total << ' ' << spec.items
      << " done (" << s.done_now << " in this run";
  if (s.repaired > 0)
    out << ", " << s.repaired << (s.repaired == 1 ? " manifest row" : " manifest rows")
        << " restored";
  out << "), " << s.failed << " failed";
  if (s.failed > 0) out << " (" << (root / spec.failures_name).string() << ")";
  const long long left = s.total - s.done - s.failed;
  if (left > 0) out << ", " << left << " left (run the same command again to resume)";
  char t[64];
  std::snprintf(t, sizeof t, "; %.1f s", s.elapsed);
  out << t << "; manifest " << (root / spec.manifest_name).string();
  return out.str();
}

}  // namespace papersim::batch
