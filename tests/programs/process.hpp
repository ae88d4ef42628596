#pragma once
// Running papersim and scenegen as a user would: argv, exit status, stdout, stderr.
#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace papersim::test {

/// What a finished program reported.
struct Outcome {
  int status = -1;  ///< exit status, or 128 + signal when a signal ended it
  bool signalled = false;
  std::string out, err;
  double seconds = 0;  ///< wall time [s]
};

/// Start `argv` with stdout / stderr to files in `log_dir`; with file_size_limit >= 0 the
/// child's RLIMIT_FSIZE is set to that many bytes (SIGXFSZ left at its default: the program
/// must ignore it itself).
pid_t start(const std::vector<std::string>& argv, const std::filesystem::path& log_dir,
            long file_size_limit = -1);

/// Wait for `pid` at most `timeout` seconds; returns false (and kills it) on timeout.
bool wait_for(pid_t pid, const std::filesystem::path& log_dir, double timeout, Outcome& outcome);

/// start + wait_for with a 120 s timeout (a hang fails the test).
Outcome run(const std::vector<std::string>& argv, long file_size_limit = -1);

/// Direct children of `pid` (from /proc).
std::vector<pid_t> children_of(pid_t pid);

/// True while `pid` exists and is not a zombie.
bool alive(pid_t pid);

/// Whole file as text ("" when missing).
std::string read_text(const std::filesystem::path& path);

/// Regular files and folders below `dir`, relative, sorted ("" entries never).
std::vector<std::string> listing(const std::filesystem::path& dir);

/// A fresh empty folder, removed by the destructor.
class Scratch {
 public:
  explicit Scratch(const std::string& tag);
  ~Scratch();
  const std::filesystem::path& path() const { return m_path; }
  std::string str(const std::string& child) const { return (m_path / child).string(); }

 private:
  std::filesystem::path m_path;
};

}  // namespace papersim::test
