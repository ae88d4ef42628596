// The metrics command: finding meshes in folders, reports, CSV, errors, CLI wiring, plots.
#include "validation/metrics_command.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "remesh/sheet_generator.hpp"
#include "remesh/sheet_io.hpp"
#include "test_meshes.hpp"

namespace papersim::validation {
namespace {

namespace fs = std::filesystem;
using test::PI;

/// A temporary folder with: a/sheet.obj (flat), a/b/sheet.obj (folded 90 deg at x = 0.1),
/// c/sheet.obj and c/sheet.ply (the same folded sheet, with plastic data in the PLY).
class MetricsCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    m_dir = fs::temp_directory_path() /
            ("papersim_metrics_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(m_dir);
    fs::create_directories(m_dir / "a" / "b");
    fs::create_directories(m_dir / "c");
    remesh::RectangleOptions r;
    r.width = 0.2;
    r.height = 0.1;
    r.nx = 21;
    r.ny = 11;
    r.triangulation = remesh::Triangulation::regular;
    m_mesh = remesh::make_rectangle(r);
    const Eigen::MatrixX2d x = m_mesh.material_coords();
    const Eigen::MatrixX3d zero = Eigen::MatrixX3d::Zero(x.rows(), 3);
    const Eigen::MatrixX3d folded = test::folded_positions(x, 0.1, PI / 2);
    write("a/sheet.obj", test::flat_positions(x), zero);
    write("a/b/sheet.obj", folded, zero);
    write("c/sheet.obj", folded, zero);
    write("c/sheet.ply", folded, zero);
  }
  void TearDown() override { fs::remove_all(m_dir); }

  void write(const std::string& name, const Eigen::MatrixX3d& positions,
             const Eigen::MatrixX3d& velocities) {
    remesh::write_sheet_file((m_dir / name).string(), m_mesh, positions, velocities, 0.2, 0.1);
  }
  std::string path(const std::string& name) const { return (m_dir / name).string(); }

  fs::path m_dir;
  remesh::SheetMesh m_mesh;
};

TEST_F(MetricsCommand, FindsMeshesRecursivelyPreferringPly) {
  std::vector<std::string> missing;
  const std::vector<std::string> files =
      find_mesh_files({m_dir.string(), path("nope.obj")}, missing);
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0], path("a/b/sheet.obj"));
  EXPECT_EQ(files[1], path("a/sheet.obj"));
  EXPECT_EQ(files[2], path("c/sheet.ply"));
  ASSERT_EQ(missing.size(), 1u);
}

TEST_F(MetricsCommand, JsonReportHasOneEntryPerMeshAndASummary) {
  MetricsCommandOptions options;
  options.json = true;
  options.threads = 2;
  std::ostringstream out, err;
  ASSERT_EQ(run_metrics_command({m_dir.string()}, options, out, err), 0) << err.str();
  const nlohmann::json report = nlohmann::json::parse(out.str());
  ASSERT_EQ(report["meshes"].size(), 3u);
  const nlohmann::json& folded = report["meshes"][0]["metrics"];
  EXPECT_EQ(folded["creases"]["lines"], 1);
  EXPECT_NEAR(folded["creases"]["total_length"].get<double>(), 0.1, 1e-6);
  EXPECT_EQ(folded["creases"]["has_plastic_data"], false);
  EXPECT_EQ(report["meshes"][2]["metrics"]["creases"]["has_plastic_data"], true);
  EXPECT_EQ(report["summary"]["measured"], 3);
  EXPECT_EQ(report["summary"]["failed"], 0);
  EXPECT_EQ(report["summary"]["fields"]["creases.lines"]["max"], 1.0);
  EXPECT_EQ(report["summary"]["fields"]["creases.lines"]["min"], 0.0);
}

TEST_F(MetricsCommand, TableAndCsv) {
  MetricsCommandOptions options;
  options.csv_path = path("out.csv");
  std::ostringstream out, err;
  ASSERT_EQ(run_metrics_command({path("a"), path("c/sheet.ply")}, options, out, err), 0);
  EXPECT_NE(out.str().find("summary over 3 of 3 meshes"), std::string::npos) << out.str();
  std::ifstream csv(options.csv_path);
  std::string line;
  int lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 4);  // header + 3 meshes

  std::ostringstream single;
  ASSERT_EQ(run_metrics_command({path("a/sheet.obj")}, {}, single, err), 0);
  EXPECT_NE(single.str().find("isometry.edge_strain_max"), std::string::npos);
}

TEST_F(MetricsCommand, ReportsBadFilesAndOptionsButMeasuresTheRest) {
  std::ofstream(path("a/broken.obj")) << "this is not a mesh\n";
  std::ostringstream out, err;
  EXPECT_EQ(run_metrics_command({path("a"), path("missing")}, {}, out, err), 2);
  EXPECT_NE(err.str().find("broken.obj"), std::string::npos);
  EXPECT_NE(err.str().find("missing"), std::string::npos);
  EXPECT_NE(out.str().find("summary over 2 of 3 meshes"), std::string::npos) << out.str();

  MetricsCommandOptions bad;
  bad.crease_angle_deg = 0.0;
  EXPECT_EQ(run_metrics_command({path("a")}, bad, out, err), 2);
  EXPECT_EQ(run_metrics_command({path("missing")}, {}, out, err), 2);
}

TEST_F(MetricsCommand, SubcommandWiring) {
  CLI::App app{"papersim"};
  int code = -1;
  std::ostringstream out, err;
  add_metrics_subcommand(app, code, out, err);
  app.parse("metrics " + path("a/b/sheet.obj") + " --json --crease-angle 95", false);
  EXPECT_EQ(code, 0) << err.str();
  const nlohmann::json report = nlohmann::json::parse(out.str());
  EXPECT_EQ(report["crease_angle_deg"], 95.0);
  EXPECT_EQ(report["meshes"][0]["metrics"]["creases"]["lines"], 0);  // 90 deg < 95 deg
}

// The one test that starts gnuplot (a smoke test: files appear).
TEST_F(MetricsCommand, PlotsWithGnuplot) {
  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) GTEST_SKIP() << "no gnuplot";
  MetricsCommandOptions options;
  options.plots_dir = path("plots");
  std::ostringstream out, err;
  ASSERT_EQ(run_metrics_command({m_dir.string()}, options, out, err), 0) << err.str();
  for (const char* name : {"edge_strain", "principal_stretch", "angle_defect", "crease_length"}) {
    const fs::path svg = m_dir / "plots" / (std::string(name) + ".svg");
    ASSERT_TRUE(fs::exists(svg)) << svg;
    EXPECT_GT(fs::file_size(svg), 1000u) << svg;
  }
}

}  // namespace
}  // namespace papersim::validation
