#include "validation/study_table.hpp"

#include <cstdio>
#include <utility>

#include "common/atomic_file.hpp"
#include "common/errors.hpp"

namespace papersim::validation {

StudyTable::StudyTable(std::string path, const std::string& header) : path_(std::move(path)) {
  if (path_.empty()) return;
  text_ = header + '\n';
  common::write_text_atomically(path_, text_);
}

void StudyTable::add(const std::string& row) {
  if (path_.empty()) return;
  text_ += row;
  text_ += '\n';
  common::write_text_atomically(path_, text_);
}

int run_study(const char* program, int (*study)(int, char**), int argc, char** argv) {
  try {
    return study(argc, argv);
  } catch (const common::OutputError& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return 5;
  }
}

}  // namespace papersim::validation
