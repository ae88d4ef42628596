#include "batch/runner.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <thread>
#include <unordered_map>

#include "batch/row_fields.hpp"
#include "common/clock.hpp"
#include "common/errors.hpp"
#include "common/exit_status.hpp"

namespace papersim::batch {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

volatile sig_atomic_t g_stop_signal = 0;
void on_stop_signal(int signal) { g_stop_signal = signal; }

/// SIGINT and SIGTERM set a flag for the duration of a batch; the old handlers come back after.
class StopSignals {
 public:
  StopSignals() {
    g_stop_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &m_old_int);
    sigaction(SIGTERM, &sa, &m_old_term);
  }
  ~StopSignals() {
    sigaction(SIGINT, &m_old_int, nullptr);
    sigaction(SIGTERM, &m_old_term, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction m_old_int {
  }, m_old_term{};
};

/// An flock on ROOT/.locks/<task>.lock; released when every copy of the descriptor is closed
/// (the child running the task holds a copy, so a lock outlives a killed batch only as long
/// as its child).
class TaskLock {
 public:
  TaskLock() = default;
  explicit TaskLock(int fd) : m_fd(fd) {}
  TaskLock(TaskLock&& o) noexcept : m_fd(o.m_fd) { o.m_fd = -1; }
  TaskLock& operator=(TaskLock&& o) noexcept {
    release();
    m_fd = o.m_fd;
    o.m_fd = -1;
    return *this;
  }
  TaskLock(const TaskLock&) = delete;
  TaskLock& operator=(const TaskLock&) = delete;
  ~TaskLock() { release(); }
  bool held() const { return m_fd >= 0; }
  int fd() const { return m_fd; }
  void release() {
    if (m_fd >= 0) close(m_fd);
    m_fd = -1;
  }

  /// @throw common::OutputError when the lock file cannot be opened
  static TaskLock try_take(const fs::path& file) {
    const int fd = open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
      throw common::OutputError("cannot open lock file '" + file.string() +
                                "': " + std::strerror(errno));
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      close(fd);
      return TaskLock();
    }
    return TaskLock(fd);
  }

 private:
  int m_fd = -1;
};

/// The last non-empty line of a text file (its final 4 KiB).
std::string last_line(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return "";
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff start = size > 4096 ? size - 4096 : 0;
  in.seekg(start);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' '))
    text.pop_back();
  const auto nl = text.find_last_of('\n');
  return nl == std::string::npos ? text : text.substr(nl + 1);
}

/// Fork and exec `cmd` in its own process group, stdout to `out`, stderr to `log`, holding a
/// copy of `lock_fd`, and dying with this process.
/// @throw std::runtime_error when fork fails
pid_t spawn(const Command& cmd, const fs::path& log, int lock_fd) {
  std::vector<char*> argv;
  for (const auto& a : cmd.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const std::string out_path = cmd.stdout_path.empty() ? log.string() : cmd.stdout_path.string();
  const std::string log_path = log.string();
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("cannot fork: ") + std::strerror(errno));
  if (pid > 0) {
    setpgid(pid, pid);  // also in the child: whichever runs first
    return pid;
  }
  // Child: only async-signal-safe calls until exec.
  setpgid(0, 0);
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(137);
  signal(SIGINT, SIG_DFL);
  signal(SIGTERM, SIG_DFL);
  signal(SIGPIPE, SIG_DFL);  // an ignored signal stays ignored across exec
  const int in = open("/dev/null", O_RDONLY);
  const int out = open(out_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  const int err = open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (in < 0 || out < 0 || err < 0) _exit(126);
  dup2(in, 0);
  dup2(out, 1);
  dup2(err, 2);
  // dup clears close-on-exec: the child holds the lock
  if (lock_fd >= 0 && dup(lock_fd) < 0) _exit(126);
  execv(argv[0], argv.data());
  const char msg[] = "batch: cannot execute the sample program\n";
  [[maybe_unused]] const ssize_t w = write(2, msg, sizeof msg - 1);
  _exit(127);
}

/// A task at work: its lock, staging folder and current child.
struct Slot {
  std::size_t task = 0;
  TaskLock lock;
  fs::path stage, log;
  std::vector<Command> commands;
  std::size_t next = 0;  ///< index of the command running now
  pid_t pid = -1;
  Clock::time_point start;
  /// The share done (BatchSpec::running_share) when first known, and when last seen to grow,
  /// with the times they were read: the task's rate in this run.
  double share_first = -1.0, share_last = -1.0;
  Clock::time_point share_first_time, share_last_time;
  double cpu_seconds = 0.0;  ///< user + system time of the finished commands [s]
  bool timed_out = false;
  /// The task's folder is in place and its manifest row not yet appended: the stage is kept
  /// (also when the batch stops), so the next scan knows to look for the row (Runner::scan).
  bool placed = false;
};

class Runner {
 public:
  Runner(const TaskList& tasks, const BatchSpec& spec) : m_tasks(tasks), m_spec(spec) {}
  BatchSummary run();

 private:
  const TaskList& m_tasks;
  const BatchSpec& m_spec;
  std::deque<std::size_t> m_pending, m_waiting;
  std::vector<std::unique_ptr<Slot>> m_slots;
  BatchSummary m_sum;
  Clock::time_point m_t0 = Clock::now(), m_last_progress = Clock::now(), m_last_wait_check;
  Clock::time_point m_run_start = Clock::now();  ///< when the tasks were checked (scan)
  unsigned m_attempt = 0;
  /// The staging folders in ROOT/.staging when the tasks were checked, by their task's
  /// safe_name (stage_owner).
  std::unordered_map<std::string, std::vector<fs::path>> m_stages;

  fs::path manifest() const { return m_spec.root / m_spec.manifest_name; }
  fs::path failures() const { return m_spec.root / m_spec.failures_name; }
  fs::path lock_file(std::string_view key) const {
    return m_spec.root / ".locks" / (safe_name(std::string(key)) + ".lock");
  }
  bool finished(std::string_view key) const { return fs::exists(m_spec.root / key); }

  /// The progress of reading `file` for the step printer (none without one).
  std::function<void(std::uintmax_t, std::uintmax_t)> reading(const fs::path& file) const;
  void scan();
  void repair(const std::vector<std::size_t>& tasks);
  nlohmann::json manifest_row(const Task& t, double wall, double cpu) const;
  void record_failure(const Task& t, const std::string& reason, const std::string& detail,
                      double wall);
  void remove_stages(const Task& t) const;
  void fill_slots();
  bool try_start(std::size_t task);
  void start_next_command(Slot& s);
  void poll();
  void on_exit(Slot& s, int status);
  void finish(Slot& s);
  void fail(Slot& s, const std::string& reason, const std::string& detail);
  void stop_all();
  void report(bool force);
};

namespace {

/// The task (its safe_name) whose staging folder is named `name`, "<safe name>.<pid>.<attempt>"
/// (Runner::try_start); empty for any other name.
std::string stage_owner(const std::string& name) {
  const auto digits_before = [&name](std::size_t end) {  // start of the digits ending at `end`
    std::size_t b = end;
    while (b > 0 && name[b - 1] >= '0' && name[b - 1] <= '9') --b;
    return b;
  };
  const std::size_t attempt = digits_before(name.size());
  if (attempt == name.size() || attempt < 2 || name[attempt - 1] != '.') return "";
  const std::size_t pid = digits_before(attempt - 1);
  if (pid == attempt - 1 || pid < 2 || name[pid - 1] != '.') return "";
  return name.substr(0, pid - 1);
}

/// The staging folders in `dir` by their task's safe_name (none when `dir` cannot be listed).
std::unordered_map<std::string, std::vector<fs::path>> stages_by_task(const fs::path& dir) {
  std::unordered_map<std::string, std::vector<fs::path>> stages;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::string owner = stage_owner(it->path().filename().string());
    if (!owner.empty()) stages[std::move(owner)].push_back(it->path());
  }
  return stages;
}

/// Append `row` as one line of a JSON-lines file (bytes that are not UTF-8 become U+FFFD).
void append_row(const fs::path& file, const nlohmann::json& row) {
  append_line(file, row.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

/// Whether a file has a byte (a missing one has none).
bool has_bytes(const fs::path& file) {
  std::error_code ec;
  const auto n = fs::file_size(file, ec);
  return !ec && n > 0;
}

/// fs::exists(root / path) for many paths of few parent folders, as a dataset's sample folders
/// are (meshes/<scenario>/<bucket>/<seed>): a parent asked for by many paths is listed once, and
/// only when its own parent lists it, so a path whose parent is missing or does not list its name
/// costs no system call (a fresh batch of ten million samples made ten million failing `stat`s,
/// 19 s). A parent asked for by few paths is not listed: each of them costs one `stat`, and none
/// when the parent is missing. A Slurm array task's shard has one sample in each bucket folder of
/// a thousand, and it listed every one of them to look for that sample. A listed symbolic link
/// is looked up as fs::exists would.
class FolderCheck {
 public:
  explicit FolderCheck(fs::path root) : m_root(std::move(root)) {}

  bool exists(std::string_view path) {
    const std::size_t slash = path.rfind('/');
    const std::string parent(slash == std::string::npos ? "" : path.substr(0, slash));
    if (m_parents.find(parent) == m_parents.end()) {
      if (m_asked.size() >= kAsked) m_asked.clear();
      if (++m_asked[parent] <= kStatFirst) {
        if (!parent.empty() && !exists(parent)) return false;
        std::error_code ec;
        return fs::exists(m_root / std::string(path), ec);
      }
    }
    const std::string name(slash == std::string::npos ? path : path.substr(slash + 1));
    const auto& names = listing(parent);
    const auto entry = names.find(name);
    if (entry == names.end()) return false;
    return entry->second || fs::exists(m_root / path);
  }

 private:
  static constexpr std::size_t kParents = 256;  ///< parents listed at once (a mix interleaves some)
  static constexpr int kStatFirst = 8;  ///< paths of a parent looked up by `stat` before listing it
  static constexpr std::size_t kAsked = 65536;  ///< parents counted at once

  /// The listing of `parent` (relative to the root; "" is the root), made when first asked for:
  /// none when the parent is missing by its own parent's listing, so a missing bucket costs one
  /// listing of its scenario's folder rather than an attempt per sample or mesh in it.
  const std::unordered_map<std::string, bool>& listing(const std::string& parent) {
    auto it = m_parents.find(parent);
    if (it != m_parents.end()) return it->second;
    const bool there = parent.empty() || exists(parent);
    if (m_parents.size() >= kParents) m_parents.clear();
    return m_parents
        .emplace(parent, there ? list(m_root / parent) : std::unordered_map<std::string, bool>{})
        .first->second;
  }

  /// The names in `dir`, each with whether it surely exists: all but symbolic links, whose
  /// target may be missing (none when `dir` cannot be listed). The listing tells each entry's
  /// type, so this costs no `stat` per name.
  static std::unordered_map<std::string, bool> list(const fs::path& dir) {
    std::unordered_map<std::string, bool> names;
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      names.emplace(it->path().filename().string(), !it->is_symlink(ec));
    return names;
  }

  fs::path m_root;
  std::unordered_map<std::string, std::unordered_map<std::string, bool>> m_parents;
  std::unordered_map<std::string, int> m_asked;  ///< paths asked for per parent not listed
};

}  // namespace

std::function<void(std::uintmax_t, std::uintmax_t)> Runner::reading(const fs::path& file) const {
  std::function<void(std::uintmax_t, std::uintmax_t)> f;
  if (m_spec.step_progress)
    f = [&tell = m_spec.step_progress, what = "reading " + file.string()](std::uintmax_t read,
                                                                          std::uintmax_t size) {
      tell(what, static_cast<double>(read) / 1e6, static_cast<double>(size) / 1e6, "MB");
    };
  return f;
}

void Runner::scan() {
  // A task is done when its folder exists, so the folders are looked for first. A finished
  // task's stage is removed only after its manifest row is appended (Runner::finish), so a done
  // task may lack its row only when a stage of it is left in ROOT/.staging (a crash, a kill or a
  // full disk between the two), or when the manifest is missing or empty (deleted to be rebuilt):
  // only then is the manifest searched, for those tasks' keys (Runner::repair). The failures file
  // is searched for the keys of the tasks not done, when failures are not retried. So a resumed
  // Slurm array task does not read the manifest the other array tasks are writing (gigabytes
  // for ten million samples) unless a crash left one of its own samples without a row.
  const auto& tell = m_spec.step_progress;
  std::vector<bool> done(m_tasks.size());
  {  // the listings it keeps (16 MB for a million tasks) go before the key sets are made
    FolderCheck folders(m_spec.root);
    const std::string looking = "looking for the " + m_spec.items + "' folders";
    for (std::size_t i = 0; i < m_tasks.size(); ++i) {
      if (tell && i % 65536 == 65535)
        tell(looking, static_cast<double>(i), static_cast<double>(m_tasks.size()), m_spec.items);
      if (folders.exists(m_tasks.key(i))) {
        done[i] = true;
        ++m_sum.done;
      } else {
        m_pending.push_back(i);
      }
    }
  }
  std::vector<std::size_t> may_lack_row;
  if (m_sum.done > 0) {
    const bool rebuild = !has_bytes(manifest());
    m_stages = stages_by_task(m_spec.root / ".staging");
    if (rebuild || !m_stages.empty())
      for (std::size_t i = 0; i < m_tasks.size(); ++i)
        if (done[i] && (rebuild || m_stages.count(safe_name(std::string(m_tasks.key(i)))) > 0))
          may_lack_row.push_back(i);
  }
  if (!m_pending.empty() && !m_spec.retry_failed && has_bytes(failures())) {
    KeySet keys;
    for (std::size_t i = 0; i < m_tasks.size(); ++i)
      if (!done[i]) keys.insert(m_tasks.key(i));
    const KeySet failed = keys_in_json_lines(failures(), keys, reading(failures()));
    const auto recorded = [&](std::size_t i) { return failed.contains(m_tasks.key(i)); };
    const auto before = m_pending.size();
    m_pending.erase(std::remove_if(m_pending.begin(), m_pending.end(), recorded), m_pending.end());
    m_sum.failed += static_cast<long long>(before - m_pending.size());
  }
  repair(may_lack_row);
  m_stages.clear();
}

/// Rows for done tasks that may lack one (Runner::scan): the manifest is read once for their
/// keys; then, a few hundred tasks at a time, their locks are taken (a task another process holds
/// is left to it) and only the rows appended since are read, so a batch appending the same row
/// right now is not doubled. A task without a row gets one; its stages go.
void Runner::repair(const std::vector<std::size_t>& tasks) {
  if (tasks.empty()) return;
  constexpr std::size_t kLocksAtOnce = 256;  // open files: a shell's limit is often 1,024
  KeySet keys;
  for (std::size_t i : tasks) keys.insert(m_tasks.key(i));
  std::uintmax_t read = 0;  // the manifest's bytes searched so far
  const KeySet rows = keys_in_json_lines(manifest(), keys, reading(manifest()), &read);
  const std::string restoring = "restoring the manifest rows of " + m_spec.items + " found done";
  for (std::size_t start = 0; start < tasks.size(); start += kLocksAtOnce) {
    if (m_spec.step_progress && start > 0)
      m_spec.step_progress(restoring, static_cast<double>(start), static_cast<double>(tasks.size()),
                           m_spec.items);
    std::vector<std::pair<std::size_t, TaskLock>> held;
    for (std::size_t k = start; k < std::min(tasks.size(), start + kLocksAtOnce); ++k) {
      TaskLock lock = TaskLock::try_take(lock_file(m_tasks.key(tasks[k])));
      if (lock.held()) held.emplace_back(tasks[k], std::move(lock));
    }
    KeySet wanted;
    for (const auto& [i, lock] : held)
      if (!rows.contains(m_tasks.key(i))) wanted.insert(m_tasks.key(i));
    const KeySet appended = keys_in_json_lines(manifest(), wanted, {}, &read);
    for (const auto& [i, lock] : held) {
      const std::string_view key = m_tasks.key(i);
      if (!rows.contains(key) && !appended.contains(key)) {
        const Task t = m_tasks[i];
        nlohmann::json row;
        try {
          row = manifest_row(t, -1.0, -1.0);
        } catch (const common::OutputError&) {
          throw;
        } catch (const std::exception& e) {
          throw DatasetError("'" + (m_spec.root / t.key).string() +
                             "' is finished (the folder exists) but has no row in '" +
                             manifest().string() + "', and none can be made from it: " + e.what() +
                             ". Remove the folder to make it again");
        }
        append_row(manifest(), row);
        ++m_sum.repaired;
      }
      const auto stages = m_stages.find(safe_name(std::string(key)));
      if (stages == m_stages.end()) continue;
      std::error_code ec;
      for (const fs::path& stage : stages->second) fs::remove_all(stage, ec);
    }
  }
}

nlohmann::json Runner::manifest_row(const Task& t, double wall, double cpu) const {
  nlohmann::json row = t.info_object();
  row["key"] = t.key;
  row["path"] = t.key;
  row["cpu_seconds"] = cpu >= 0 ? nlohmann::json(cpu) : nlohmann::json(nullptr);
  if (m_spec.manifest_row) row.update(m_spec.manifest_row(t, m_spec.root / t.key, wall));
  return row;
}

void Runner::record_failure(const Task& t, const std::string& reason, const std::string& detail,
                            double wall) {
  nlohmann::json row = t.info_object();
  row["key"] = t.key;
  row["reason"] = reason;
  row["detail"] = detail;
  row["wall_seconds"] = wall;
  // The detail is a child's last log line: any bytes. Bytes that are not UTF-8 become U+FFFD.
  append_row(failures(), row);
  ++m_sum.failed;
  ++m_sum.failed_now;
}

void Runner::remove_stages(const Task& t) const {
  const std::string name = safe_name(t.key);
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(m_spec.root / ".staging", ec))
    if (stage_owner(e.path().filename().string()) == name) fs::remove_all(e.path(), ec);
}

bool Runner::try_start(std::size_t task) {
  const Task t = m_tasks[task];
  TaskLock lock = TaskLock::try_take(lock_file(t.key));
  if (!lock.held()) return false;
  if (finished(t.key)) {  // another process finished it since the scan
    ++m_sum.done;
    return true;
  }
  remove_stages(t);
  auto s = std::make_unique<Slot>();
  s->task = task;
  s->lock = std::move(lock);
  s->stage =
      m_spec.root / ".staging" /
      (safe_name(t.key) + "." + std::to_string(getpid()) + "." + std::to_string(m_attempt++));
  s->log = s->stage / "log.txt";
  s->start = Clock::now();
  fs::create_directories(s->stage);
  try {
    if (m_spec.prepare) m_spec.prepare(t, s->stage);
    s->commands = m_spec.commands(t, s->stage);
  } catch (const common::OutputError&) {
    std::error_code ec;
    fs::remove_all(s->stage, ec);
    throw;  // as a child that cannot write: the batch stops (Runner::run)
  } catch (const std::exception& e) {
    fail(*s, "prepare", e.what());
    return true;
  }
  start_next_command(*s);
  m_slots.push_back(std::move(s));
  return true;
}

void Runner::start_next_command(Slot& s) { s.pid = spawn(s.commands[s.next], s.log, s.lock.fd()); }

void Runner::fill_slots() {
  while (static_cast<int>(m_slots.size()) < m_spec.jobs && !m_pending.empty()) {
    const std::size_t i = m_pending.front();
    m_pending.pop_front();
    if (!try_start(i)) m_waiting.push_back(i);
  }
  // Tasks another process holds: look again twice a second while a slot is free.
  if (m_waiting.empty() || static_cast<int>(m_slots.size()) >= m_spec.jobs) return;
  if (seconds_since(m_last_wait_check) < 0.5) return;
  m_last_wait_check = Clock::now();
  const std::size_t n = m_waiting.size();
  for (std::size_t k = 0; k < n && static_cast<int>(m_slots.size()) < m_spec.jobs; ++k) {
    const std::size_t i = m_waiting.front();
    m_waiting.pop_front();
    if (!try_start(i)) m_waiting.push_back(i);
  }
}

void Runner::poll() {
  for (std::size_t k = 0; k < m_slots.size();) {
    Slot& s = *m_slots[k];
    int status = 0;
    struct rusage usage {};
    const pid_t r = wait4(s.pid, &status, WNOHANG, &usage);
    if (r == s.pid) {
      s.cpu_seconds += static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                       1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
      on_exit(s, status);
    } else if (m_spec.time_limit > 0 && !s.timed_out &&
               seconds_since(s.start) > m_spec.time_limit) {
      s.timed_out = true;
      kill(-s.pid, SIGKILL);
    }
    if (s.pid < 0) {
      m_slots.erase(m_slots.begin() + static_cast<std::ptrdiff_t>(k));
    } else {
      ++k;
    }
  }
}

void Runner::on_exit(Slot& s, int status) {
  kill(-s.pid, SIGKILL);  // anything the child left behind in its group
  s.pid = -1;
  if (s.timed_out) {
    fail(s, "time limit", "exceeded " + std::to_string(m_spec.time_limit) + " s");
    return;
  }
  if (WIFSIGNALED(status)) {
    fail(s, "signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")",
         last_line(s.log));
    return;
  }
  const int code = WEXITSTATUS(status);
  if (code == common::EXIT_OUTPUT) {
    // The child could not write its output (a full disk, a file size limit, no permission): every
    // later sample would fail the same way at its end, so the batch stops, and records nothing for
    // this sample, which the same command runs again once there is room.
    throw common::OutputError(
        std::string(m_tasks.key(s.task)) + ": " + last_line(s.log) +
        " (the batch stopped; nothing is recorded for this sample: free space and "
        "run the same command again)");
  }
  if (code != 0) {
    const std::string line = last_line(s.log);
    std::string reason = m_spec.failure_reason ? m_spec.failure_reason(code, line) : "";
    if (reason.empty()) reason = "exit status " + std::to_string(code);
    fail(s, reason, line);
    return;
  }
  if (++s.next < s.commands.size()) {
    start_next_command(s);
    return;
  }
  finish(s);
}

void Runner::finish(Slot& s) {
  const Task t = m_tasks[s.task];
  const Attempt attempt{s.stage, seconds_since(s.start), s.cpu_seconds};
  fs::path product;
  try {
    product = m_spec.finalize(t, attempt);
  } catch (const common::OutputError&) {
    throw;  // as a child that cannot write: the batch stops (Runner::run)
  } catch (const std::exception& e) {
    fail(s, "outputs", e.what());
    return;
  }
  const fs::path target = m_spec.root / t.key;
  fs::create_directories(target.parent_path());
  fs::rename(product, target);  // the one step that makes the sample exist
  s.placed = true;
  append_row(manifest(), manifest_row(t, attempt.wall_seconds, attempt.cpu_seconds));
  std::error_code ec;
  fs::remove_all(s.stage, ec);  // only now: a stage left tells the next scan to look for the row
  s.lock.release();
  ++m_sum.done;
  ++m_sum.done_now;
}

void Runner::fail(Slot& s, const std::string& reason, const std::string& detail) {
  record_failure(m_tasks[s.task], reason, detail, seconds_since(s.start));
  std::error_code ec;
  fs::remove_all(s.stage, ec);
  s.lock.release();
  s.pid = -1;
}

/// Interrupted: terminate every child's group, give them 3 s, then kill; nothing is recorded.
void Runner::stop_all() {
  for (auto& s : m_slots)
    if (s->pid > 0) kill(-s->pid, SIGTERM);
  const auto t0 = Clock::now();
  for (auto& s : m_slots) {
    while (s->pid > 0) {
      int status = 0;
      if (waitpid(s->pid, &status, WNOHANG) == s->pid) {
        kill(-s->pid, SIGKILL);
        s->pid = -1;
      } else if (seconds_since(t0) > 3.0) {
        kill(-s->pid, SIGKILL);
        waitpid(s->pid, &status, 0);
        s->pid = -1;
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    }
    std::error_code ec;
    if (!s->placed) fs::remove_all(s->stage, ec);
  }
  m_slots.clear();
  m_sum.interrupted = true;
}

void Runner::report(bool force) {
  if (!m_spec.progress || (!force && seconds_since(m_last_progress) < m_spec.progress_every))
    return;
  m_last_progress = Clock::now();
  Progress p;
  p.total = m_sum.total;
  p.done = m_sum.done;
  p.failed = m_sum.failed;
  p.running = static_cast<long long>(m_slots.size());
  p.waiting = static_cast<long long>(m_waiting.size());
  p.done_now = m_sum.done_now;
  p.elapsed = seconds_since(m_t0);
  const long long ended_now = m_sum.done_now + m_sum.failed_now;
  const double running = seconds_since(m_run_start);
  if (ended_now > 0 && running > 0) {
    p.per_hour = 3600.0 * static_cast<double>(m_sum.done_now) / running;
    const long long left = p.total - p.done - p.failed;
    p.eta = static_cast<double>(left) * running / static_cast<double>(ended_now);
  }
  std::vector<RunningRate> rates;
  if (m_spec.running_share) {
    const auto now = Clock::now();
    for (const auto& s : m_slots) {
      const double share = m_spec.running_share(m_tasks[s->task]);
      if (share < 0) continue;
      p.running_done.push_back(share);
      if (s->share_first < 0) {
        s->share_first = s->share_last = share;
        s->share_first_time = s->share_last_time = now;
      } else if (share > s->share_last) {
        s->share_last = share;
        s->share_last_time = now;
      }
      const double dt =
          std::chrono::duration<double>(s->share_last_time - s->share_first_time).count();
      if (s->share_last > s->share_first && dt > 0)
        rates.push_back({share, (s->share_last - s->share_first) / dt});
    }
  }
  if (p.total - p.done - p.failed == 0) {
    p.eta = 0.0;
  } else if (ended_now == 0) {
    const long long queued = p.total - p.done - p.failed - static_cast<long long>(rates.size());
    p.eta = eta_from_running(rates, queued, m_spec.jobs);
  }
  m_spec.progress(p);
}

BatchSummary Runner::run() {
  fs::create_directories(m_spec.root / ".locks");
  fs::create_directories(m_spec.root / ".staging");
  m_sum.total = static_cast<long long>(m_tasks.size());
  StopSignals signals;
  scan();
  // The first line once the tasks are checked: how many were done before. The rate counts
  // from here, without the check.
  m_run_start = Clock::now();
  report(true);
  m_last_wait_check = Clock::now() - std::chrono::seconds(1);
  try {
    while (!m_pending.empty() || !m_waiting.empty() || !m_slots.empty()) {
      if (g_stop_signal) {
        stop_all();
        break;
      }
      fill_slots();
      poll();
      report(false);
      // Tasks another process held may have finished meanwhile: fill_slots counts them then.
      std::this_thread::sleep_for(std::chrono::milliseconds(m_slots.empty() ? 100 : 20));
    }
  } catch (...) {
    // The manifest, the failures file or a sample's folder cannot be written (a full disk):
    // stop every running sample and remove this process's staging folders, also one whose
    // failure could not be recorded; the finished samples and whole lines stay, and the same
    // command later runs the rest. The stage of a sample whose row could not be appended stays,
    // so that command restores the row.
    std::vector<fs::path> keep;
    for (const auto& s : m_slots)
      if (s->placed) keep.push_back(s->stage);
    stop_all();
    const std::string mine = "." + std::to_string(getpid()) + ".";
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(m_spec.root / ".staging", ec))
      if (e.path().filename().string().find(mine) != std::string::npos &&
          std::find(keep.begin(), keep.end(), e.path()) == keep.end())
        fs::remove_all(e.path(), ec);
    throw;
  }
  m_sum.elapsed = seconds_since(m_t0);
  report(true);
  return m_sum;
}

}  // namespace

TaskList select_shard(const TaskList& tasks, int index, int count) {
  if (count < 1 || index < 0 || index >= count)
    throw std::invalid_argument("shard " + std::to_string(index) + "/" + std::to_string(count) +
                                " is not I/N with 0 <= I < N");
  TaskList out;
  for (std::size_t p = static_cast<std::size_t>(index); p < tasks.size();
       p += static_cast<std::size_t>(count))
    out.add(tasks.key(p), tasks.info(p));
  return out;
}

double eta_from_running(const std::vector<RunningRate>& running, long long queued, int jobs) {
  double longest = 0, work = 0, whole = 0;
  int known = 0;
  for (const auto& r : running) {
    if (!(r.rate > 0)) continue;
    const double rest = std::max(0.0, 1.0 - r.share) / r.rate;
    longest = std::max(longest, rest);
    work += rest;
    whole += 1.0 / r.rate;
    ++known;
  }
  if (known == 0) return -1.0;
  work += static_cast<double>(std::max(queued, 0LL)) * whole / known;
  return std::max(longest, work / std::max(jobs, 1));
}

std::pair<int, int> parse_shard(const std::string& text, const std::string& option) {
  const auto slash = text.find('/');
  try {
    if (slash == std::string::npos) throw std::invalid_argument(text);
    std::size_t used_i = 0, used_n = 0;
    const int i = std::stoi(text.substr(0, slash), &used_i);
    const int n = std::stoi(text.substr(slash + 1), &used_n);
    if (used_i != slash || used_n != text.size() - slash - 1 || n < 1 || i < 0 || i >= n)
      throw std::invalid_argument(text);
    return {i, n};
  } catch (const std::logic_error&) {
    throw std::invalid_argument(option + " '" + text + "' is not I/N with 0 <= I < N (e.g. 0/4)");
  }
}

BatchSummary run_batch(const TaskList& tasks, const BatchSpec& spec) {
  if (spec.jobs < 1) throw std::invalid_argument("jobs must be >= 1");
  if (!spec.commands || !spec.finalize)
    throw std::invalid_argument("batch spec needs commands and finalize");
  Runner runner(tasks, spec);
  return runner.run();
}

void append_line(const fs::path& path, const std::string& text) {
  const std::string line = text + "\n";
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0)
    throw common::OutputError("cannot open '" + path.string() + "': " + std::strerror(errno));
  // Appenders of other processes wait here, so a line cut short (a full disk) can be cut off
  // again before another is appended after it.
  int locked = -1;
  while ((locked = flock(fd, LOCK_EX)) != 0 && errno == EINTR) {
  }
  struct stat before {};
  const bool sized = locked == 0 && fstat(fd, &before) == 0;  // unlocked (ENOLCK): never cut
  const ssize_t w = write(fd, line.data(), line.size());
  const int write_errno = errno;
  const bool synced = w == static_cast<ssize_t>(line.size()) && fdatasync(fd) == 0;
  const int sync_errno = errno;
  if (!synced && sized) {
    if (ftruncate(fd, before.st_size) == 0) fdatasync(fd);
  }
  close(fd);  // releases the lock
  if (!synced)
    throw common::OutputError("cannot append to '" + path.string() + "': " +
                              (w < 0 ? std::strerror(write_errno)
                               : w != static_cast<ssize_t>(line.size())
                                   ? "short write (the disk is full?)"
                                   : std::strerror(sync_errno)));
}

std::vector<nlohmann::json> read_json_lines(const fs::path& path) {
  std::vector<nlohmann::json> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (!j.is_discarded() && j.is_object()) rows.push_back(std::move(j));
  }
  return rows;
}

KeySet keys_in_json_lines(const fs::path& path, const KeySet& wanted,
                          const std::function<void(std::uintmax_t, std::uintmax_t)>& progress,
                          std::uintmax_t* offset) {
  KeySet found;
  if (wanted.size() == 0) return found;
  const std::vector<std::string> no_figures;
  RowFields row(no_figures);  // the row's own "key", read without building the row
  std::ifstream in(path, std::ios::binary);
  if (offset && *offset > 0) in.seekg(static_cast<std::streamoff>(*offset));
  std::error_code ec;
  const std::uintmax_t size = progress ? fs::file_size(path, ec) : 0;
  std::uintmax_t read = offset ? *offset : 0, lines = 0;
  std::string line;
  while (std::getline(in, line)) {
    // A last line without its newline (being appended) is searched but not passed over.
    if (!in.eof()) read += line.size() + 1;
    if (offset) *offset = read;
    if (progress && ++lines % 4096 == 0) progress(read, ec ? read : size);
    // Every wanted row holds "key" then a colon and the key as a JSON string. Only a line where
    // such a string, read up to its closing quote, is a wanted key is parsed, so that the row's
    // own "key" decides (the pattern may also be a nested object's). A line with a backslash
    // (an escaped character: the raw text is not the value) is always parsed.
    bool candidate = line.find('\\') != std::string::npos;
    for (std::size_t at = line.find("\"key\""); !candidate && at != std::string::npos;
         at = line.find("\"key\"", at + 5)) {
      std::size_t i = line.find_first_not_of(" \t\r", at + 5);
      if (i == std::string::npos || line[i] != ':') continue;
      i = line.find_first_not_of(" \t\r", i + 1);
      if (i == std::string::npos || line[i] != '"') continue;
      const std::size_t end = line.find('"', i + 1);
      if (end != std::string::npos &&
          wanted.contains(std::string_view(line).substr(i + 1, end - i - 1)))
        candidate = true;
    }
    if (!candidate) continue;
    if (row.read_key(line) && wanted.contains(row.key())) found.insert(row.key());
  }
  return found;
}

void write_file_atomically(const fs::path& path, const std::string& text) {
  // The process id in the temporary name: two batches on one dataset may write the same file.
  const fs::path tmp = path.string() + ".tmp" + std::to_string(getpid());
  {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.close();
    if (!out) {
      const int error = errno;
      std::error_code ec;
      fs::remove(tmp, ec);
      throw common::OutputError("cannot write '" + path.string() +
                                "': " + (error != 0 ? std::strerror(error) : "write failed"));
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw common::OutputError("cannot write '" + path.string() + "': " + ec.message());
  }
}

fs::path self_executable() { return fs::read_symlink("/proc/self/exe"); }

std::string safe_name(const std::string& key) {
  std::string s = key;
  for (char& c : s)
    if (c == '/' || c == ' ') c = '_';
  return s;
}

}  // namespace papersim::batch
