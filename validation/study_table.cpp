#include "validation/study_table.hpp"

#include <cstdio>
#include <utility>

#include "common/atomic_file.hpp"
#include "common/errors.hpp"

namespace papersim::validation {

StudyTable::StudyTable(std::string path, const std::string& header) : m_path(std::move(path)) {
  if (m_path.empty()) return;
  m_text = header + '\n';
  common::write_text_atomically(m_path, m_text);
}

void StudyTable::add(const std::string& row) {
  if (m_path.empty()) return;
  m_text += row;
  m_text += '\n';
  common::write_text_atomically(m_path, m_text);
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
