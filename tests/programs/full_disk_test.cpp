// Issue 17, failure 2: on a full file system every program fails with exit status 5 and leaves
// no file behind (before, papersim exited 0 with a 0-byte meta.json). The disk is a small tmpfs
// filled to the last byte when this process may mount one (root with CAP_SYS_ADMIN, as in CI),
// else every write is refused by a file size limit of 0 bytes (RLIMIT_FSIZE, `ulimit -f 0`).
#include <gtest/gtest.h>
#include <sys/mount.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <vector>

#include "fixtures.hpp"

namespace papersim::test {
namespace {

namespace fs = std::filesystem;

/// A full disk at path(): a mounted, filled tmpfs, or (fsize_limit() == 0) a size limit.
class FullDisk {
 public:
  FullDisk() : m_scratch("fulldisk") {
    m_mount = m_scratch.path() / "disk";
    fs::create_directories(m_mount);
    m_mounted = mount("tmpfs", m_mount.c_str(), "tmpfs", 0, "size=256k") == 0;
    if (m_mounted) fill();
    m_method = m_mounted ? "a full 256 KiB tmpfs" : "a file size limit of 0 bytes (RLIMIT_FSIZE)";
    std::cout << "full-disk test uses " << m_method << '\n';
    ::testing::Test::RecordProperty("full_disk_method", m_method);
  }
  ~FullDisk() {
    if (m_mounted) umount(m_mount.c_str());
  }
  const fs::path& path() const { return m_mount; }
  /// The file size limit for the programs: none on a mounted disk, else 0 bytes.
  long fsize_limit() const { return m_mounted ? -1 : 0; }
  const std::string& method() const { return m_method; }

 private:
  void fill() {
    std::FILE* f = std::fopen((m_mount / "filler").c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::vector<char> block(4096, 'x');
    while (std::fwrite(block.data(), 1, block.size(), f) == block.size()) {
    }
    std::fclose(f);
    // A byte at a time fills the last partial block.
    f = std::fopen((m_mount / "filler2").c_str(), "wb");
    if (f) {
      while (std::fputc('x', f) != EOF && std::fflush(f) == 0) {
      }
      std::fclose(f);
    }
  }
  Scratch m_scratch;
  fs::path m_mount;
  bool m_mounted = false;
  std::string m_method;
};

/// Files of `dir` other than the filler, with their sizes.
std::vector<std::string> left_behind(const fs::path& dir) {
  std::vector<std::string> out;
  for (const std::string& name : listing(dir))
    if (name != "filler" && name != "filler2") out.push_back(name);
  return out;
}

class FullDiskTest : public ::testing::Test {
 protected:
  Scratch inputs{"fulldisk-inputs"};
  FullDisk disk;
};

TEST_F(FullDiskTest, PapersimRunFailsWithStatus5AndWritesNothing) {
  const std::string scene = write_scene(inputs, "s.json", small_scene(inputs));
  const Outcome r =
      run({PAPERSIM, "run", scene, "--out", (disk.path() / "out").string(), "--quiet"},
          disk.fsize_limit());
  EXPECT_EQ(r.status, 5) << disk.method() << ": " << r.err;
  EXPECT_TRUE(r.err.find("cannot write") != std::string::npos) << r.err;
  EXPECT_EQ(left_behind(disk.path()), std::vector<std::string>{}) << disk.method();
}

TEST_F(FullDiskTest, PapersimScenarioDrawOnlyFailsWithStatus5AndWritesNothing) {
  // Without --draw-only, scenario publishes scene.json with the run's files through the same
  // staging folder as `papersim run` (tested above); the pull run itself takes a minute.
  const Outcome r = run({PAPERSIM, "scenario", "pull", "--seed", "1", "--draw-only", "--out",
                         (disk.path() / "out").string()},
                        disk.fsize_limit());
  EXPECT_EQ(r.status, 5) << disk.method() << ": " << r.err;
  EXPECT_EQ(left_behind(disk.path()), std::vector<std::string>{}) << disk.method();
}

TEST_F(FullDiskTest, PapersimMetricsCsvAndPlotsFailWithStatus5) {
  const std::string mesh = example_sheet(inputs, "cylinder", "c.obj");
  const std::string csv = (disk.path() / "m.csv").string();
  Outcome r = run({PAPERSIM, "metrics", mesh, "--csv", csv}, disk.fsize_limit());
  EXPECT_EQ(r.status, 5) << disk.method() << ": " << r.err;
  EXPECT_FALSE(fs::exists(csv));
  r = run({PAPERSIM, "metrics", mesh, "--plots", (disk.path() / "plots").string()},
          disk.fsize_limit());
  EXPECT_EQ(r.status, 5) << disk.method() << ": " << r.err;
  EXPECT_EQ(r.err.find("wrote"), std::string::npos) << r.err;
  for (const std::string& name : left_behind(disk.path()))
    EXPECT_EQ(name, "plots") << "an empty folder at most; found " << name;
}

TEST_F(FullDiskTest, ScenegenRenderAndExampleFailWithStatus5AndWriteNothing) {
  const std::string mesh = example_sheet(inputs, "flat", "flat.obj");
  Outcome r = run({SCENEGEN, "render", mesh, "--out", (disk.path() / "sample").string(), "--size",
                   "32x48", "--quality", "draft", "--quiet"},
                  disk.fsize_limit());
  EXPECT_EQ(r.status, 5) << disk.method() << ": " << r.err;
  r = run({SCENEGEN, "example", "flat", "--out", (disk.path() / "flat.obj").string()},
          disk.fsize_limit());
  EXPECT_EQ(r.status, 5) << disk.method() << ": " << r.err;
  EXPECT_EQ(left_behind(disk.path()), std::vector<std::string>{}) << disk.method();
}

// A batch on a full disk stops at its first sample that cannot write (every later one would fail
// the same way at its end), exit status 5, and records no failure: the same command runs every
// sample once there is room. It leaves no sample folder, no row and no staging folder.
TEST_F(FullDiskTest, PapersimBatchStopsWithStatus5AndRecordsNoFailure) {
  const fs::path ds = disk.path() / "ds";
  const Outcome r =
      run({PAPERSIM, "batch", "--out", ds.string(), "--scenarios", "pull", "--seeds", "0-3",
           "--set", "duration=0.05", "--set", "sheet.edge_length=0.02", "--quiet"},
          disk.fsize_limit());
  EXPECT_EQ(r.status, 5) << disk.method() << ": " << r.err;
  EXPECT_NE(r.err.find("cannot"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(ds / "meshes"));
  for (const char* rows : {"manifest.jsonl", "failures.jsonl"}) {
    if (fs::exists(ds / rows)) {
      EXPECT_EQ(fs::file_size(ds / rows), 0u) << rows;
    }
  }
  if (fs::exists(ds / ".staging")) {
    EXPECT_TRUE(fs::is_empty(ds / ".staging"));
  }
}

}  // namespace
}  // namespace papersim::test
