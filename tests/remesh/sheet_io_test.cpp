#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "remesh/errors.hpp"
#include "remesh/sheet_generator.hpp"
#include "remesh/sheet_io.hpp"

using namespace papersim::remesh;
namespace fs = std::filesystem;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("papersim_io_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(reinterpret_cast<uintptr_t>(this)));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

SheetData sample_sheet() {
  RectangleOptions o;
  o.nx = 6;
  o.ny = 8;
  o.jitter = 0.2;
  SheetData d;
  d.mesh = make_rectangle(o);
  d.width = o.width;
  d.height = o.height;
  const Eigen::MatrixX2d X = d.mesh.material_coords();
  d.positions.resize(X.rows(), 3);
  for (int v = 0; v < X.rows(); ++v)
    d.positions.row(v) << X(v, 0) - 0.1, X(v, 1) - 0.15, 0.01 * std::sin(20 * X(v, 0));
  d.velocities = Eigen::MatrixX3d::Random(X.rows(), 3);
  Eigen::MatrixX3d k = Eigen::MatrixX3d::Random(d.mesh.num_faces(), 3);
  d.mesh.set_plastic_curvature(k);
  d.mesh.set_damage(Eigen::VectorXd::LinSpaced(d.mesh.num_faces(), 0, 1));
  return d;
}

}  // namespace

TEST(SheetIo, ObjRoundTripKeepsMaterialCoordinates) {
  TempDir dir;
  const SheetData d = sample_sheet();
  const std::string path = (dir.path / "sheet.obj").string();
  write_sheet_file(path, d.mesh, d.positions, d.velocities, d.width, d.height);
  const SheetData r = read_sheet(path);
  EXPECT_DOUBLE_EQ(r.width, d.width);
  EXPECT_LT((r.mesh.material_coords() - d.mesh.material_coords()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((r.positions - d.positions).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(r.mesh.faces(), d.mesh.faces());
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST(SheetIo, PlyRoundTripKeepsEveryField) {
  TempDir dir;
  const SheetData d = sample_sheet();
  const std::string path = (dir.path / "sheet.ply").string();
  write_sheet_file(path, d.mesh, d.positions, d.velocities, d.width, d.height);
  const SheetData r = read_sheet(path);
  EXPECT_EQ(r.positions, d.positions);
  EXPECT_EQ(r.velocities, d.velocities);
  EXPECT_EQ(r.mesh.material_coords(), d.mesh.material_coords());
  EXPECT_EQ(r.mesh.plastic_curvature(), d.mesh.plastic_curvature());
  EXPECT_EQ(r.mesh.damage(), d.mesh.damage());
  EXPECT_DOUBLE_EQ(r.height, d.height);
}

TEST(SheetIo, ObjWithoutHeaderFitsTheMaterialScale) {
  TempDir dir;
  const SheetData d = sample_sheet();
  std::ostringstream s;
  write_obj(s, d.mesh, d.positions, d.width, d.height);
  std::string text = s.str();
  text = text.substr(text.find('\n') + 1);  // drop the header
  const std::string path = (dir.path / "foreign.obj").string();
  std::ofstream(path) << text;
  const SheetData r = read_sheet(path);
  // The sample is only mildly curved (chords shorten by < 1%), so the fit is close.
  EXPECT_NEAR(r.width, d.width, 0.01 * d.width);
  EXPECT_NEAR(r.height, d.height, 0.01 * d.height);
}

TEST(SheetIo, ReportsBadFiles) {
  TempDir dir;
  EXPECT_THROW(read_sheet((dir.path / "missing.obj").string()), IoError);
  const std::string novt = (dir.path / "novt.obj").string();
  std::ofstream(novt) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  EXPECT_THROW(read_sheet(novt), IoError);
  const std::string nan = (dir.path / "nan.obj").string();
  std::ofstream(nan) << "v 0 0 nan\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
  EXPECT_THROW(read_sheet(nan), MeshError);
  const std::string degenerate = (dir.path / "deg.obj").string();
  std::ofstream(degenerate) << "v 0 0 0\nv 1 0 0\nv 2 0 0\nvt 0 0\nvt 0.5 0\nvt 1 0\nf 1/1 2/2 3/3\n";
  EXPECT_THROW(read_sheet(degenerate), MeshError);
  try {
    read_sheet(degenerate);
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("deg.obj"), std::string::npos) << "names the file";
  }
}
