// The folders' dependencies flow one way (DESIGN.md, "Layout"): collision and remesh are
// independent of each other and of simulation, simulation uses both, scenegen uses neither,
// validation may use everything. common (files, exit statuses, the invariant check) and batch
// (the dataset runner) sit below the libraries that use them. The programs' entry files are
// built after every library and may use any. OpenVDB and CGAL are included only by the .cpp
// files that need them, never by a header.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// The folders each library folder may include from.
const std::map<std::string, std::set<std::string>>& allowed() {
  static const std::map<std::string, std::set<std::string>> a = {
      {"common", {"common"}},
      {"batch", {"batch", "common"}},
      {"collision", {"collision", "common"}},
      {"remesh", {"remesh", "common"}},
      {"simulation", {"simulation", "collision", "remesh", "batch", "common"}},
      {"scenegen", {"scenegen", "batch", "common"}},
  };
  return a;
}

/// Files built after every library (a program's main), which may include any folder.
const std::set<std::string> PROGRAMS = {"simulation/papersim_main.cpp"};

/// Every include under `root` that breaks the rules, as "file:line: what".
std::vector<std::string> violations(const fs::path& root) {
  std::vector<std::string> found;
  const std::regex project_include(R"(^\s*#\s*include\s*"([a-z_]+)/)");
  const std::regex heavy_include(R"(^\s*#\s*include\s*<(openvdb|CGAL)/)");
  for (const auto& [folder, may] : allowed()) {
    if (!fs::is_directory(root / folder)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root / folder)) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
      const std::string rel = fs::relative(entry.path(), root).generic_string();
      std::ifstream in(entry.path());
      std::string line;
      for (int n = 1; std::getline(in, line); ++n) {
        std::smatch m;
        if (std::regex_search(line, m, project_include) && !may.count(m[1]) &&
            !PROGRAMS.count(rel) && fs::is_directory(root / m[1].str()))
          found.push_back(rel + ":" + std::to_string(n) + ": " + folder + " includes " +
                          m[1].str() + "/");
        if (ext == ".hpp" && std::regex_search(line, m, heavy_include))
          found.push_back(rel + ":" + std::to_string(n) + ": a header includes " + m[1].str() +
                          "/");
      }
    }
  }
  return found;
}

}  // namespace

TEST(Layering, EveryIncludeFollowsTheFoldersDependencies) {
  const fs::path root = PAPERSIM_SOURCE_DIR;
  ASSERT_TRUE(fs::is_directory(root / "simulation")) << root;
  std::size_t files = 0;
  for (const auto& [folder, may] : allowed())
    for (const auto& e : fs::recursive_directory_iterator(root / folder))
      files += e.is_regular_file();
  EXPECT_GT(files, 100u) << "the source tree was not found whole";
  const auto found = violations(root);
  for (const auto& v : found) ADD_FAILURE() << v;
  EXPECT_TRUE(found.empty());
}

// The check finds what it should: in a small tree, remesh including collision, a header
// including OpenVDB and scenegen including simulation are reported with their lines; the allowed
// includes, a system header and a program's main are not.
TEST(Layering, TheCheckReportsABadIncludeWithItsLine) {
  const fs::path root =
      fs::temp_directory_path() / ("papersim_layering_" + std::to_string(::getpid()));
  fs::remove_all(root);
  for (const char* d : {"common", "remesh", "collision", "simulation", "scenegen"})
    fs::create_directories(root / d);
  std::ofstream(root / "remesh/a.cpp")
      << "#include \"remesh/a.hpp\"\n#include <vector>\n#include \"collision/b.hpp\"\n";
  std::ofstream(root / "collision/b.hpp") << "#pragma once\n#include <openvdb/openvdb.h>\n";
  std::ofstream(root / "collision/b.cpp")
      << "#include <openvdb/openvdb.h>\n#include \"common/x.hpp\"\n";
  std::ofstream(root / "scenegen/c.cpp") << "// x\n\n  #  include \"simulation/run.hpp\"\n";
  std::ofstream(root / "simulation/papersim_main.cpp") << "#include \"scenegen/c.hpp\"\n";
  const auto found = violations(root);
  EXPECT_EQ(std::set<std::string>(found.begin(), found.end()),
            (std::set<std::string>{"remesh/a.cpp:3: remesh includes collision/",
                                   "collision/b.hpp:2: a header includes openvdb/",
                                   "scenegen/c.cpp:3: scenegen includes simulation/"}));
  fs::remove_all(root);
}
