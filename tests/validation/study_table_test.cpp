#include "validation/study_table.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "common/errors.hpp"

namespace fs = std::filesystem;
namespace pv = papersim::validation;

namespace {

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

}  // namespace

// The file holds the header from the start and every row after each add, complete, with no
// temporary left beside it.
TEST(StudyTable, HoldsTheHeaderAndEveryFinishedRow) {
  const fs::path dir = fresh_dir("papersim_study_table");
  const fs::path csv = dir / "t.csv";
  pv::StudyTable table(csv.string(), "seed,verdict");
  EXPECT_TRUE(table.enabled());
  EXPECT_EQ(read(csv), "seed,verdict\n");
  table.add("0,PASS");
  EXPECT_EQ(read(csv), "seed,verdict\n0,PASS\n");
  table.add("1,FAIL nan");
  EXPECT_EQ(read(csv), "seed,verdict\n0,PASS\n1,FAIL nan\n");
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
  fs::remove_all(dir);
}

// A path that cannot be written fails at once, before any row, naming the file; an empty path
// writes nothing.
TEST(StudyTable, NamesAnUnwritablePathBeforeAnyRow) {
  const fs::path dir = fresh_dir("papersim_study_table_bad");
  const std::string bad = (dir / "missing" / "t.csv").string();
  try {
    pv::StudyTable table(bad, "seed");
    FAIL() << "no error for " << bad;
  } catch (const papersim::common::OutputError& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
  pv::StudyTable none("", "seed");
  EXPECT_FALSE(none.enabled());
  none.add("0");
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}
