#pragma once
// Comparing two datasets and driving the batch programs from tests.
#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace papersim::test {

/// Differences between two datasets, one line each (empty: equal). Compared: the same files
/// under `part` (meshes or renders); every file byte for byte except meshes' meta.json, which is
/// compared as JSON without its wall times ("wall_seconds", "seconds", "seconds_*": they measure
/// this run, not the sample); the manifest as a set of rows by key, without wall_seconds,
/// sim_wall_seconds and cpu_seconds. Also reports staging leftovers.
std::vector<std::string> dataset_differences(const std::filesystem::path& a,
                                             const std::filesystem::path& b,
                                             const std::string& part, const std::string& manifest);

/// Start `argv` with stdout and stderr into `log`; returns its process id.
pid_t start(const std::vector<std::string>& argv, const std::filesystem::path& log);

/// Wait for `pid`; its exit status, or 128 + signal.
int wait_status(pid_t pid);

/// Lines in a file (0 when missing).
std::size_t line_count(const std::filesystem::path& file);

/// Text of a file.
std::string read_text(const std::filesystem::path& file);

}  // namespace papersim::test
