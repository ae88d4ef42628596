#include "remesh/sheet_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/errors.hpp"
#include "remesh/errors.hpp"
#include "remesh/sheet_generator.hpp"

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
  std::ofstream(degenerate)
      << "v 0 0 0\nv 1 0 0\nv 2 0 0\nvt 0 0\nvt 0.5 0\nvt 1 0\nf 1/1 2/2 3/3\n";
  EXPECT_THROW(read_sheet(degenerate), MeshError);
  try {
    read_sheet(degenerate);
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("deg.obj"), std::string::npos) << "names the file";
  }
}

TEST(SheetIo, BadObjInputNamesFileLineAndLimit) {
  const std::string head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n";
  const auto error_of = [](const std::string& text) {
    std::istringstream in(text);
    try {
      parse_sheet(in, "m.obj", SheetFormat::obj);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error_of(head + "f 1/1 x/2 3/3\n"), "m.obj:7: bad face index 'x'");
  EXPECT_EQ(error_of(head + "f 1/1 99999999999999999999/2 3/3\n"),
            "m.obj:7: bad face index '99999999999999999999'");
  EXPECT_EQ(error_of(head + "f 1/1 0/2 3/3\n"), "m.obj:7: face index 0 out of range");
  // Half the faces cut off: a vertex is then used by none.
  EXPECT_EQ(
      error_of(
          "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nf 1/1 2/2 3/3\n"),
      "m.obj: vertex 4 is used by no face (a truncated file?)");
  EXPECT_EQ(error_of("v 1e200 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n"),
            "m.obj: a vertex coordinate exceeds the limit of 1e6 m");
  EXPECT_EQ(error_of("# papersim sheet 1e300 1\n" + head + "f 1/1 2/2 3/3\n"),
            "m.obj:1: sheet size must be in (0, 1000000] m");
}

TEST(SheetIo, BadPlyHeadersAreErrorsNotAllocations) {
  const auto error_of = [](const std::string& text) {
    std::istringstream in(text, std::ios::binary);
    try {
      parse_sheet(in, "m.ply", SheetFormat::ply);
    } catch (const IoError& e) {
      return std::string(e.what());
    } catch (const MeshError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of("ply\nformat ascii 1.0\nelement vertex -5\nend_header\n"),
            "m.ply: malformed element line: element vertex -5");
  EXPECT_EQ(error_of("ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n"),
            "m.ply: element vertex has 99999999999 entries, more than the limit of 500000");
  EXPECT_EQ(error_of("ply\nformat ascii 1.0\nelement vertex 3\n"),
            "m.ply: no end_header (not a PLY file or truncated)");
  EXPECT_EQ(
      error_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
               "property double z\nproperty double mx\nproperty double my\nelement face 1\n"
               "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n3 0 -1 7\n"),
      "m.ply: bad vertex index in element face");
}

TEST(SheetIo, WriteSheetFileIsAtomic) {
  TempDir dir;
  const SheetData s = sample_sheet();
  const std::string path = (dir.path / "s.obj").string();
  write_sheet_file(path, s.mesh, s.positions, s.velocities, s.width, s.height);
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  EXPECT_THROW(write_sheet_file((dir.path / "missing" / "s.obj").string(), s.mesh, s.positions,
                                s.velocities, s.width, s.height),
               papersim::common::OutputError);
}
