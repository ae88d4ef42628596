// Slurm for real: a one-node cluster on this machine (scripts/slurm_cluster.sh) runs the job
// arrays papersim batch --slurm and scenegen batch --slurm write for 8 small meshes and 8 small
// renders; one array task is cancelled mid-run and submitted again; the dataset must then be
// complete and equal to a local batch of the same seeds.
#include "batch/slurm.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <set>
#include <thread>

#include "batch/runner.hpp"
#include "dataset_tree.hpp"

namespace fs = std::filesystem;
namespace pt = papersim::test;

namespace {

const std::string PAPERSIM = PAPERSIM_EXE, SCENEGEN = SCENEGEN_EXE;
const std::string CLUSTER_SCRIPT = CLUSTER_SCRIPT_PATH;

/// stdout of a shell command, trailing newlines removed.
std::string shell(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  pclose(p);
  while (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

bool wait_until(const std::function<bool()>& done, double seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!done()) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > seconds)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return true;
}

/// Wait until no task of job `id` is pending or running.
bool wait_for_job(const std::string& id) {
  return wait_until([&] { return shell("squeue -h -j " + id + " 2>/dev/null").empty(); }, 240);
}

/// The cluster lives as long as the test; its daemons are stopped by their process ids.
class Cluster {
 public:
  explicit Cluster(const fs::path& dir) : m_dir(dir) {
    m_started =
        std::system(("bash '" + CLUSTER_SCRIPT + "' start '" + dir.string() + "'").c_str()) == 0;
    setenv("SLURM_CONF", (dir / "slurm.conf").c_str(), 1);
  }
  ~Cluster() {
    std::system(("bash '" + CLUSTER_SCRIPT + "' stop '" + m_dir.string() + "'").c_str());
  }
  Cluster(const Cluster&) = delete;
  Cluster& operator=(const Cluster&) = delete;
  bool started() const { return m_started; }

 private:
  fs::path m_dir;
  bool m_started = false;
};

std::vector<std::string> mesh_args(const fs::path& out) {
  // 0.3 s of simulated time (30 steps) so a task is still at work when it is cancelled.
  return {PAPERSIM, "batch",   "--out", out.string(), "--mix",
          TINY_MIX, "--seeds", "1-8",   "--set",      "duration=0.3"};
}

std::vector<std::string> render_args(const fs::path& out) {
  return {SCENEGEN,    "batch", out.string(), "--views",       "1",     "--size", "48x64",
          "--quality", "draft", "--passes",   "image,uv,mask", "--dpi", "30"};
}

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& more) {
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

/// "key: reason" of every failure row.
std::set<std::string> failures(const fs::path& file) {
  std::set<std::string> out;
  for (const auto& r : papersim::batch::read_json_lines(file))
    out.insert(r["key"].get<std::string>() + ": " + r["reason"].get<std::string>());
  return out;
}

int run(const std::vector<std::string>& argv, const fs::path& log) {
  return pt::wait_status(pt::start(argv, log));
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

}  // namespace

TEST(Slurm, OneNodeClusterRunsTheArraysAResubmittedTaskResumesAndTheDatasetEqualsALocalBatch) {
  const fs::path work = fs::path(SLURM_WORK_DIR);
  fs::remove_all(work);
  fs::create_directories(work);
  Cluster cluster(work / "cluster");
  ASSERT_TRUE(cluster.started()) << "see " << (work / "cluster" / "log").string();
  // A folder name with a space, a '#' and quotes: sbatch reads #SBATCH values up to white space
  // or '#' unless they are quoted.
  const fs::path ds = work / "data set #1 'q\"", local = work / "local";
  const std::vector<std::string> slurm = {"--slurm",      "4",       "--slurm-mem", "300M",
                                          "--slurm-time", "00:05:00"};

  ASSERT_EQ(run(with(mesh_args(ds), slurm), work / "write_meshes.log"), 0)
      << pt::read_text(work / "write_meshes.log");
  const std::string script = (ds / "slurm" / "papersim-batch.sbatch").string();
  const std::string job = shell("sbatch --parsable " + papersim::batch::shell_quote(script));
  ASSERT_FALSE(job.empty());
  // Cancel array task 0 once it is running and has a sample in progress.
  ASSERT_TRUE(
      wait_until([&] { return shell("squeue -h -j " + job + "_0 -o %T") == "RUNNING"; }, 120));
  ASSERT_TRUE(wait_until(
      [&] { return fs::exists(ds / ".staging") && !fs::is_empty(ds / ".staging"); }, 60));
  shell("scancel " + job + "_0");
  ASSERT_TRUE(wait_for_job(job));
  EXPECT_NE(shell("scontrol show job " + job + "_0").find("JobState=CANCELLED"), std::string::npos)
      << "task 0 ended before it was cancelled";
  const std::size_t after_cancel = pt::line_count(ds / "manifest.jsonl");
  EXPECT_LT(after_cancel, 8u);
  // Resubmit the cancelled task: it resumes shard 0.
  const std::string again =
      shell("sbatch --parsable --array=0 " + papersim::batch::shell_quote(script));
  ASSERT_FALSE(again.empty());
  ASSERT_TRUE(wait_for_job(again));
  EXPECT_EQ(pt::line_count(ds / "manifest.jsonl"), 8u);

  ASSERT_EQ(run(with(render_args(ds), slurm), work / "write_renders.log"), 0)
      << pt::read_text(work / "write_renders.log");
  const std::string renders =
      shell("sbatch --parsable " +
            papersim::batch::shell_quote((ds / "slurm" / "scenegen-batch.sbatch").string()));
  ASSERT_FALSE(renders.empty());
  ASSERT_TRUE(wait_for_job(renders));
  // Every view is rendered or recorded as failed (a draw with no valid camera is a recorded
  // failure, not a crash).
  EXPECT_EQ(pt::line_count(ds / "renders.jsonl") + failures(ds / "renders_failures.jsonl").size(),
            8u)
      << shell("cat " + papersim::batch::shell_quote((ds / "slurm").string()) + "/*.err");

  // The same seeds locally.
  ASSERT_EQ(run(with(mesh_args(local), {"--jobs", "2"}), work / "local_meshes.log"), 0);
  const int local_renders =
      run(with(render_args(local), {"--jobs", "2"}), work / "local_renders.log");
  EXPECT_EQ(local_renders, failures(local / "renders_failures.jsonl").empty() ? 0 : 1);
  auto diffs = pt::dataset_differences(local, ds, "meshes", "manifest.jsonl");
  EXPECT_TRUE(diffs.empty()) << joined(diffs);
  diffs = pt::dataset_differences(local, ds, "renders", "renders.jsonl");
  EXPECT_TRUE(diffs.empty()) << joined(diffs);
  EXPECT_EQ(failures(local / "renders_failures.jsonl"), failures(ds / "renders_failures.jsonl"));
  EXPECT_FALSE(fs::exists(ds / "failures.jsonl"));
}
