#pragma once
/// Errors shared by every papersim module and program.
#include <stdexcept>
#include <string>

namespace papersim::common {

/// An output file or folder that cannot be created, written, closed or renamed (a full disk, a
/// file size limit, no permission). The message names the file. Exit status 5.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A run that stopped because the program was asked to (SIGINT, SIGTERM).
struct Interrupted : std::runtime_error {
  explicit Interrupted(int signal_number)
      : std::runtime_error("interrupted by signal " + std::to_string(signal_number)),
        signal(signal_number) {}
  int signal;  ///< the signal number (2: SIGINT, 15: SIGTERM)
};

}  // namespace papersim::common
