#include "validation/study_table.hpp"

#include <utility>

#include "common/atomic_file.hpp"

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

}  // namespace papersim::validation
