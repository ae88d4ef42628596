#include "common/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/format.hpp"

namespace papersim::common {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& tag) {
  const fs::path p =
      fs::temp_directory_path() / ("papersim-atomic-" + tag + "-" + std::to_string(getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(AtomicFile, WritesTheWholeTextAndLeavesNoTemporary) {
  const fs::path dir = scratch("ok");
  write_text_atomically(dir / "a.txt", "hello\n");
  EXPECT_EQ(read(dir / "a.txt"), "hello\n");
  EXPECT_FALSE(fs::exists(dir / "a.txt.tmp"));
  fs::remove_all(dir);
}

TEST(AtomicFile, AFailingWriterKeepsTheOldFileAndRemovesTheTemporary) {
  const fs::path dir = scratch("throw");
  write_text_atomically(dir / "a.txt", "old\n");
  EXPECT_THROW(write_file_atomically(dir / "a.txt",
                                     [](std::ostream& out) {
                                       out << "half";
                                       throw std::runtime_error("writer failed");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read(dir / "a.txt"), "old\n");
  EXPECT_FALSE(fs::exists(dir / "a.txt.tmp"));
  fs::remove_all(dir);
}

TEST(AtomicFile, AMissingFolderIsAnOutputErrorNamingTheFile) {
  const fs::path dir = scratch("missing");
  try {
    write_text_atomically(dir / "no" / "a.txt", "x");
    FAIL() << "expected OutputError";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("a.txt"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// The file size limit stands in for a full disk: the data (64 KiB) does not fit under the limit
// (1 KiB), so the write fails when the buffer is flushed or the file closed. Checked in a child
// process, whose limit does not touch the test runner.
TEST(AtomicFile, AWriteBeyondTheFileSizeLimitIsAnOutputErrorAndLeavesNothing) {
  const fs::path dir = scratch("fsize");
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit{1024, 1024};
    setrlimit(RLIMIT_FSIZE, &limit);
    try {
      write_text_atomically(dir / "big.txt", std::string(65536, 'x'));
      _exit(10);  // reported success: the bug of issue 17
    } catch (const OutputError& e) {
      _exit(fs::exists(dir / "big.txt") || fs::exists(dir / "big.txt.tmp") ? 11 : 0);
    } catch (...) {
      _exit(12);
    }
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "10: success reported, 11: a file left, 12: wrong error";
  fs::remove_all(dir);
}

TEST(FormatNumber, IsShortForHugeValues) {
  EXPECT_EQ(format_number(1e300), "1e+300");
  EXPECT_EQ(format_number(0.25), "0.25");
  EXPECT_LE(format_number(-1.7976931348623157e308).size(), 13u);
}

}  // namespace
}  // namespace papersim::common
