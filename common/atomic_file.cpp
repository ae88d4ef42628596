#include "common/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

namespace papersim::common {

namespace fs = std::filesystem;

namespace {

/// The reason of the last failed system call, or a generic one when errno says nothing.
std::string reason(int error) {
  return error != 0 ? std::string(std::strerror(error)) : std::string("write failed");
}

void remove_quietly(const fs::path& p) {
  std::error_code ec;
  fs::remove(p, ec);
}

}  // namespace

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& fill) {
  const fs::path tmp = path.string() + ".tmp";
  std::ofstream out;
  errno = 0;
  out.open(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw OutputError("cannot create '" + tmp.string() + "': " + reason(errno));
  try {
    fill(out);
  } catch (...) {
    out.close();
    remove_quietly(tmp);
    throw;
  }
  errno = 0;
  out.flush();
  out.close();  // writes what the buffer still holds: a full disk shows here at the latest
  if (out.fail()) {
    const int error = errno;
    remove_quietly(tmp);
    throw OutputError("cannot write '" + path.string() + "': " + reason(error));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    remove_quietly(tmp);
    throw OutputError("cannot rename '" + tmp.string() + "' to '" + path.string() +
                      "': " + ec.message());
  }
}

void write_text_atomically(const fs::path& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace papersim::common
