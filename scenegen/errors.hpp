#pragma once
/// Errors of the scenegen module. Library code throws these; only `main` catches them and turns
/// them into a message and a non-zero exit status.
#include <stdexcept>
#include <string>

namespace papersim::scenegen {

/// Bad user input: an unreadable or malformed mesh, document or parameter value.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A file or directory that cannot be read, written, created or renamed.
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// No candidate camera direction sees the whole sheet without self-occlusion.
struct NoValidCameraError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// POV-Ray could not be started or failed on a pass.
struct RenderError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace papersim::scenegen
