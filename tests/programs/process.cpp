#include "process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace papersim::test {

namespace fs = std::filesystem;

pid_t start(const std::vector<std::string>& argv, const fs::path& log_dir, long file_size_limit) {
  fs::create_directories(log_dir);
  const std::string out = (log_dir / "stdout").string(), err = (log_dir / "stderr").string();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    const int o = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (o < 0 || e < 0) _exit(120);
    dup2(o, 1);
    dup2(e, 2);
    if (file_size_limit >= 0) {
      rlimit limit{static_cast<rlim_t>(file_size_limit), static_cast<rlim_t>(file_size_limit)};
      setrlimit(RLIMIT_FSIZE, &limit);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

bool wait_for(pid_t pid, const fs::path& log_dir, double timeout, Outcome& outcome) {
  const auto t0 = std::chrono::steady_clock::now();
  int status = 0;
  for (;;) {
    const pid_t r = waitpid(pid, &status, WNOHANG);
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r == pid) break;
    if (outcome.seconds > timeout) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  outcome.signalled = WIFSIGNALED(status);
  outcome.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  outcome.out = read_text(log_dir / "stdout");
  outcome.err = read_text(log_dir / "stderr");
  return true;
}

Outcome run(const std::vector<std::string>& argv, long file_size_limit) {
  Scratch logs("logs");
  Outcome outcome;
  const pid_t pid = start(argv, logs.path(), file_size_limit);
  if (!wait_for(pid, logs.path(), 120.0, outcome)) outcome.status = -2;  // a hang
  return outcome;
}

std::vector<pid_t> children_of(pid_t pid) {
  std::vector<pid_t> kids;
  std::error_code ec;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
    std::istringstream in(read_text(task.path() / "children"));
    pid_t k;
    while (in >> k) kids.push_back(k);
  }
  return kids;
}

bool alive(pid_t pid) {
  const std::string stat = read_text("/proc/" + std::to_string(pid) + "/stat");
  if (stat.empty()) return false;
  const auto paren = stat.rfind(')');
  return paren == std::string::npos || paren + 2 >= stat.size() || stat[paren + 2] != 'Z';
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    names.push_back(fs::relative(it->path(), dir).string());
  std::sort(names.begin(), names.end());
  return names;
}

Scratch::Scratch(const std::string& tag) {
  std::random_device rd;
  m_path = fs::temp_directory_path() / ("papersim-programs-" + tag + "-" +
                                        std::to_string(getpid()) + "-" + std::to_string(rd()));
  fs::create_directories(m_path);
}

Scratch::~Scratch() {
  std::error_code ec;
  fs::remove_all(m_path, ec);
}

}  // namespace papersim::test
