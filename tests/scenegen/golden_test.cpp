// Golden-file tests of the generated POV-Ray text. Regenerate after an intended change with
// SCENEGEN_UPDATE_GOLDEN=1 ./scenegen_tests --gtest_filter='Golden*' and review the diff.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "scenegen/camera.hpp"
#include "scenegen/document.hpp"
#include "scenegen/errors.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/geometry.hpp"
#include "scenegen/pov_writer.hpp"
#include "scenegen/resting_pose.hpp"
#include "scenegen/scene_draw.hpp"

namespace papersim::scenegen {
namespace {

void expect_golden(const std::string& name, const std::string& text) {
  const std::string path = std::string(SCENEGEN_TEST_DATA_DIR) + "/golden/" + name;
  if (std::getenv("SCENEGEN_UPDATE_GOLDEN")) {
    std::ofstream(path) << text;
    return;
  }
  std::ifstream in(path);
  ASSERT_TRUE(in) << "missing golden file " << path;
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), text) << "generated text differs from " << path;
}

SceneDescription fold_scene(Quality q) {
  const SheetMesh mesh = make_example_sheet("fold");
  SceneDescription s;
  s.stage = find_resting_pose(mesh);
  Rng cam(7, "camera"), light(7, "lighting"), bg(7, "background"), paper(7, "paper");
  s.camera = choose_camera(mesh, s.stage, 128, 180, CameraParams{}, cam).camera;
  s.lighting = draw_lighting(light, s.stage, s.stage.centre_of_mass);
  s.background = draw_background(bg, {});
  s.paper = draw_paper(paper);
  s.quality = quality_settings(q);
  set_coords_encoding(s, mesh);
  return s;
}

TEST(Golden, SheetMesh2) {
  ExampleSheetParams p;
  p.nx = 3;
  p.ny = 3;
  const SheetMesh m = make_example_sheet("cylinder", p);
  std::ostringstream out;
  write_sheet_inc(out, m, vertex_normals(m));
  expect_golden("sheet.inc", out.str());
}

TEST(Golden, SceneIncludeDraft) {
  std::ostringstream out;
  write_scene_inc(out, fold_scene(Quality::draft));
  expect_golden("scene_draft.inc", out.str());
}

TEST(Golden, SceneIncludeFinal) {
  std::ostringstream out;
  SceneDescription s = fold_scene(Quality::final);
  s.contact.enabled = true;  // the contact shadow's declarations (draft: SG_Contact = 0)
  s.contact.x0 = -0.14;
  s.contact.y0 = -0.19;
  s.contact.width = 0.26;
  s.contact.height = 0.378;
  s.contact.strength = 0.29;
  write_scene_inc(out, s);
  expect_golden("scene_final.inc", out.str());
}

TEST(Quality, BestIsFinalWithThreeByThreeAreaLightsAndNamesRoundTrip) {
  const QualitySettings f = quality_settings(Quality::final), b = quality_settings(Quality::best);
  EXPECT_EQ(f.area_samples, 2);
  EXPECT_TRUE(f.area_jitter);
  EXPECT_EQ(b.area_samples, 3);
  EXPECT_EQ(b.area_adaptive, 0);
  EXPECT_TRUE(b.area_jitter);
  // Everything else is the final preset's.
  QualitySettings rest = b;
  rest.area_samples = f.area_samples;
  rest.area_adaptive = f.area_adaptive;
  rest.area_jitter = f.area_jitter;
  std::ostringstream x, y;
  write_pass_ini(x, RawPass::image, 64, 90, rest, 0);
  write_pass_ini(y, RawPass::image, 64, 90, f, 0);
  EXPECT_EQ(x.str(), y.str());
  EXPECT_EQ(rest.radiosity_nearest, f.radiosity_nearest);
  EXPECT_EQ(rest.bands, f.bands);
  EXPECT_EQ(rest.ambient, f.ambient);
  for (Quality q : {Quality::draft, Quality::final, Quality::best})
    EXPECT_EQ(parse_quality(quality_name(q)), q);
  try {
    parse_quality("fine");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'fine'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("best"), std::string::npos) << e.what();
  }
  std::ostringstream inc;
  write_scene_inc(inc, fold_scene(Quality::best));
  EXPECT_NE(inc.str().find("#declare SG_Area_Samples = 3;"), std::string::npos);
  EXPECT_NE(inc.str().find("#declare SG_Area_Adaptive = 0;"), std::string::npos);
  EXPECT_NE(inc.str().find("#declare SG_Area_Jitter = 1;"), std::string::npos);
}

TEST(Golden, PassInis) {
  std::ostringstream out;
  write_pass_ini(out, RawPass::uv, 1024, 1440, quality_settings(Quality::final), 2);
  write_pass_ini(out, RawPass::image, 1024, 1440, quality_settings(Quality::final), 0);
  write_pass_ini(out, RawPass::image, 1024, 1440, quality_settings(Quality::final), 1,
                 RowBand{1, 3});
  write_pass_ini(out, RawPass::shading, 1024, 1440, quality_settings(Quality::draft), 0);
  write_document_ini(out, 1240, 1754, 0);
  expect_golden("passes.ini", out.str());
}

TEST(Golden, DocumentPage) {
  std::ostringstream out;
  write_document_pov(out, generate_document(5, DocumentParams{}));
  expect_golden("document.pov", out.str());
}

TEST(Document, SameSeedSamePageDifferentSeedDifferentPage) {
  std::ostringstream a, b, c;
  write_document_pov(a, generate_document(11, DocumentParams{}));
  write_document_pov(b, generate_document(11, DocumentParams{}));
  write_document_pov(c, generate_document(12, DocumentParams{}));
  EXPECT_EQ(a.str(), b.str());
  EXPECT_NE(a.str(), c.str());
  const DocumentLayout d = generate_document(11, DocumentParams{});
  EXPECT_GT(d.paragraphs, 0);
  EXPECT_GT(d.headings, 0);
  EXPECT_FALSE(d.figure_kind.empty());
}

}  // namespace
}  // namespace papersim::scenegen
