#include <gtest/gtest.h>

#include <sstream>

#include "scenegen/errors.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/limits.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {
namespace {

TEST(SheetObj, ParsesHeaderUvAndFaces) {
  std::istringstream in(
      "# papersim sheet 0.2 0.3\nv 0 0 0\nv 0.2 0 0\nv 0 0.3 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 "
      "3/3\n");
  const SheetMesh m = parse_sheet_obj(in, "test");
  EXPECT_EQ(m.num_vertices(), 3);
  EXPECT_EQ(m.num_faces(), 1);
  EXPECT_TRUE(m.size_from_header);
  EXPECT_DOUBLE_EQ(m.width, 0.2);
  EXPECT_DOUBLE_EQ(m.height, 0.3);
  EXPECT_DOUBLE_EQ(m.uv(1, 0), 1.0);
}

TEST(SheetObj, OrientsFacesByUvAndFitsSizeWithoutHeader) {
  // Clockwise in UV: flipped to positive UV area; size fitted to edge lengths.
  std::istringstream in("v 0 0 0\nv 0.2 0 0\nv 0 0.3 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 3/3 2/2\n");
  const SheetMesh m = parse_sheet_obj(in, "test");
  EXPECT_EQ(m.faces(0, 1), 1);
  EXPECT_FALSE(m.size_from_header);
  EXPECT_NEAR(m.width, 0.2, 1e-12);
  EXPECT_NEAR(m.height, 0.3, 1e-12);
}

TEST(SheetObj, RejectsMeshWithoutVt) {
  std::istringstream in("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  try {
    parse_sheet_obj(in, "novt.obj");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no texture coordinates"), std::string::npos) << e.what();
  }
}

TEST(SheetObj, RejectsTwoUvsOnOneVertexAndBadIndices) {
  std::istringstream seam(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\n"
      "f 1/1 2/2 3/3\nf 1/4 2/2 3/3\n");
  EXPECT_THROW(parse_sheet_obj(seam, "seam"), InputError);
  std::istringstream bad("v 0 0 0\nvt 0 0\nf 1/1 2/1 3/1\n");
  EXPECT_THROW(parse_sheet_obj(bad, "bad"), InputError);
  std::istringstream outside(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1.5 0\nvt 0 1\nf 1/1 2/2 3/3\n");
  EXPECT_THROW(parse_sheet_obj(outside, "outside"), InputError);
}

TEST(SheetObj, MissingFileIsIoError) {
  EXPECT_THROW(read_sheet_obj("/nonexistent/sheet.obj"), IoError);
}

TEST(SheetObj, WriteReadRoundTripIsExact) {
  const SheetMesh a = make_example_sheet("cylinder");
  std::stringstream s;
  write_sheet_obj(s, a);
  const SheetMesh b = parse_sheet_obj(s, "roundtrip");
  EXPECT_EQ((a.positions - b.positions).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((a.uv - b.uv).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a.width, b.width);
}

TEST(SheetObj, RejectsTruncatedFilesAndInputBeyondTheLimits) {
  const auto error_of = [](const std::string& text) {
    std::istringstream in(text);
    try {
      parse_sheet_obj(in, "m.obj");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Half the faces cut off: vertex 4 is used by no face (it used to get UV (0.5, 0.5)).
  EXPECT_EQ(error_of("# papersim sheet 0.2 0.3\nv 0 0 0\nv 0.2 0 0\nv 0 0.3 0\nv 0.2 0.3 0\n"
                     "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nf 1/1 2/2 3/3\n"),
            "m.obj: vertex 4 is used by no face (a truncated file?)");
  // 1e200 crashed the camera search (issue 17).
  EXPECT_EQ(error_of("# papersim sheet 0.2 0.3\nv 1e200 0 0\nv 0.2 0 0\nv 0 0.3 0\n"
                     "vt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n"),
            "m.obj: a vertex coordinate exceeds the limit of 1000 m");
  EXPECT_EQ(error_of("# papersim sheet 1e5 0.3\nv 0 0 0\n"),
            "m.obj:1: sheet size outside the limits [1e-4, 1000] m");
  std::string many = "# papersim sheet 0.2 0.3\n";
  for (long i = 0; i <= MAX_MESH_VERTICES; ++i) many += "v 0 0 0\n";
  EXPECT_EQ(error_of(many), "m.obj:250002: more than 250000 vertices (the limit)");
}

}  // namespace
}  // namespace papersim::scenegen
