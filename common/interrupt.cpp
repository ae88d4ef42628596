#include "common/interrupt.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <mutex>
#include <thread>
#include <vector>

#include "common/errors.hpp"
#include "common/exit_status.hpp"

namespace papersim::common {

namespace fs = std::filesystem;

namespace {

std::atomic<int> g_signal{0};
int g_pipe[2] = {-1, -1};
std::mutex g_mutex;
std::vector<fs::path> g_cleanup;  // guarded by g_mutex

/// The handler only records the first signal and wakes the watcher (async-signal-safe).
extern "C" void on_stop_signal(int signal_number) {
  int expected = 0;
  if (g_signal.compare_exchange_strong(expected, signal_number)) {
    const unsigned char byte = static_cast<unsigned char>(signal_number);
    [[maybe_unused]] const ssize_t n = write(g_pipe[1], &byte, 1);
  }
}

/// Wait for a stop signal, give the program STOP_GRACE_SECONDS to unwind, then end it after
/// removing the registered paths.
void watch() {
  unsigned char byte = 0;
  while (read(g_pipe[0], &byte, 1) != 1) {
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(STOP_GRACE_SECONDS));
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    for (const fs::path& p : g_cleanup) {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  }
  _exit(exit_status_for_signal(g_signal.load()));
}

}  // namespace

void install_interrupt_handling() {
  std::signal(SIGXFSZ, SIG_IGN);
  if (pipe(g_pipe) != 0) return;  // no watcher: signals keep their default action
  fcntl(g_pipe[0], F_SETFD, FD_CLOEXEC);
  fcntl(g_pipe[1], F_SETFD, FD_CLOEXEC);
  std::thread(watch).detach();
  // A handler, not a blocked mask: libraries (OpenBLAS) start threads before main.
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() { return g_signal.load() != 0; }

int stop_signal() { return g_signal.load(); }

void throw_if_stop_requested() {
  if (const int s = g_signal.load()) throw Interrupted(s);
}

void add_cleanup_path(const fs::path& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_cleanup.push_back(path);
}

void remove_cleanup_path(const fs::path& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_cleanup.erase(std::remove(g_cleanup.begin(), g_cleanup.end(), path), g_cleanup.end());
}

void reset_signals_in_child() {
  // exec resets handled signals to their default; an ignored one would stay ignored.
  std::signal(SIGXFSZ, SIG_DFL);
}

}  // namespace papersim::common
