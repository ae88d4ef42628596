#pragma once
/// Errors of the batch module that a program reports with its own exit status.

#include <stdexcept>

namespace papersim::batch {

/// A dataset that cannot be read or gone on with: a path that is not a folder, a file that cannot
/// be read, a finished task's folder from which its missing manifest row cannot be made. The
/// message names the path. Exit status 2.
struct DatasetError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace papersim::batch
