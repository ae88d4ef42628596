#pragma once
/// Atomic file writes: a file appears under its name complete, or not at all.
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

#include "common/errors.hpp"

namespace papersim::common {

/// Write `path` through a temporary file beside it (`path` + ".tmp"): `fill` writes the
/// content, the stream is flushed, closed and checked, and only then renamed over `path`.
/// A failed write (full disk, file size limit, ...) leaves neither `path` changed nor the
/// temporary file. Exceptions thrown by `fill` remove the temporary and pass through.
/// @throw OutputError naming `path` when creating, writing, closing or renaming fails
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& fill);

/// write_file_atomically with a ready text. @throw OutputError
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace papersim::common
