// Issue 17, failure 3 and the signal rules: SIGINT / SIGTERM end papersim and scenegen within a
// second, kill POV-Ray, remove the staging folder and exit with 128 + signal; what SIGKILL
// leaves is removed by the next run into the same output.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "fixtures.hpp"

namespace papersim::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// A scene that runs for far longer than the test waits.
std::string long_scene(const Scratch& dir) {
  json scene = small_scene(dir);
  scene["duration"] = 20.0;
  return write_scene(dir, "long.json", scene);
}

/// Wait until `path` exists (at most `timeout` seconds).
bool appears(const fs::path& path, double timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(path)) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

/// Wait until `pid` has at least one child (POV-Ray started).
std::vector<pid_t> wait_for_children(pid_t pid, double timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    const auto kids = children_of(pid);
    if (!kids.empty()) return kids;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout)
      return {};
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

bool all_gone(const std::vector<pid_t>& pids, double timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    bool any = false;
    for (pid_t p : pids) any = any || alive(p);
    if (!any) return true;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

TEST(Signals, PapersimStopsWithinASecondAndLeavesNothing) {
  for (const int sig : {SIGINT, SIGTERM}) {
    Scratch dir("sig-papersim");
    const std::string out = dir.str("out");
    const pid_t pid = start({PAPERSIM, "run", long_scene(dir), "--out", out, "--frames", "1"},
                            dir.path() / "logs");
    ASSERT_TRUE(appears(fs::path(out) / ".papersim-partial" / "frames" / "frame_000002.obj", 60.0));
    kill(pid, sig);
    Outcome r;
    ASSERT_TRUE(wait_for(pid, dir.path() / "logs", 5.0, r))
        << "still running 5 s after signal " << sig;
    EXPECT_LT(r.seconds, 1.0) << "signal " << sig;
    EXPECT_EQ(r.status, 128 + sig) << r.err;
    EXPECT_FALSE(r.signalled) << "ended by the signal instead of handling it";
    EXPECT_FALSE(fs::exists(out)) << "the run created it, so it must go";
  }
}

TEST(Signals, PapersimKeepsAnEarlierRunWhenInterrupted) {
  Scratch dir("sig-keep");
  const std::string out = dir.str("out");
  ASSERT_EQ(
      run({PAPERSIM, "run", write_scene(dir, "s.json", small_scene(dir)), "--out", out, "--quiet"})
          .status,
      0);
  const std::string meta = read_text(out + "/meta.json");
  const pid_t pid =
      start({PAPERSIM, "run", long_scene(dir), "--out", out, "--frames", "1"}, dir.path() / "logs");
  ASSERT_TRUE(appears(fs::path(out) / ".papersim-partial" / "frames" / "frame_000002.obj", 60.0));
  kill(pid, SIGINT);
  Outcome r;
  ASSERT_TRUE(wait_for(pid, dir.path() / "logs", 5.0, r));
  EXPECT_EQ(r.status, 130);
  EXPECT_EQ(listing(out), (std::vector<std::string>{"meta.json", "sheet.obj", "sheet.ply"}));
  EXPECT_EQ(read_text(out + "/meta.json"), meta);
}

TEST(Signals, WhatSigkillLeavesIsRemovedByTheNextRun) {
  Scratch dir("sig-kill");
  const std::string out = dir.str("out");
  const pid_t pid =
      start({PAPERSIM, "run", long_scene(dir), "--out", out, "--frames", "1"}, dir.path() / "logs");
  ASSERT_TRUE(appears(fs::path(out) / ".papersim-partial" / "frames" / "frame_000002.obj", 60.0));
  kill(pid, SIGKILL);
  Outcome r;
  ASSERT_TRUE(wait_for(pid, dir.path() / "logs", 5.0, r));
  ASSERT_TRUE(fs::exists(fs::path(out) / ".papersim-partial"));
  // The next run into the same output fails on bad input, and still removes the leftover.
  json bad = small_scene(dir);
  bad["duration"] = -1;
  EXPECT_EQ(run({PAPERSIM, "run", write_scene(dir, "bad.json", bad), "--out", out}).status, 2);
  EXPECT_FALSE(fs::exists(fs::path(out) / ".papersim-partial"));
}

TEST(Signals, ScenegenStopsWithinASecondKillsPovrayAndLeavesNothing) {
  for (const int sig : {SIGTERM, SIGINT}) {
    Scratch dir("sig-scenegen");
    const std::string mesh = example_sheet(dir, "cylinder", "c.obj");
    const std::string out = dir.str("sample");
    const pid_t pid =
        start({SCENEGEN, "render", mesh, "--out", out, "--size", "256x360", "--parallel", "2"},
              dir.path() / "logs");
    const std::vector<pid_t> povray = wait_for_children(pid, 60.0);
    ASSERT_FALSE(povray.empty()) << "POV-Ray never started";
    kill(pid, sig);
    Outcome r;
    ASSERT_TRUE(wait_for(pid, dir.path() / "logs", 5.0, r))
        << "still running 5 s after signal " << sig;
    EXPECT_LT(r.seconds, 1.0);
    EXPECT_EQ(r.status, 128 + sig) << r.err;
    EXPECT_TRUE(all_gone(povray, 1.0)) << "POV-Ray outlived scenegen";
    EXPECT_FALSE(fs::exists(out)) << "the run created it, so it must go";
  }
}

TEST(Signals, ScenegenKilledTakesPovrayWithItAndTheNextRunCleansUp) {
  Scratch dir("sig-scenegen-kill");
  const std::string mesh = example_sheet(dir, "cylinder", "c.obj");
  const std::string out = dir.str("sample");
  const pid_t pid =
      start({SCENEGEN, "render", mesh, "--out", out, "--size", "256x360", "--parallel", "2"},
            dir.path() / "logs");
  const std::vector<pid_t> povray = wait_for_children(pid, 60.0);
  ASSERT_FALSE(povray.empty());
  kill(pid, SIGKILL);
  Outcome r;
  ASSERT_TRUE(wait_for(pid, dir.path() / "logs", 5.0, r));
  // A generous wait: the kernel tears a killed POV-Ray down at once, but a loaded machine may
  // take a moment to show it.
  EXPECT_TRUE(all_gone(povray, 3.0)) << "POV-Ray outlived a killed scenegen";
  ASSERT_TRUE(fs::exists(fs::path(out) / ".scenegen-job"));
  // The next render into the same output fails (POV-Ray cannot run) and removes the leftover.
  EXPECT_EQ(
      run({SCENEGEN, "render", mesh, "--out", out, "--povray", "/bin/false", "--size", "32x48"})
          .status,
      6);
  EXPECT_FALSE(fs::exists(fs::path(out) / ".scenegen-job"));
}

}  // namespace
}  // namespace papersim::test
