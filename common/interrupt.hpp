#pragma once
/// Stop requests for the command-line programs: SIGINT and SIGTERM end a run cleanly.
///
/// install_interrupt_handling() handles SIGINT / SIGTERM: the handler only records the signal
/// (the stop request) and wakes a watcher thread. Runs poll stop_requested() and answer by
/// throwing Interrupted; their destructors remove staging folders. Should the program still run
/// STOP_GRACE_SECONDS later (a long solve that does not poll), the waiting thread removes the
/// registered cleanup paths itself and ends the process with status 128 + signal. SIGXFSZ is
/// ignored, so that a file size limit shows as a failed write (exit status 5) instead of killing
/// the program.
#include <filesystem>

namespace papersim::common {

/// Seconds between a stop signal and the forced end of the process.
constexpr double STOP_GRACE_SECONDS = 0.7;

/// Call once at the start of main.
void install_interrupt_handling();

/// True once SIGINT or SIGTERM arrived. Safe from any thread.
bool stop_requested();

/// The signal that asked to stop (0 when none).
int stop_signal();

/// Throw Interrupted when a stop was requested. @throw Interrupted
void throw_if_stop_requested();

/// Remove `path` (recursively) if the process has to be ended before it unwinds.
void add_cleanup_path(const std::filesystem::path& path);

/// Forget a path given to add_cleanup_path (e.g. once the output is published).
void remove_cleanup_path(const std::filesystem::path& path);

/// Restore what install_interrupt_handling changed that exec would keep (SIGXFSZ), in a child
/// process between fork and exec.
void reset_signals_in_child();

}  // namespace papersim::common
