// papersim batch and scenegen batch end to end on tiny samples (4 cm edges, 0.05 s): a batch
// killed at about half (SIGKILL or SIGINT) and run again ends with the same dataset as one that
// was never interrupted; a sample that cannot finish is recorded and the rest finish; two
// batches on one dataset run each sample once; bad options are named.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <set>
#include <thread>

#include "batch/runner.hpp"
#include "dataset_tree.hpp"
#include "simulation/batch.hpp"

namespace fs = std::filesystem;
namespace pt = papersim::test;
using nlohmann::json;

namespace {

const std::string PAPERSIM = PAPERSIM_EXE;
constexpr const char* SEEDS = "1-40";
constexpr std::size_t SAMPLES = 40;

/// This process's scratch folder, removed when the process ends.
struct ScratchDir {
  fs::path path = fs::temp_directory_path() / ("papersim_batch_test_" + std::to_string(getpid()));
  ScratchDir() {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

fs::path work_dir() {
  static const ScratchDir d;
  return d.path;
}

/// Four scenarios, tiny: 48 vertices, 5 steps of 10 ms.
fs::path tiny_mix() { return TINY_MIX; }

std::vector<std::string> batch_argv(const fs::path& out) {
  return {PAPERSIM,  "batch", "--out",  out.string(), "--mix", tiny_mix().string(),
          "--seeds", SEEDS,   "--jobs", "2"};
}

int run(const std::vector<std::string>& argv, const fs::path& log) {
  return pt::wait_status(pt::start(argv, log));
}

/// The uninterrupted batch every resume is compared with: made by the ctest fixture
/// PapersimBatch.ReferenceDataset, or here (under a lock) when the tests run on their own.
const fs::path& reference() {
  static const fs::path ref = [] {
    const fs::path d = BATCH_REFERENCE_DIR;
    fs::create_directories(d.parent_path());
    const int fd = open((d.string() + ".lock").c_str(), O_RDWR | O_CREAT, 0644);
    flock(fd, LOCK_EX);
    if (pt::line_count(d / "manifest.jsonl") != SAMPLES) {
      fs::remove_all(d);
      const int status = run(batch_argv(d), work_dir() / "reference.log");
      EXPECT_EQ(status, 0) << pt::read_text(work_dir() / "reference.log");
    }
    close(fd);
    return d;
  }();
  return ref;
}

/// Start a batch, send `signal` once the manifest holds half the samples, wait for it.
/// Returns the batch's exit status and the rows it had at the signal.
std::pair<int, std::size_t> interrupt_at_half(const std::vector<std::string>& argv,
                                              const fs::path& manifest, std::size_t total,
                                              int signal, const fs::path& log) {
  const pid_t pid = pt::start(argv, log);
  std::size_t rows = 0;
  int status = 0;
  while ((rows = pt::line_count(manifest)) < total / 2) {
    if (waitpid(pid, &status, WNOHANG) == pid) {  // ended before half: the caller's checks fail
      ADD_FAILURE() << "the batch ended on its own before half its samples: " << pt::read_text(log);
      return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), rows};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, signal);
  return {pt::wait_status(pid), rows};
}

/// Run `argv` with stdout and stderr into a pipe whose reader has ended (every write fails);
/// its exit status, or 128 + signal.
int status_with_no_reader(const std::vector<std::string>& argv) {
  int ends[2];
  if (pipe(ends) != 0) return -1;
  close(ends[0]);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    signal(SIGPIPE, SIG_DFL);  // as a shell starts a pipeline's commands
    dup2(ends[1], 1);
    dup2(ends[1], 2);
    execv(args[0], args.data());
    _exit(127);
  }
  close(ends[1]);
  return pt::wait_status(pid);
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

}  // namespace

TEST(PapersimBatch, ResumedAfterSigkillEqualsAnUninterruptedBatch) {
  const fs::path d = work_dir() / "sigkill";
  const auto [status, rows] = interrupt_at_half(batch_argv(d), d / "manifest.jsonl", SAMPLES,
                                                SIGKILL, work_dir() / "sigkill.log");
  EXPECT_EQ(status, 128 + SIGKILL);
  EXPECT_LT(rows, SAMPLES) << "the batch ended before it was killed";
  ASSERT_EQ(run(batch_argv(d), work_dir() / "sigkill_resume.log"), 0)
      << pt::read_text(work_dir() / "sigkill_resume.log");
  EXPECT_EQ(pt::line_count(d / "manifest.jsonl"), SAMPLES);
  EXPECT_FALSE(fs::exists(d / "failures.jsonl"));
  const auto diffs = pt::dataset_differences(reference(), d, "meshes", "manifest.jsonl");
  EXPECT_TRUE(diffs.empty()) << joined(diffs);
}

TEST(PapersimBatch, ResumedAfterSigintEqualsAnUninterruptedBatch) {
  const fs::path d = work_dir() / "sigint";
  const auto [status, rows] = interrupt_at_half(batch_argv(d), d / "manifest.jsonl", SAMPLES,
                                                SIGINT, work_dir() / "sigint.log");
  EXPECT_EQ(status, 130) << pt::read_text(work_dir() / "sigint.log");
  EXPECT_LT(rows, SAMPLES);
  EXPECT_NE(pt::read_text(work_dir() / "sigint.log").find("interrupted"), std::string::npos);
  EXPECT_TRUE(fs::is_empty(d / ".staging")) << "an interrupted batch left a half-written sample";
  EXPECT_FALSE(fs::exists(d / "failures.jsonl")) << "an interrupted sample was recorded as failed";
  ASSERT_EQ(run(batch_argv(d), work_dir() / "sigint_resume.log"), 0)
      << pt::read_text(work_dir() / "sigint_resume.log");
  const auto diffs = pt::dataset_differences(reference(), d, "meshes", "manifest.jsonl");
  EXPECT_TRUE(diffs.empty()) << joined(diffs);
}

TEST(PapersimBatch, TwoBatchesOnOneDatasetRunEachSampleOnce) {
  const fs::path d = work_dir() / "twice";
  const pid_t a = pt::start(batch_argv(d), work_dir() / "twice_a.log");
  const pid_t b = pt::start(batch_argv(d), work_dir() / "twice_b.log");
  EXPECT_EQ(pt::wait_status(a), 0) << pt::read_text(work_dir() / "twice_a.log");
  EXPECT_EQ(pt::wait_status(b), 0) << pt::read_text(work_dir() / "twice_b.log");
  const auto diffs = pt::dataset_differences(reference(), d, "meshes", "manifest.jsonl");
  EXPECT_TRUE(diffs.empty()) << joined(diffs);
}

// Its output into a pipe no one reads (`papersim batch ... 2>&1 | tee log`, tee ended): every
// line fails, and the batch still makes every sample and ends with status 0 (it was killed by
// SIGPIPE at its first progress line).
TEST(PapersimBatch, FinishesItsSamplesWhenNoOneReadsItsOutput) {
  const fs::path d = work_dir() / "no_reader";
  EXPECT_EQ(status_with_no_reader(batch_argv(d)), 0);
  const auto diffs = pt::dataset_differences(reference(), d, "meshes", "manifest.jsonl");
  EXPECT_TRUE(diffs.empty()) << joined(diffs);
}

TEST(PapersimBatch, ASampleOverTheTimeLimitIsRecordedAndTheOthersFinish) {
  // fall-sphere made long (10,000 steps of 0.1 ms: minutes on any machine) against a 10 s limit;
  // tiny pulls.
  const fs::path d = work_dir() / "isolation", mix = work_dir() / "isolation_mix.json";
  std::ofstream(mix)
      << R"({"scenarios": {"pull": {"weight": 3, "set": {"duration": 0.05, "time_step": 0.01,
                            "sheet.edge_length": 0.04}}, "fall-sphere": {"weight": 1, "set": {"duration": 1.0,
                            "time_step": 0.0001}}}})";
  const papersim::simulation::Mix m = papersim::simulation::load_mix(mix.string());
  std::set<std::uint64_t> slow;
  for (std::uint64_t seed = 1; seed <= 8; ++seed)
    if (m.scenarios[papersim::simulation::mix_pick(m, seed)] == "fall-sphere") slow.insert(seed);
  ASSERT_FALSE(slow.empty());
  const int status = run({PAPERSIM, "batch", "--out", d.string(), "--mix", mix.string(), "--seeds",
                          "1-8", "--jobs", "2", "--time-limit", "10"},
                         work_dir() / "isolation.log");
  EXPECT_EQ(status, 1) << pt::read_text(work_dir() / "isolation.log");
  std::set<std::uint64_t> failed, done;
  for (const auto& r : papersim::batch::read_json_lines(d / "failures.jsonl")) {
    failed.insert(r["seed"].get<std::uint64_t>());
    EXPECT_EQ(r["reason"], "time limit");
    EXPECT_EQ(r["scenario"], "fall-sphere");
    EXPECT_GE(r["wall_seconds"].get<double>(), 10.0);
  }
  for (const auto& r : papersim::batch::read_json_lines(d / "manifest.jsonl"))
    done.insert(r["seed"].get<std::uint64_t>());
  EXPECT_EQ(failed, slow);
  EXPECT_EQ(done.size() + slow.size(), 8u);
  for (std::uint64_t s : slow)
    EXPECT_FALSE(fs::exists(d / "meshes" / "fall-sphere" / "0" / std::to_string(s)));
  // dataset-stats reads it back: 1 failure reason, counts per scenario, plots.
  ASSERT_EQ(run({PAPERSIM, "dataset-stats", d.string(), "--plots", (d / "plots").string()},
                work_dir() / "stats.log"),
            0)
      << pt::read_text(work_dir() / "stats.log");
  const std::string stats = pt::read_text(work_dir() / "stats.log");
  EXPECT_NE(stats.find("time limit"), std::string::npos) << stats;
  EXPECT_NE(stats.find("fall-sphere"), std::string::npos) << stats;
  EXPECT_TRUE(fs::exists(d / "plots" / "meshes_wall_seconds.svg"));
}

namespace {

/// A remeshed fold sample of 50 steps of 10 ms (about 2 s): seed 3, coarse.
std::vector<std::string> fold_batch_argv(const fs::path& out,
                                         const std::vector<std::string>& extra) {
  std::vector<std::string> argv{PAPERSIM, "batch", "--out", out.string(), "--scenarios", "fold",
                                "--seeds", "3", "--jobs", "1", "--quiet", "--set", "duration=0.5",
                                "--set", "sheet.edge_length=0.03", "--set", "remesh.size_min=0.015",
                                // The reference's 10 cm (the scenario's 2 cm is close to 1.5 cm,
                                // and its mesh would hardly change): a run that remeshes on most
                                // of its passes.
                                "--set", "remesh.size_max=0.1"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

/// The step of the checkpoint in `cdir`, 0 when there is none yet.
int checkpoint_step(const fs::path& cdir) {
  const json j = json::parse(pt::read_text(cdir / "checkpoint.json"), nullptr, false);
  return j.is_object() ? j.value("step", 0) : 0;
}

/// Start a checkpointing batch and SIGKILL it once its sample saved a checkpoint at step 10 or
/// later; fails the test when the batch ends first.
void kill_after_a_checkpoint(const std::vector<std::string>& argv, const fs::path& cdir,
                             const fs::path& log) {
  const pid_t pid = pt::start(argv, log);
  int status = 0;
  while (checkpoint_step(cdir) < 10) {
    if (waitpid(pid, &status, WNOHANG) == pid) {
      ADD_FAILURE() << "the batch ended before it saved a checkpoint at step 10: "
                    << pt::read_text(log);
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(pid, SIGKILL);
  pt::wait_status(pid);
}

}  // namespace

// --checkpoint-every: a sample killed mid-run continues from its checkpoint when the batch runs
// again, and ends with the uninterrupted sample's mesh to the byte (the run remeshes); a
// checkpoint of another scene, or one cut short, is not used.
TEST(PapersimBatch, AKilledSampleContinuesFromItsCheckpointToTheSameMesh) {
  const fs::path ref = work_dir() / "ckpt_ref", d = work_dir() / "ckpt";
  ASSERT_EQ(run(fold_batch_argv(ref, {}), work_dir() / "ckpt_ref.log"), 0)
      << pt::read_text(work_dir() / "ckpt_ref.log");
  const std::vector<std::string> every5{"--checkpoint-every", "5"};
  const fs::path cdir = d / ".checkpoints" / "meshes_fold_0_3",
                 sample = fs::path("meshes") / "fold" / "0" / "3";
  kill_after_a_checkpoint(fold_batch_argv(d, every5), cdir, work_dir() / "ckpt_kill.log");
  ASSERT_FALSE(fs::exists(d / sample)) << "the sample finished before the kill";
  const int saved = checkpoint_step(cdir);
  ASSERT_GE(saved, 10);

  ASSERT_EQ(run(fold_batch_argv(d, every5), work_dir() / "ckpt_resume.log"), 0)
      << pt::read_text(work_dir() / "ckpt_resume.log");
  const json meta = json::parse(pt::read_text(d / sample / "meta.json"));
  ASSERT_TRUE(meta.contains("resumed")) << "the sample started over";
  EXPECT_EQ(meta["resumed"]["step"].get<int>(), saved);
  EXPECT_TRUE(meta["resumed"]["whole_run"].get<bool>());
  // The same scene: the roller's keyframes, rebuilt from its motion as it yields, differ from
  // the saved ones in rounding only, which is not a change.
  EXPECT_EQ(meta["resumed"]["scene_changes"], json::array()) << meta["resumed"];
  const json ref_meta = json::parse(pt::read_text(ref / sample / "meta.json"));
  EXPECT_EQ(meta["run"]["newton_iterations"], ref_meta["run"]["newton_iterations"]);
  EXPECT_EQ(meta["run"]["remesh"]["passes"], ref_meta["run"]["remesh"]["passes"]);
  EXPECT_GT(meta["run"]["remesh"]["passes"].get<int>(), 10);
  for (const char* f : {"sheet.ply", "sheet.obj"})
    EXPECT_EQ(pt::read_text(d / sample / f), pt::read_text(ref / sample / f))
        << f << " differs from the uninterrupted sample's";
  EXPECT_FALSE(fs::exists(cdir)) << "the finished sample's checkpoint was left";

  // Killed again in a fresh dataset, then run with another scene: the checkpoint is discarded.
  const fs::path e = work_dir() / "ckpt_other";
  const fs::path edir = e / ".checkpoints" / "meshes_fold_0_3";
  kill_after_a_checkpoint(fold_batch_argv(e, every5), edir, work_dir() / "ckpt_kill2.log");
  std::vector<std::string> other = every5;
  other.insert(other.end(), {"--set", "remesh.size_max=0.05"});
  ASSERT_EQ(run(fold_batch_argv(e, other), work_dir() / "ckpt_other.log"), 0)
      << pt::read_text(work_dir() / "ckpt_other.log");
  EXPECT_FALSE(json::parse(pt::read_text(e / sample / "meta.json")).contains("resumed"));
  EXPECT_FALSE(fs::exists(edir));

  // A checkpoint whose sheet file a crash cut short is not used either: the sample starts over.
  const fs::path g = work_dir() / "ckpt_cut";
  const fs::path gdir = g / ".checkpoints" / "meshes_fold_0_3";
  kill_after_a_checkpoint(fold_batch_argv(g, every5), gdir, work_dir() / "ckpt_kill3.log");
  const std::string ply =
      json::parse(pt::read_text(gdir / "checkpoint.json")).at("sheet").get<std::string>();
  fs::resize_file(gdir / ply, fs::file_size(gdir / ply) / 2);
  ASSERT_EQ(run(fold_batch_argv(g, every5), work_dir() / "ckpt_cut.log"), 0)
      << pt::read_text(work_dir() / "ckpt_cut.log");
  EXPECT_FALSE(json::parse(pt::read_text(g / sample / "meta.json")).contains("resumed"));
  EXPECT_EQ(pt::read_text(g / sample / "sheet.ply"), pt::read_text(ref / sample / "sheet.ply"));
}

TEST(PapersimBatch, BadOptionsAreNamedAndNothingRuns) {
  const fs::path d = work_dir() / "bad";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--scenarios", "pull", "--seeds", "5-1"}, "--seeds"},
      {{"--scenarios", "pull", "--seeds", "1-2", "--set", "sheet.edge_lenght=0.02"},
       "sheet.edge_lenght"},
      {{"--scenarios", "pull", "--seeds", "1-2", "--set", "duration=-1"}, "duration"},
      {{"--scenarios", "pull,pulll", "--seeds", "1-2"}, "pulll"},
      {{"--mix", (work_dir() / "missing.json").string(), "--seeds", "1-2"}, "--mix"},
      {{"--scenarios", "pull", "--seeds", "1-2", "--shard", "2/2"}, "--shard"},
      {{"--seeds", "1-2"}, "--scenarios or --mix"},
      // Passed on to every sample's papersim run, which takes at most 2^30: each sample failed.
      {{"--scenarios", "pull", "--seeds", "1-2", "--checkpoint-every", "2147483647"},
       "--checkpoint-every"},
      // A well-formed number, only too long: the message says so.
      {{"--scenarios", "pull", "--seeds", "1000000000000000000"},
       "'1000000000000000000' has a seed of more than 18 digits"},
  };
  for (const auto& [args, named] : cases) {
    std::vector<std::string> argv{PAPERSIM, "batch", "--out", d.string()};
    argv.insert(argv.end(), args.begin(), args.end());
    EXPECT_EQ(run(argv, work_dir() / "bad.log"), 2) << named;
    EXPECT_NE(pt::read_text(work_dir() / "bad.log").find(named), std::string::npos)
        << named << ": " << pt::read_text(work_dir() / "bad.log");
    EXPECT_FALSE(fs::exists(d / "meshes"));
  }
}

TEST(PapersimBatch, SlurmWritesAJobArrayAndRunsNothing) {
  const fs::path d = work_dir() / "slurm";
  ASSERT_EQ(run({PAPERSIM, "batch", "--out", d.string(), "--mix", tiny_mix().string(), "--seeds",
                 "1-10", "--slurm", "3", "--slurm-cpus", "2", "--slurm-time", "00:10:00",
                 "--checkpoint-every", "25"},
                work_dir() / "slurm.log"),
            0)
      << pt::read_text(work_dir() / "slurm.log");
  const std::string script = pt::read_text(d / "slurm" / "papersim-batch.sbatch");
  EXPECT_NE(script.find("#SBATCH --array=0-2\n"), std::string::npos) << script;
  EXPECT_NE(script.find("#SBATCH --cpus-per-task=2\n"), std::string::npos) << script;
  EXPECT_NE(script.find("#SBATCH --time=\"00:10:00\"\n"), std::string::npos) << script;
  EXPECT_NE(script.find("--shard \"${SLURM_ARRAY_TASK_ID}/3\""), std::string::npos) << script;
  EXPECT_NE(script.find("'--checkpoint-every' '25'"), std::string::npos) << script;
  EXPECT_NE(pt::read_text(work_dir() / "slurm.log")
                .find("sbatch " + (fs::absolute(d) / "slurm" / "papersim-batch.sbatch").string()),
            std::string::npos);
  EXPECT_FALSE(fs::exists(d / "meshes"));
}

// An array task whose shard is empty would start, find nothing and end: --slurm N over fewer
// samples makes one task per sample. An array whose last index is at Slurm's default
// MaxArraySize or above gets a note (sbatch of a default cluster refuses it; checked on
// scripts/slurm_cluster.sh's cluster: --array=0-1000 is taken, 0-1500 refused).
TEST(PapersimBatch, SlurmMakesNoMoreArrayTasksThanSamplesAndNotesSlurmsArrayLimit) {
  const fs::path d = work_dir() / "slurm_small";
  const fs::path log = work_dir() / "slurm_small.log";
  ASSERT_EQ(run({PAPERSIM, "batch", "--out", d.string(), "--mix", tiny_mix().string(), "--seeds",
                 "1-3", "--slurm", "500"},
                log),
            0)
      << pt::read_text(log);
  std::string script = pt::read_text(d / "slurm" / "papersim-batch.sbatch");
  EXPECT_NE(script.find("#SBATCH --array=0-2\n"), std::string::npos) << script;
  EXPECT_NE(script.find("--shard \"${SLURM_ARRAY_TASK_ID}/3\""), std::string::npos) << script;
  EXPECT_NE(pt::read_text(log).find("(3 array tasks over 3 samples)\nnote: --slurm 500 is more "
                                    "than the 3 samples: one array task per sample"),
            std::string::npos)
      << pt::read_text(log);
  EXPECT_EQ(pt::read_text(log).find("MaxArraySize"), std::string::npos) << pt::read_text(log);
  for (const auto& [shards, noted] :
       std::vector<std::pair<std::string, bool>>{{"1001", false}, {"1002", true}}) {
    ASSERT_EQ(run({PAPERSIM, "batch", "--out", d.string(), "--mix", tiny_mix().string(), "--seeds",
                   "1-5000", "--slurm", shards},
                  log),
              0)
        << pt::read_text(log);
    script = pt::read_text(d / "slurm" / "papersim-batch.sbatch");
    EXPECT_NE(script.find("#SBATCH --array=0-" + std::to_string(std::stoi(shards) - 1) + "\n"),
              std::string::npos)
        << script;
    EXPECT_EQ(pt::read_text(log).find("note: --slurm"), std::string::npos) << pt::read_text(log);
    EXPECT_EQ(pt::read_text(log).find("MaxArraySize, 1001 unless slurm.conf sets it") !=
                  std::string::npos,
              noted)
        << pt::read_text(log);
  }
  EXPECT_FALSE(fs::exists(d / "meshes"));
}

// A dataset folder that is a file, or lies under one, is named before the samples are drawn
// (it was "filesystem error: cannot create directories: Not a directory [F/.locks]"), and so is an
// empty one.
TEST(PapersimBatch, ADatasetFolderThatIsAFileIsNamed) {
  const fs::path file = work_dir() / "a file";
  std::ofstream(file) << "kept\n";
  const fs::path log = work_dir() / "out_file.log";
  for (const fs::path& out : {file, file / "sub"})
    for (const bool slurm : {false, true}) {
      std::vector<std::string> argv{
          PAPERSIM, "batch", "--out", out.string(), "--mix", tiny_mix().string(), "--seeds", "1-2"};
      if (slurm) argv.insert(argv.end(), {"--slurm", "2"});
      EXPECT_EQ(run(argv, log), 5) << out;
      EXPECT_NE(pt::read_text(log).find("--out '" + out.string() + "': '" + file.string() +
                                        "' is not a folder"),
                std::string::npos)
          << pt::read_text(log);
    }
  EXPECT_EQ(pt::read_text(file), "kept\n");
  // An empty one is a usage error (it was exit 5, "cannot make absolute path").
  EXPECT_EQ(
      run({PAPERSIM, "batch", "--out", "", "--mix", tiny_mix().string(), "--seeds", "1-2"}, log),
      2);
  EXPECT_NE(pt::read_text(log).find("--out: must not be empty"), std::string::npos)
      << pt::read_text(log);
}

#ifdef SCENEGEN_EXE
// scenegen batch's tasks are views: its help says so for the options it shares with papersim
// batch, whose help says samples.
TEST(ScenegenBatch, ItsHelpCountsViews) {
  const fs::path log = work_dir() / "help.log";
  ASSERT_EQ(run({SCENEGEN_EXE, "batch", "--help"}, log), 0);
  const std::string help = pt::read_text(log);
  for (const char* said :
       {"views at once", "seconds per view; a view over it", "the views at positions",
        "run views recorded", "at most one per view", "= views at once"})
    EXPECT_NE(help.find(said), std::string::npos) << said << "\n" << help;
  EXPECT_EQ(help.find("sample"), std::string::npos) << help;
  ASSERT_EQ(run({PAPERSIM, "batch", "--help"}, log), 0);
  EXPECT_NE(pt::read_text(log).find("samples at once"), std::string::npos);
}

// Values every view's scenegen render would refuse were taken, and each view of the dataset was
// then recorded as failed (a million meshes: four million failure rows, or a cluster's time).
TEST(ScenegenBatch, ValuesEveryViewWouldRefuseAreRefusedBeforeAnyRuns) {
  const fs::path d = work_dir() / "bad_render_options";
  fs::remove_all(d);
  fs::create_directories(d / "meshes" / "pull" / "0" / "0");
  std::ofstream(d / "meshes" / "pull" / "0" / "0" / "sheet.obj") << "";
  fs::create_directories(d / "no_images");
  std::ofstream(d / "no_images" / "notes.txt") << "not an image\n";
  const std::string none = (d / "no_images").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--dpi", "5000"}, "--dpi"},
      {{"--threads", "5000"}, "--threads"},
      {{"--size", "9000x9000"}, "exceeds the limit of 8192"},
      {{"--size", "4x4"}, "too small"},
      {{"--documents", none}, "documents folder '" + none + "' has no PNG or JPEG file"},
      {{"--backgrounds", none}, "backgrounds folder '" + none + "' has no PNG or JPEG file"},
  };
  for (const auto& [args, named] : cases) {
    std::vector<std::string> argv{SCENEGEN_EXE, "batch", d.string()};
    argv.insert(argv.end(), args.begin(), args.end());
    EXPECT_EQ(run(argv, work_dir() / "bad_render.log"), 2) << named;
    EXPECT_NE(pt::read_text(work_dir() / "bad_render.log").find(named), std::string::npos)
        << named << ": " << pt::read_text(work_dir() / "bad_render.log");
    EXPECT_FALSE(fs::exists(d / "renders"));
    EXPECT_FALSE(fs::exists(d / "renders_failures.jsonl"));
  }
  fs::remove_all(d);
}

TEST(ScenegenBatch, ResumedAfterSigkillEqualsAnUninterruptedBatch) {
  // Three meshes of the reference, two views each (one flipped), tiny renders.
  const fs::path a = work_dir() / "render_ref", b = work_dir() / "render_kill";
  for (const fs::path& d : {a, b})
    for (const char* m : {"meshes/pull", "meshes/fall-gable"}) {
      fs::create_directories(d / m);
      fs::copy(reference() / m, d / m, fs::copy_options::recursive);
    }
  const auto argv = [](const fs::path& d) {
    return std::vector<std::string>{
        SCENEGEN_EXE, "batch", d.string(), "--views",       "2",     "--flip", "--size", "48x64",
        "--quality",  "draft", "--passes", "image,uv,mask", "--dpi", "30",     "--jobs", "2"};
  };
  // Keep it small: the first three meshes of the copy (by seed) stay.
  for (const fs::path& d : {a, b}) {
    std::vector<fs::path> all;
    for (const auto& e : fs::recursive_directory_iterator(d / "meshes"))
      if (e.path().filename() == "sheet.obj") all.push_back(e.path().parent_path());
    std::sort(all.begin(), all.end());
    for (std::size_t i = 3; i < all.size(); ++i) fs::remove_all(all[i]);
  }
  ASSERT_EQ(run(argv(a), work_dir() / "render_ref.log"), 0)
      << pt::read_text(work_dir() / "render_ref.log");
  const std::size_t views = pt::line_count(a / "renders.jsonl");
  EXPECT_EQ(views, 6u);
  // Its lines count views, not samples.
  const std::string said = pt::read_text(work_dir() / "render_ref.log");
  EXPECT_NE(said.find("6 of 6 views done (6 in this run)"), std::string::npos) << said;
  EXPECT_NE(said.find(" views/h "), std::string::npos) << said;
  EXPECT_EQ(said.find("samples"), std::string::npos) << said;
  const auto [status, rows] = interrupt_at_half(argv(b), b / "renders.jsonl", views, SIGKILL,
                                                work_dir() / "render_kill.log");
  EXPECT_EQ(status, 128 + SIGKILL);
  EXPECT_LT(rows, views);
  ASSERT_EQ(run(argv(b), work_dir() / "render_resume.log"), 0)
      << pt::read_text(work_dir() / "render_resume.log");
  const auto diffs = pt::dataset_differences(a, b, "renders", "renders.jsonl");
  EXPECT_TRUE(diffs.empty()) << joined(diffs);
}

// As papersim batch: no reader of its lines, and every view is rendered.
TEST(ScenegenBatch, FinishesItsViewsWhenNoOneReadsItsOutput) {
  const fs::path d = work_dir() / "render_no_reader";
  const fs::path one = fs::directory_iterator(reference() / "meshes" / "pull" / "0")->path();
  fs::create_directories(d / "meshes" / "pull" / "0");
  fs::copy(one, d / "meshes" / "pull" / "0" / one.filename(), fs::copy_options::recursive);
  EXPECT_EQ(status_with_no_reader({SCENEGEN_EXE, "batch", d.string(), "--views", "2", "--size",
                                   "48x64", "--quality", "draft", "--passes", "image,mask", "--dpi",
                                   "30", "--jobs", "2"}),
            0);
  EXPECT_EQ(pt::line_count(d / "renders.jsonl"), 2u);
  EXPECT_FALSE(fs::exists(d / "renders_failures.jsonl"));
}

TEST(ScenegenBatch, SlurmWritesAMeshListAndTheTasksRenderItAlone) {
  // Two meshes of the reference: --slurm lists them once; a third added afterwards is not
  // rendered by the array's command line, which reads the list instead of the dataset's folders.
  const fs::path d = work_dir() / "render_list";
  fs::create_directories(d / "meshes" / "pull");
  fs::copy(reference() / "meshes" / "pull", d / "meshes" / "pull", fs::copy_options::recursive);
  std::vector<fs::path> all;
  for (const auto& e : fs::recursive_directory_iterator(d / "meshes"))
    if (e.path().filename() == "sheet.obj") all.push_back(e.path().parent_path());
  std::sort(all.begin(), all.end());
  ASSERT_GE(all.size(), 3u);
  const fs::path later = d / "later";
  fs::rename(all[2], later);
  for (std::size_t i = 3; i < all.size(); ++i) fs::remove_all(all[i]);
  const std::vector<std::string> options{"--views", "1",        "--size",     "48x64", "--quality",
                                         "draft",   "--passes", "image,mask", "--dpi", "30"};
  std::vector<std::string> slurm{SCENEGEN_EXE, "batch", d.string(), "--slurm", "2"};
  slurm.insert(slurm.end(), options.begin(), options.end());
  ASSERT_EQ(run(slurm, work_dir() / "render_list.log"), 0)
      << pt::read_text(work_dir() / "render_list.log");
  const fs::path list = d / "slurm" / "scenegen-batch.meshes";
  EXPECT_EQ(pt::line_count(list), 3u);  // the head and two meshes
  const std::string script = pt::read_text(d / "slurm" / "scenegen-batch.sbatch");
  EXPECT_NE(script.find("'--mesh-list' '" + fs::absolute(list).string() + "'"), std::string::npos)
      << script;
  EXPECT_NE(pt::read_text(work_dir() / "render_list.log").find("(2 meshes)"), std::string::npos)
      << pt::read_text(work_dir() / "render_list.log");
  EXPECT_FALSE(fs::exists(d / "renders.jsonl"));
  fs::rename(later, all[2]);
  for (const char* shard : {"0/2", "1/2"}) {
    std::vector<std::string> task{SCENEGEN_EXE,  "batch",   d.string(), "--mesh-list",
                                  list.string(), "--shard", shard};
    task.insert(task.end(), options.begin(), options.end());
    ASSERT_EQ(run(task, work_dir() / "render_list_task.log"), 0)
        << pt::read_text(work_dir() / "render_list_task.log");
  }
  EXPECT_EQ(pt::line_count(d / "renders.jsonl"), 2u);
  const fs::path rendered =
      fs::path("renders") / "pull" / all[2].parent_path().filename() / all[2].filename();
  EXPECT_FALSE(fs::exists(d / rendered)) << rendered;
  // A missing or malformed list is refused before anything runs, naming it.
  std::ofstream(d / "bad.meshes") << "# scenegen batch mesh list: 1 meshes\nmeshes/pull/x\n";
  for (const auto& [file, named] : std::vector<std::pair<std::string, std::string>>{
           {(d / "none.meshes").string(),
            "--mesh-list '" + (d / "none.meshes").string() + "' is not a file"},
           {(d / "bad.meshes").string(), "line 2: 'meshes/pull/x' is not"}}) {
    std::vector<std::string> task{SCENEGEN_EXE, "batch",   d.string(), "--mesh-list",
                                  file,         "--shard", "0/2"};
    task.insert(task.end(), options.begin(), options.end());
    EXPECT_EQ(run(task, work_dir() / "render_list_bad.log"), 2) << named;
    EXPECT_NE(pt::read_text(work_dir() / "render_list_bad.log").find(named), std::string::npos)
        << pt::read_text(work_dir() / "render_list_bad.log");
  }
  EXPECT_EQ(pt::line_count(d / "renders.jsonl"), 2u);
}
#endif
