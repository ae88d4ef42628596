#pragma once
/// A study program's CSV table (--csv), kept complete on disk while the study runs.
#include <string>

namespace papersim::validation {

/// The CSV table of a study over seeds or cases. The file is rewritten through a temporary name
/// (common::write_text_atomically) at the start, with the header alone, and after every row, so
/// at any moment it holds the header and every row finished so far, complete: a study stopped
/// halfway keeps its finished rows, and a failed write leaves the last complete table, never a
/// partial line. Writing the header at the start makes a path that cannot be written fail before
/// the first run, not after hours of them. With an empty path nothing is written.
class StudyTable {
 public:
  /// @throw common::OutputError naming `path` when it cannot be written
  StudyTable(std::string path, const std::string& header);

  /// Append one row (its cells joined by commas, no newline) and rewrite the file.
  /// @throw common::OutputError naming the path when it cannot be written
  void add(const std::string& row);

  bool enabled() const { return !m_path.empty(); }

 private:
  std::string m_path;
  std::string m_text;
};

/// The main of a study program: `study(argc, argv)`, with a table that cannot be written
/// (common::OutputError) turned into a message prefixed by `program` and exit status 5.
int run_study(const char* program, int (*study)(int, char**), int argc, char** argv);

}  // namespace papersim::validation
