// The batch runner on small shell commands: finished tasks are never redone, failures are
// recorded with their reason and do not stop the batch, the time limit kills, a lost manifest
// row is restored, shards partition the tasks, and concurrent appends never interleave.
#include "batch/runner.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <thread>

#include "batch/cli.hpp"
#include "batch/slurm.hpp"
#include "common/errors.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using papersim::batch::BatchSpec;
using papersim::batch::Command;
using papersim::batch::KeySet;
using papersim::batch::Task;

namespace {

fs::path fresh_dir(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("papersim_runner_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  return d;
}

papersim::batch::TaskList numbered_tasks(int n) {
  papersim::batch::TaskList tasks;
  for (int i = 0; i < n; ++i)
    tasks.push_back({"t/" + std::to_string(i), json{{"index", i}}.dump()});
  return tasks;
}

/// The word in a task folder's file "value".
std::string value_in(const fs::path& dir) {
  std::ifstream in(dir / "value");
  std::string v;
  in >> v;
  return v;
}

/// Each task runs `script` in sh with $1 = its output folder and $2 = its index; a run count
/// per task is appended to ROOT/runs.txt so a test can tell what ran.
BatchSpec shell_spec(const fs::path& root, const std::string& script) {
  BatchSpec spec;
  spec.root = root;
  spec.jobs = 2;
  spec.commands = [root, script](const Task& t, const fs::path& stage) {
    const std::string index = std::to_string(t.info_object().at("index").get<int>());
    return std::vector<Command>{{{"/bin/sh", "-c",
                                  "echo " + index + " >> '" + (root / "runs.txt").string() +
                                      "'; mkdir -p \"$1\" && " + script,
                                  "sh", (stage / "out").string(), index},
                                 {}}};
  };
  spec.finalize = [](const Task&, const papersim::batch::Attempt& a) { return a.stage / "out"; };
  spec.manifest_row = [](const Task&, const fs::path& dir, double) {
    return json{{"value", value_in(dir)}};
  };
  return spec;
}

/// The exit status of `f` run in a forked child under a file size limit of `bytes` (SIGXFSZ
/// ignored, so a write past it is a short write, as on a full disk): 7 when `f` threw
/// common::OutputError, 0 when it returned, -1 when the child did not exit.
int status_under_file_size_limit(rlim_t bytes, const std::function<void()>& f) {
  const pid_t pid = fork();
  if (pid == 0) {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{bytes, bytes};
    setrlimit(RLIMIT_FSIZE, &limit);
    try {
      f();
    } catch (const papersim::common::OutputError&) {
      _exit(7);
    }
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Whether a file exists with a byte in it.
bool has_rows(const fs::path& p) { return fs::exists(p) && fs::file_size(p) > 0; }

std::vector<std::string> lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

}  // namespace

TEST(Runner, RunsEveryTaskOnceAndNeverRedoesAFinishedOne) {
  const fs::path root = fresh_dir("once");
  const auto tasks = numbered_tasks(6);
  const auto spec = shell_spec(root, "echo v$2 > \"$1/value\"");
  const auto first = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(first.done, 6);
  EXPECT_EQ(first.done_now, 6);
  EXPECT_EQ(lines(root / "runs.txt").size(), 6u);
  const auto rows = papersim::batch::read_json_lines(root / "manifest.jsonl");
  ASSERT_EQ(rows.size(), 6u);
  for (const auto& r : rows) EXPECT_EQ(r["value"], "v" + std::to_string(r["index"].get<int>()));
  const auto second = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(second.done, 6);
  EXPECT_EQ(second.done_now, 0);
  EXPECT_EQ(lines(root / "runs.txt").size(), 6u) << "a finished task ran again";
  EXPECT_TRUE(fs::is_empty(root / ".staging"));
  fs::remove_all(root);
}

TEST(Runner, FailuresAreRecordedWithTheirReasonAndTheRestFinishes) {
  const fs::path root = fresh_dir("fail");
  const auto tasks = numbered_tasks(6);
  auto spec = shell_spec(root,
                         "if [ $2 = 2 ]; then echo 'diverged at step 3' >&2; exit 3; fi; "
                         "if [ $2 = 4 ]; then sleep 30; fi; echo ok > \"$1/value\"");
  spec.time_limit = 1.0;
  spec.failure_reason = [](int code, const std::string&) {
    return code == 3 ? std::string("simulation failed") : std::string();
  };
  const auto s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.done, 4);
  EXPECT_EQ(s.failed, 2);
  EXPECT_LT(s.elapsed, 20.0) << "the time limit did not stop the sleeping task";
  std::map<int, json> failures;
  for (const auto& r : papersim::batch::read_json_lines(root / "failures.jsonl"))
    failures[r["index"].get<int>()] = r;
  ASSERT_EQ(failures.size(), 2u);
  EXPECT_EQ(failures[2]["reason"], "simulation failed");
  EXPECT_EQ(failures[2]["detail"], "diverged at step 3");
  EXPECT_EQ(failures[4]["reason"], "time limit");
  EXPECT_FALSE(fs::exists(root / "t" / "2"));
  // Recorded failures are skipped, and run again with retry_failed.
  EXPECT_EQ(papersim::batch::run_batch(tasks, spec).done_now, 0);
  EXPECT_EQ(lines(root / "runs.txt").size(), 6u);
  spec.retry_failed = true;
  const auto retry = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(lines(root / "runs.txt").size(), 8u);
  EXPECT_EQ(retry.failed_now, 2);
  fs::remove_all(root);
}

// The progress of running tasks that tell their share done: the runner asks for it before every
// progress call, and the command line's progress line shows it.
TEST(Runner, ProgressShowsTheShareOfRunningTasks) {
  const fs::path root = fresh_dir("share");
  const auto tasks = numbered_tasks(2);
  // Task 0 outlives task 1, so every progress call with a task running has task 0 among them.
  auto spec = shell_spec(root, "if [ $2 = 0 ]; then sleep 0.8; fi; echo ok > \"$1/value\"");
  spec.progress_every = 0.05;
  spec.running_share = [](const Task& t) {
    return t.info_object().at("index").get<int>() == 0 ? 0.414 : -1.0;
  };
  std::vector<std::vector<double>> seen;
  spec.progress = [&seen](const papersim::batch::Progress& p) {
    if (p.running > 0) seen.push_back(p.running_done);
  };
  EXPECT_EQ(papersim::batch::run_batch(tasks, spec).done, 2);
  ASSERT_FALSE(seen.empty());
  for (const auto& shares : seen)
    EXPECT_EQ(shares, std::vector<double>{0.414});  // task 1 tells none

  std::ostringstream line;
  papersim::batch::Progress p;
  p.total = 9;
  p.running = 6;
  p.running_done = {0.414, 0.17, 1.0, 0.0, 0.5};
  papersim::batch::progress_printer(line, false, "papersim batch")(p);
  EXPECT_NE(line.str().find("  running at 41%, 17%, 100%, 0%, ...\n"), std::string::npos)
      << line.str();
  // No task ended in this run: the rate is unknown, not zero.
  EXPECT_NE(line.str().find("  ? samples/h  ETA ?"), std::string::npos) << line.str();
  p.per_hour = 0.04;
  std::ostringstream known;
  papersim::batch::progress_printer(known, false, "papersim batch")(p);
  EXPECT_NE(known.str().find("  0.0 samples/h  "), std::string::npos) << known.str();
  fs::remove_all(root);
}

// The first progress call comes once the tasks are checked, before any runs: how many were done
// before. With progress_every far off, the calls are that one and the last.
TEST(Runner, TheFirstProgressTellsWhatWasDoneBeforeAnyTaskRuns) {
  const fs::path root = fresh_dir("first");
  auto spec = shell_spec(root, "echo ok > \"$1/value\"");
  papersim::batch::run_batch(numbered_tasks(1), spec);
  spec.progress_every = 1e6;
  std::vector<papersim::batch::Progress> seen;
  spec.progress = [&seen](const papersim::batch::Progress& p) { seen.push_back(p); };
  EXPECT_EQ(papersim::batch::run_batch(numbered_tasks(3), spec).done_now, 2);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].total, 3);
  EXPECT_EQ(seen[0].done, 1);
  EXPECT_EQ(seen[0].done_now, 0);
  EXPECT_EQ(seen[0].running, 0);
  EXPECT_EQ(seen[0].eta, -1.0);  // nothing known yet
  EXPECT_EQ(seen[0].per_hour, -1.0);
  EXPECT_EQ(seen[1].done, 3);
  EXPECT_EQ(seen[1].eta, 0.0);  // nothing left
  EXPECT_GT(seen[1].per_hour, 0.0);
  fs::remove_all(root);
}

// Checking the tasks against the dataset tells its progress: the tasks' folders looked for every
// 65,536 tasks, then the manifest (for the done tasks' rows) and the failures file (for the
// others') read in MB of their sizes every 4,096 lines. 70,000 tasks, 10 done with their rows and
// the rest recorded as failed: none runs. Then, with nothing done, the manifest is not read.
TEST(Runner, CheckingTheTasksTellsHowFarItHasReadAndReadsOnlyWhatItNeeds) {
  const fs::path root = fresh_dir("check");
  fs::create_directories(root);
  const int n = 70000, n_done = 10;
  papersim::batch::TaskList tasks;
  std::size_t first_failures = 0;  // bytes of the first 4,096 rows of the failures file
  {
    std::ofstream failures(root / "failures.jsonl"), manifest(root / "manifest.jsonl");
    for (int i = 0; i < 5000; ++i) manifest << json{{"key", "other/" + std::to_string(i)}} << '\n';
    for (int i = 0; i < n; ++i) {
      const std::string key = "t/" + std::to_string(i);
      tasks.push_back({key, "{}"});
      if (i < n_done) {
        fs::create_directories(root / key);
        manifest << json{{"key", key}} << '\n';
        continue;
      }
      const std::string row = json{{"key", key}, {"reason", "x"}}.dump();
      failures << row << '\n';
      if (i < n_done + 4096) first_failures += row.size() + 1;
    }
  }
  auto spec = shell_spec(root, "exit 1");
  struct Told {
    std::string what, unit;
    double done, total;
  };
  std::vector<Told> told;
  spec.step_progress = [&told](const std::string& what, double done, double total,
                               const std::string& unit) {
    told.push_back({what, unit, done, total});
  };
  const auto steps = [&told](const std::string& what) {
    std::vector<Told> out;
    for (const auto& t : told)
      if (t.what == what) out.push_back(t);
    return out;
  };
  const std::string reading_manifest = "reading " + (root / "manifest.jsonl").string();
  const std::string reading_failures = "reading " + (root / "failures.jsonl").string();
  // No stage is left, so the done tasks' rows are trusted: the manifest is not read.
  auto s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.done, n_done);
  EXPECT_EQ(s.failed, n - n_done);
  EXPECT_EQ(s.done_now + s.failed_now + s.repaired, 0);
  const auto l = steps("looking for the samples' folders");
  const auto f = steps(reading_failures);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_TRUE(steps(reading_manifest).empty());
  ASSERT_EQ(f.size(), (n - n_done) / 4096u);  // 17
  EXPECT_EQ(l.size() + f.size(), told.size());
  EXPECT_EQ(told.front().what, l[0].what);  // the folders first
  EXPECT_EQ(l[0].done, 65535.0);
  EXPECT_EQ(l[0].total, static_cast<double>(n));
  EXPECT_EQ(l[0].unit, "samples");
  // A stage of a done task left behind: the manifest is read (5,010 lines), for its row.
  fs::create_directories(root / ".staging" / "t_3.123.0");
  told.clear();
  s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.done_now + s.failed_now + s.repaired, 0);
  const auto m = steps(reading_manifest);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_DOUBLE_EQ(m[0].total, static_cast<double>(fs::file_size(root / "manifest.jsonl")) / 1e6);
  EXPECT_FALSE(fs::exists(root / ".staging" / "t_3.123.0"));
  const double f_size = static_cast<double>(fs::file_size(root / "failures.jsonl")) / 1e6;
  EXPECT_DOUBLE_EQ(f[0].done, static_cast<double>(first_failures) / 1e6);
  for (std::size_t i = 0; i < f.size(); ++i) {
    EXPECT_EQ(f[i].unit, "MB");
    EXPECT_DOUBLE_EQ(f[i].total, f_size);
    EXPECT_GT(f[i].done, i > 0 ? f[i - 1].done : 0.0);
    EXPECT_LE(f[i].done, f_size);
  }

  // Nothing done: the manifest is not read; the 10 tasks without a failure run (and fail).
  fs::remove_all(root / "t");
  told.clear();
  s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.done, 0);
  EXPECT_EQ(s.failed_now, n_done);
  EXPECT_EQ(s.failed, n);
  EXPECT_TRUE(steps(reading_manifest).empty());
  EXPECT_EQ(steps(reading_failures).size(), (n - n_done) / 4096u);
  fs::remove_all(root);
}

// The step printer: nothing in a step's first second, then on a terminal the line redrawn.
TEST(Runner, TheStepPrinterShowsAStepAfterItsFirstSecondWithItsEta) {
  std::ostringstream out;
  const auto print = papersim::batch::step_printer(out, true, "papersim batch");
  print("drawing the samples", 1, 10, "samples");
  EXPECT_EQ(out.str(), "");
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  print("drawing the samples", 5, 10, "samples");
  EXPECT_EQ(out.str(),
            "\r\033[Kpapersim batch: drawing the samples: 5 of 10 samples, 1 s, ETA 1 s");
  print("reading m", 1, 2, "MB");  // a new step: its own first second
  EXPECT_EQ(out.str().find("reading"), std::string::npos);
}

// Before any task ends, the ETA comes from the running tasks' shares: the rest of each, and the
// whole of each task left at the mean duration those rates give, shared by the jobs.
TEST(Runner, EtaFromRunningSharesSharesTheWorkLeftAmongTheJobs) {
  using papersim::batch::eta_from_running;
  // 50 s and 150 s left of tasks of 100 s and 200 s: two more tasks of 150 s each.
  const std::vector<papersim::batch::RunningRate> two = {{0.5, 0.01}, {0.25, 0.005}};
  EXPECT_NEAR(eta_from_running(two, 2, 2), (50.0 + 150.0 + 2 * 150.0) / 2, 1e-9);
  EXPECT_NEAR(eta_from_running(two, 0, 2), 150.0, 1e-9);  // the slowest running task
  EXPECT_NEAR(eta_from_running(two, 2, 1), 500.0, 1e-9);
  // Tasks not seen to progress tell nothing; a share past 1 has nothing left.
  EXPECT_EQ(eta_from_running({{0.3, 0.0}}, 3, 2), -1.0);
  EXPECT_EQ(eta_from_running({}, 3, 2), -1.0);
  EXPECT_NEAR(eta_from_running({{1.2, 0.1}, {0.3, 0.0}}, 0, 1), 0.0, 1e-9);
}

TEST(Runner, ProgressHasAnEtaBeforeAnyTaskEndsWhenTheRunningOnesTellTheirShare) {
  const fs::path root = fresh_dir("eta");
  const auto tasks = numbered_tasks(1);
  auto spec = shell_spec(root, "sleep 1; echo ok > \"$1/value\"");
  spec.progress_every = 0.05;
  const auto t0 = std::chrono::steady_clock::now();
  // A task that does half of its work per second: 2 s in all.
  spec.running_share = [t0](const Task&) {
    return std::min(
        1.0, 0.5 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  };
  std::vector<double> etas;
  spec.progress = [&etas](const papersim::batch::Progress& p) {
    if (p.running > 0 && p.done_now == 0) etas.push_back(p.eta);
  };
  EXPECT_EQ(papersim::batch::run_batch(tasks, spec).done, 1);
  ASSERT_GE(etas.size(), 3u);
  EXPECT_EQ(etas.front(), -1.0);  // one reading gives no rate
  const double last = etas.back();
  // The rest of a 2 s task read shortly before its command ends at 1 s: about 1 s, and below
  // 1.95 s once 2.5% of it has passed (the rate is read off the same clock as the share).
  EXPECT_GT(last, 0.0);
  EXPECT_LT(last, 1.95);
  fs::remove_all(root);
}

// A crash between a task's rename and its row's append leaves the task's stage (removed only
// after the append): the next run restores the row of a done task with a stage left, and removes
// the stage. Where no stage is left the manifest is trusted and not read; a missing (or empty)
// manifest is rebuilt whole.
TEST(Runner, RestoresTheManifestRowOfATaskFinishedBeforeACrash) {
  const fs::path root = fresh_dir("repair");
  const auto tasks = numbered_tasks(4);
  const auto spec = shell_spec(root, "echo v$2 > \"$1/value\"");
  EXPECT_EQ(papersim::batch::run_batch(tasks, spec).done_now, 4);
  EXPECT_TRUE(fs::is_empty(root / ".staging"));
  // Rows of t/0 only; t/2 and t/3 crashed in the window (a stage each, t/3 two from two
  // attempts); t/1's row was lost otherwise.
  const auto rows = lines(root / "manifest.jsonl");
  ASSERT_EQ(rows.size(), 4u);
  std::ofstream(root / "manifest.jsonl") << rows[0] << '\n';
  const auto row_of = [&](const std::string& key) {
    for (const auto& r : papersim::batch::read_json_lines(root / "manifest.jsonl"))
      if (r["key"] == key) return r;
    return json();
  };
  const std::string t0 = row_of("t/0").dump();
  for (const char* stage : {"t_2.4242.0", "t_3.4242.1", "t_3.77.0", "t_1x.5.0", "t_1.x.0"}) {
    fs::create_directories(root / ".staging" / stage);
    std::ofstream(root / ".staging" / stage / "log.txt") << "log\n";
  }
  auto s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.repaired, 2);
  EXPECT_EQ(s.done_now, 0);
  EXPECT_EQ(s.done, 4);
  EXPECT_EQ(lines(root / "manifest.jsonl").size(), 3u);
  EXPECT_EQ(row_of("t/0").dump(), t0);
  for (const char* key : {"t/2", "t/3"}) {
    const json r = row_of(key);
    EXPECT_EQ(r["value"], std::string("v") + key[2]) << key;
    EXPECT_TRUE(r["cpu_seconds"].is_null()) << key;
  }
  EXPECT_TRUE(row_of("t/1").is_null());
  // The stages of t/2 and t/3 went; names of no task's stage stay.
  std::set<std::string> left;
  for (const auto& e : fs::directory_iterator(root / ".staging"))
    left.insert(e.path().filename().string());
  EXPECT_EQ(left, (std::set<std::string>{"t_1x.5.0", "t_1.x.0"}));
  // A stage whose row is there already: nothing is added, the stage goes.
  fs::create_directories(root / ".staging" / "t_0.9.3");
  s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.repaired, 0);
  EXPECT_FALSE(fs::exists(root / ".staging" / "t_0.9.3"));
  EXPECT_EQ(lines(root / "manifest.jsonl").size(), 3u);
  // The manifest moved away: every done task's row is rebuilt.
  fs::rename(root / "manifest.jsonl", root / "old.jsonl");
  s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.repaired, 4);
  EXPECT_EQ(lines(root / "manifest.jsonl").size(), 4u);
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(row_of("t/" + std::to_string(i))["value"], "v" + std::to_string(i));
  fs::remove_all(root);
}

// The row of a finished task that cannot be appended (here a file size limit; on a full disk the
// same short write) stops the batch, and the task's stage stays with its folder in place, so the
// next run restores the row instead of trusting the manifest.
TEST(Runner, ARowThatCouldNotBeAppendedIsRestoredByTheNextRun) {
  const fs::path root = fresh_dir("rowlost");
  const auto tasks = numbered_tasks(1);
  auto spec = shell_spec(root, "echo ok > \"$1/value\"");
  spec.jobs = 1;
  spec.manifest_row = [](const Task&, const fs::path& dir, double) {
    return json{{"value", value_in(dir)}, {"pad", std::string(3000, 'x')}};
  };
  // 1,000 bytes: the shell's writes fit, the row does not.
  ASSERT_EQ(status_under_file_size_limit(1000, [&] { papersim::batch::run_batch(tasks, spec); }), 7)
      << "the row that could not be appended was not reported";
  EXPECT_TRUE(fs::exists(root / "t" / "0"));
  EXPECT_EQ(fs::file_size(root / "manifest.jsonl"), 0u);
  ASSERT_EQ(std::distance(fs::directory_iterator(root / ".staging"), fs::directory_iterator()), 1);
  std::ofstream(root / "manifest.jsonl") << json{{"key", "other"}} << '\n';  // not empty
  const auto s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.repaired, 1);
  EXPECT_EQ(s.done_now, 0);
  const auto rows = papersim::batch::read_json_lines(root / "manifest.jsonl");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1]["key"], "t/0");
  EXPECT_EQ(rows[1]["value"], "ok");
  EXPECT_TRUE(fs::is_empty(root / ".staging"));
  fs::remove_all(root);
}

// A batch ignores SIGPIPE (batch::keep_running_without_readers); the programs it starts get the
// default action back, as an ignored signal would stay ignored across exec.
TEST(Runner, TheTasksProgramsGetTheDefaultActionOfSigpipe) {
  const fs::path root = fresh_dir("sigpipe");
  const auto tasks = numbered_tasks(2);
  auto spec = shell_spec(root, "awk '/^SigIgn:/ { print $2 }' /proc/self/status > \"$1/value\"");
  struct sigaction ignore {
  }, before{};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, &before);
  const auto s = papersim::batch::run_batch(tasks, spec);
  sigaction(SIGPIPE, &before, nullptr);
  ASSERT_EQ(s.done, 2);
  for (const char* t : {"0", "1"}) {
    const std::string mask = value_in(root / "t" / t);
    ASSERT_EQ(mask.size(), 16u) << mask;  // the ignored signals, in hex
    EXPECT_EQ(std::stoull(mask, nullptr, 16) & (1ull << (SIGPIPE - 1)), 0u) << mask;
  }
  fs::remove_all(root);
}

// The last line of a batch: what is done, restored, failed and left, in words that fit the count.
TEST(Runner, TheSummaryLineCountsInWords) {
  papersim::batch::BatchSummary s;
  s.total = 5;
  s.done = 3;
  s.done_now = 1;
  s.repaired = 1;
  papersim::batch::BatchSpec spec;
  const fs::path root = "/data/ds";
  const std::string one = papersim::batch::summary_line(s, root, spec);
  EXPECT_EQ(one.rfind("3 of 5 samples done (1 in this run, 1 manifest row restored), 0 failed, 2 "
                      "left (run the same command again to resume)",
                      0),
            0u)
      << one;
  s.repaired = 2;
  s.failed = 1;
  const std::string two = papersim::batch::summary_line(s, root, spec);
  EXPECT_NE(
      two.find("(1 in this run, 2 manifest rows restored), 1 failed (/data/ds/failures.jsonl), "
               "1 left"),
      std::string::npos)
      << two;
}

// A finished task's folder without a row, from which no row can be made (its files damaged):
// the batch stops before any task runs, naming the folder; no row is made up for it.
TEST(Runner, AFinishedFolderWhoseRowCannotBeMadeStopsTheBatchNamingIt) {
  const fs::path root = fresh_dir("damaged");
  const auto tasks = numbered_tasks(3);
  auto spec = shell_spec(root, "echo ok > \"$1/value\"");
  spec.manifest_row = [](const Task&, const fs::path& dir, double) {
    if (!fs::exists(dir / "value")) throw std::runtime_error("no value in it");
    return json{{"value", value_in(dir)}};
  };
  fs::create_directories(root / "t" / "1");  // done, but empty
  try {
    papersim::batch::run_batch(tasks, spec);
    ADD_FAILURE() << "the batch went on";
  } catch (const papersim::batch::DatasetError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'" + (root / "t" / "1").string() + "' is finished"), std::string::npos) << m;
    EXPECT_NE(m.find("no value in it"), std::string::npos) << m;
  }
  EXPECT_FALSE(fs::exists(root / "runs.txt"));
  EXPECT_FALSE(has_rows(root / "manifest.jsonl"));
  // Removed, as the message says: the task is made again with the others.
  fs::remove_all(root / "t" / "1");
  EXPECT_EQ(papersim::batch::run_batch(tasks, spec).done_now, 3);
  fs::remove_all(root);
}

// A task's stage is named after its key: starting a task removes its own earlier stages, not
// the stage of a running task whose name begins with it ("m/a" and "m/a.5").
TEST(Runner, StartingATaskLeavesTheStagesOfOtherTasksAlone) {
  const fs::path root = fresh_dir("stagenames");
  papersim::batch::TaskList tasks;
  tasks.push_back({"m/a.5", json{{"index", 0}}.dump()});
  tasks.push_back({"m/a", json{{"index", 1}}.dump()});
  auto spec = shell_spec(root, "if [ $2 = 0 ]; then sleep 1; fi; echo v$2 > \"$1/value\"");
  spec.jobs = 2;
  const auto s = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(s.done_now, 2);
  EXPECT_EQ(s.failed, 0);
  EXPECT_TRUE(fs::exists(root / "m" / "a.5" / "value"));
  fs::remove_all(root);
}

// The scan looks up the tasks of a parent folder of few by `stat` and lists a parent of many
// once: either way a task is finished exactly when fs::exists says its folder is there, whether
// that is a folder, a file, a link to a folder, in one of many parents (more than the scan keeps
// listed at once); not when only another name is there or a parent is missing.
TEST(Runner, AFinishedTaskIsOneWhoseFolderExists) {
  const fs::path root = fresh_dir("exists");
  papersim::batch::TaskList tasks;
  for (int p = 0; p < 300; ++p)  // 300 parents, two tasks each, the second made below
    for (int i = 0; i < 2; ++i)
      tasks.push_back(papersim::batch::Task::in_folder(
          "p" + std::to_string(p) + "/" + std::to_string(i), json{{"index", 2 * p + i}}));
  for (int q = 0; q < 10; ++q)  // two levels down: q0-q4 hold x/0, q5-q9 are missing
    tasks.push_back(papersim::batch::Task::in_folder("q" + std::to_string(q) + "/x/0",
                                                     json{{"index", 600 + q}}));
  for (int r = 0; r < 6; ++r)  // 6 parents of 20 tasks, listed: r0-r4 hold 15 each, r5 is missing
    for (int i = 0; i < 20; ++i)
      tasks.push_back(papersim::batch::Task::in_folder(
          "r" + std::to_string(r) + "/" + std::to_string(i), json{{"index", 610 + 20 * r + i}}));
  fs::create_directories(root / "elsewhere");
  std::set<std::string> made;  // the indices of the tasks whose folder is made here
  for (int r = 0; r < 5; ++r)
    for (int i = 0; i < 20; ++i) {
      const fs::path dir = root / ("r" + std::to_string(r)) / std::to_string(i);
      if (i % 4 == 3) continue;
      fs::create_directories(dir.parent_path());
      if (i % 4 == 0) fs::create_directories(dir);
      if (i % 4 == 1) std::ofstream(dir) << "a file\n";
      if (i % 4 == 2) fs::create_directory_symlink(root / "elsewhere", dir);
      made.insert(std::to_string(610 + 20 * r + i));
    }
  for (int q = 0; q < 5; ++q) {
    fs::create_directories(root / ("q" + std::to_string(q)) / "x" / "0");
    made.insert(std::to_string(600 + q));
  }
  for (int p = 0; p < 300; ++p) {
    const fs::path dir = root / ("p" + std::to_string(p));
    if (p % 50 == 49) continue;  // a missing parent
    fs::create_directories(dir / "0");
    made.insert(std::to_string(2 * p));
    if (p % 50 == 48) {
      fs::create_directories(dir / "11");  // another name only
      continue;
    }
    if (p % 3 == 0) fs::create_directories(dir / "1");
    if (p % 3 == 1) std::ofstream(dir / "1") << "a file\n";
    if (p % 3 == 2) fs::create_directory_symlink(root / "elsewhere", dir / "1");
    made.insert(std::to_string(2 * p + 1));
  }
  const auto spec = shell_spec(root, "echo ok > \"$1/value\"");
  papersim::batch::BatchSpec quick = spec;
  quick.jobs = 8;
  // The 662 rows are restored under a limit of 400 open files (a task's lock is an open file).
  rlimit files{};
  ASSERT_EQ(getrlimit(RLIMIT_NOFILE, &files), 0);
  const rlimit low{std::min<rlim_t>(400, files.rlim_cur), files.rlim_max};
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &low), 0);
  papersim::batch::BatchSummary s;
  try {
    s = papersim::batch::run_batch(tasks, quick);
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
  }
  setrlimit(RLIMIT_NOFILE, &files);
  EXPECT_EQ(s.done, 730);
  EXPECT_EQ(made.size(), 662u);  // 294 + 288 of the p parents, 5 of q, 75 of r
  EXPECT_EQ(s.repaired, static_cast<long long>(made.size()));
  EXPECT_EQ(s.done_now, 730 - static_cast<long long>(made.size()));
  for (const auto& ran : lines(root / "runs.txt"))
    EXPECT_EQ(made.count(ran), 0u) << "task " << ran << " was finished and ran";
  fs::remove_all(root);
}

TEST(Runner, ManifestKeysAreFoundByTheRowsOwnKeyOnly) {
  // keys_in_json_lines skips the parse of lines that name no wanted key; what it returns must
  // still be exactly the wanted keys that are some whole row's own "key".
  const fs::path root = fresh_dir("keys");
  fs::create_directories(root);
  const fs::path file = root / "manifest.jsonl";
  std::ofstream(file) << R"({"key":"m/0","seed":0})" << '\n'
                      << R"({"key":"m/1","set":{"key":"m/2"}})" << '\n'  // m/2 only nested
                      << R"({"a":1, "key" : "m/3"})" << '\n'             // spaces around the colon
                      << R"({"key":"m\/4","note":"\"key\":\"m/5\""})"
                      << '\n'                                     // escapes: m/4, not m/5
                      << R"({"key":"m/6","not":"a row")" << '\n'  // cut short: not a row
                      << R"(["key","m/7"])" << '\n'               // not an object
                      << R"({"key":"m/9","key":5})" << '\n'       // the last "key" counts
                      << R"({"key":7,"key":"m/10"})" << '\n'
                      << R"({"key":"m/13","key":{"a":"m/13"}})" << '\n'
                      << R"({"x":[{"key":"m/12"}],"key":"m/11"})" << '\n'
                      << "{\"key\"\r:\r\"m/14\"}\r\n"  // '\r' is white space in JSON
                      << R"({"key":"m/8"})";           // a last line without newline
  const auto set_of = [](std::initializer_list<const char*> keys) {
    KeySet s;
    for (const char* k : keys) s.insert(k);
    return s;
  };
  const std::vector<std::string> asked{"m/0", "m/2", "m/3",  "m/4",  "m/5",  "m/6",  "m/7",
                                       "m/8", "m/9", "m/10", "m/11", "m/12", "m/13", "m/14"};
  KeySet wanted;
  for (const auto& k : asked) wanted.insert(k);
  const KeySet found = papersim::batch::keys_in_json_lines(file, wanted);
  std::vector<std::string> found_keys;
  for (const auto& k : asked)
    if (found.contains(k)) found_keys.push_back(k);
  EXPECT_EQ(found_keys,
            (std::vector<std::string>{"m/0", "m/3", "m/4", "m/8", "m/10", "m/11", "m/14"}));
  EXPECT_EQ(found.size(), 7u);
  // m/1 is a row but not wanted; nothing is found in a missing file or for no wanted key.
  EXPECT_TRUE(papersim::batch::keys_in_json_lines(file, set_of({"m/1"})).contains("m/1"));
  EXPECT_EQ(papersim::batch::keys_in_json_lines(root / "none.jsonl", wanted).size(), 0u);
  EXPECT_EQ(papersim::batch::keys_in_json_lines(file, KeySet()).size(), 0u);
  // The same answer as reading every row.
  std::vector<std::string> all;
  for (const auto& r : papersim::batch::read_json_lines(file))
    if (r.contains("key") && r["key"].is_string() && wanted.contains(r["key"].get<std::string>()))
      all.push_back(r["key"]);
  std::sort(all.begin(), all.end());
  std::sort(found_keys.begin(), found_keys.end());
  EXPECT_EQ(found_keys, all);
  // From an offset: the search starts there and ends at the end of the last whole line, so a
  // line being appended (no newline yet) is searched again once it is whole.
  const fs::path grows = root / "grows.jsonl";
  const std::string first = R"({"key":"g/0"})"
                            "\n"
                            R"({"key":"g/1"})"
                            "\n";
  std::ofstream(grows) << first << R"({"key":"g/2")";
  std::uintmax_t offset = 0;
  EXPECT_EQ(papersim::batch::keys_in_json_lines(grows, set_of({"g/0", "g/2"}), {}, &offset).size(),
            1u);
  EXPECT_EQ(offset, first.size());
  std::ofstream(grows, std::ios::app) << "}\n"
                                      << R"({"key":"g/3"})" << '\n';
  const KeySet tail =
      papersim::batch::keys_in_json_lines(grows, set_of({"g/0", "g/2", "g/3"}), {}, &offset);
  EXPECT_EQ(tail.size(), 2u);
  EXPECT_TRUE(tail.contains("g/2") && tail.contains("g/3"));
  EXPECT_EQ(offset, fs::file_size(grows));
  fs::remove_all(root);
}

// A failure's detail is the child's last log line, any bytes: one that is not UTF-8 (a path
// with 0xFF in it) made the row's dump throw and the batch end with an internal error.
TEST(Runner, AFailureWhoseLastLineIsNotUtf8IsRecorded) {
  const fs::path root = fresh_dir("utf8");
  const auto spec = shell_spec(root, "printf 'cannot read /data/page\\377.png\\n' >&2; exit 3");
  const auto s = papersim::batch::run_batch(numbered_tasks(2), spec);
  EXPECT_EQ(s.failed, 2);
  const auto f = papersim::batch::read_json_lines(root / "failures.jsonl");
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0]["detail"], "cannot read /data/page\xef\xbf\xbd.png");
  fs::remove_all(root);
}

TEST(Runner, AFailedOutputCheckIsRecordedAndLeavesNoFolder) {
  const fs::path root = fresh_dir("outputs");
  auto spec = shell_spec(root, "true");
  spec.finalize = [](const Task&, const papersim::batch::Attempt&) -> fs::path {
    throw std::runtime_error("missing sheet.obj");
  };
  const auto s = papersim::batch::run_batch(numbered_tasks(2), spec);
  EXPECT_EQ(s.failed, 2);
  const auto f = papersim::batch::read_json_lines(root / "failures.jsonl");
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0]["reason"], "outputs");
  EXPECT_FALSE(fs::exists(root / "t"));
  fs::remove_all(root);
}

// A child that exits with status 5 cannot write its output (a full disk): every later sample
// would fail the same way at its end, so the batch stops at once, records nothing for it, kills
// the sample running beside it and removes its staging folders; the same call later finishes
// every task.
TEST(Runner, AChildThatCannotWriteStopsTheBatchAndRecordsNoFailure) {
  const fs::path root = fresh_dir("nospace");
  const auto tasks = numbered_tasks(6);
  const fs::path full = root / "full";  // the disk is full while this file exists
  const auto spec = shell_spec(
      root,
      "if [ -e '" + full.string() +
          "' ]; then if [ $2 = 1 ]; then "
          "echo 'cannot write output: No space left on device' >&2; exit 5; fi; sleep 30; fi; "
          "echo ok > \"$1/value\"");
  fs::create_directories(root);
  std::ofstream(full) << "";
  const auto start = std::chrono::steady_clock::now();
  try {
    papersim::batch::run_batch(tasks, spec);
    ADD_FAILURE() << "the batch went on after a child could not write";
  } catch (const papersim::common::OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("t/1: cannot write output: No space left on device"),
              std::string::npos)
        << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0)
      << "the sample running beside it was not stopped";
  EXPECT_TRUE(papersim::batch::read_json_lines(root / "failures.jsonl").empty());
  EXPECT_TRUE(papersim::batch::read_json_lines(root / "manifest.jsonl").empty());
  EXPECT_TRUE(fs::is_empty(root / ".staging"));
  // Task 1 ran; task 0, started beside it, may have been stopped before its shell wrote its line.
  std::vector<std::string> ran = lines(root / "runs.txt");
  std::sort(ran.begin(), ran.end());
  EXPECT_TRUE(ran == std::vector<std::string>{"1"} || ran == (std::vector<std::string>{"0", "1"}))
      << "a task started after the batch should have stopped: " << ran.size() << " ran";
  fs::remove(full);
  const auto again = papersim::batch::run_batch(tasks, spec);
  EXPECT_EQ(again.done_now, 6);
  EXPECT_EQ(again.failed, 0);
  fs::remove_all(root);
}

// A line that cannot be written whole (here a file size limit 100 bytes above the file's size;
// on a full disk the same short write) is cut off again: the file keeps its whole lines, and a
// line appended later is read back.
TEST(Runner, AnAppendThatCannotBeWrittenWholeLeavesOnlyWholeLines) {
  const fs::path root = fresh_dir("shortappend");
  fs::create_directories(root);
  const fs::path file = root / "rows.jsonl";
  papersim::batch::append_line(file, json{{"i", 0}}.dump());
  const auto size = fs::file_size(file);
  EXPECT_EQ(status_under_file_size_limit(
                size + 100,
                [&] {
                  papersim::batch::append_line(
                      file, json{{"i", 1}, {"pad", std::string(3000, 'x')}}.dump());
                }),
            7)
      << "the short append was not reported";
  EXPECT_EQ(fs::file_size(file), size) << "the cut line was left in the file";
  papersim::batch::append_line(file, json{{"i", 2}}.dump());
  const auto rows = papersim::batch::read_json_lines(file);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1]["i"], 2);
  fs::remove_all(root);
}

TEST(Runner, ShardsPartitionTheTasks) {
  const auto tasks = numbered_tasks(23);
  std::multiset<std::string> seen;
  for (int i = 0; i < 4; ++i)
    for (const auto& t : papersim::batch::select_shard(tasks, i, 4)) seen.insert(t.key);
  EXPECT_EQ(seen.size(), 23u);
  EXPECT_EQ(std::set<std::string>(seen.begin(), seen.end()).size(), 23u);
  EXPECT_EQ(papersim::batch::parse_shard("3/4", "--shard"), std::make_pair(3, 4));
  for (const char* bad : {"4/4", "-1/4", "1", "a/b", "1/0", "1/4x"})
    EXPECT_THROW(papersim::batch::parse_shard(bad, "--shard"), std::invalid_argument) << bad;
  try {
    papersim::batch::parse_shard("5/2", "--shard");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--shard"), std::string::npos);
  }
}

TEST(Runner, ConcurrentAppendsNeverInterleave) {
  const fs::path root = fresh_dir("append");
  fs::create_directories(root);
  const fs::path file = root / "rows.jsonl";
  const std::string pad(3000, 'x');  // lines far above PIPE_BUF
  std::vector<pid_t> kids;
  for (int w = 0; w < 4; ++w) {
    const pid_t pid = fork();
    if (pid == 0) {
      for (int i = 0; i < 100; ++i)
        papersim::batch::append_line(file, json{{"w", w}, {"i", i}, {"pad", pad}}.dump());
      _exit(0);
    }
    kids.push_back(pid);
  }
  for (pid_t p : kids) waitpid(p, nullptr, 0);
  const auto all = lines(file);
  EXPECT_EQ(all.size(), 400u);
  EXPECT_EQ(papersim::batch::read_json_lines(file).size(), 400u) << "a line was torn";
  fs::remove_all(root);
}

TEST(Slurm, ScriptMapsTheArrayIndexToTheShard) {
  papersim::batch::SlurmOptions o;
  o.shards = 8;
  o.cpus_per_task = 4;
  o.mem = "8G";
  o.time = "02:00:00";
  o.partition = "cpu";
  const std::string s = papersim::batch::slurm_script(
      {"/opt/papersim", "batch", "--out", "/data/it's"}, o, "/data/slurm");
  for (const char* line :
       {"#SBATCH --array=0-7\n", "#SBATCH --cpus-per-task=4\n", "#SBATCH --mem=\"8G\"\n",
        "#SBATCH --time=\"02:00:00\"\n", "#SBATCH --partition=\"cpu\"\n",
        "#SBATCH --output=\"/data/slurm/%A_%a.out\"\n",
        "exec '/opt/papersim' 'batch' '--out' '/data/it'\\''s' --shard "
        "\"${SLURM_ARRAY_TASK_ID}/8\""})
    EXPECT_NE(s.find(line), std::string::npos) << line << "\nin\n" << s;
  o.shards = 0;
  EXPECT_THROW(papersim::batch::slurm_script({"x"}, o, "/tmp"), std::invalid_argument);
}

TEST(Slurm, AScriptPathIsPrintedAsBashTakesIt) {
  EXPECT_EQ(papersim::batch::shell_word("/scratch/DS/slurm/papersim-batch.sbatch"),
            "/scratch/DS/slurm/papersim-batch.sbatch");
  EXPECT_EQ(papersim::batch::shell_word("/data/my data #2/it's.sbatch"),
            "'/data/my data #2/it'\\''s.sbatch'");
  EXPECT_EQ(papersim::batch::shell_word("a$b"), "'a$b'");
  EXPECT_EQ(papersim::batch::shell_word(""), "''");
}

// sbatch 22.05 ends a directive's value at white space or '#' unless it is quoted: a dataset
// folder named "my data #2" made sbatch refuse the script ("Invalid directive"). Values are in
// double quotes now (the Slurm test runs such a folder on a real cluster); what no #SBATCH line
// can hold is refused, naming it.
TEST(Slurm, DirectiveValuesAreQuotedAndWhatNoLineCanHoldIsRefused) {
  papersim::batch::SlurmOptions o;
  const std::string s =
      papersim::batch::slurm_script({"/opt/papersim"}, o, "/data/my data #2 \"q\"/slurm");
  EXPECT_NE(s.find("#SBATCH --output=\"/data/my data #2 \\\"q\\\"/slurm/%A_%a.out\"\n"),
            std::string::npos)
      << s;
  const auto refused = [&](const std::string& log_dir, const std::string& part) {
    try {
      (void)papersim::batch::slurm_script({"/opt/papersim"}, o, log_dir);
      ADD_FAILURE() << "accepted " << log_dir;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(log_dir), std::string::npos) << e.what();
    }
  };
  refused("/data/a%Ab/slurm", "has a '%'");
  refused("/data/a\\b/slurm", "has a backslash");
  refused("/data/a\nb/slurm", "has a line break");
  o.mem = "";
  EXPECT_THROW((void)papersim::batch::slurm_script({"/opt/papersim"}, o, "/data/slurm"),
               std::invalid_argument);
  o.mem = "2G\n#SBATCH --exclusive";
  try {
    (void)papersim::batch::slurm_script({"/opt/papersim"}, o, "/data/slurm");
    ADD_FAILURE() << "accepted a line break in --slurm-mem";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--slurm-mem"), std::string::npos) << e.what();
  }
}
