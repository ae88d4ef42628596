// --flip and --views: the flipped sample sees the sheet's other side at the mirrored material
// point; K views of one mesh differ in every draw and share the document page.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "scenegen/edge_lift.hpp"
#include "scenegen/geometry.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/job.hpp"
#include "scenegen/meta.hpp"
#include "scenegen/random.hpp"
#include "scenegen/smooth_surface.hpp"
#include "test_support.hpp"

namespace papersim::scenegen {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

using test::read_json;

TEST(Views, FlippedUvIsTheMirrorAtTheSameMaterialPoint) {
  test::TempDir dir("flip");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "bump", "bump.obj");
  o.seed = 5;
  o.width = 96;
  o.height = 136;
  o.quality = Quality::draft;
  o.passes = {Pass::uv, Pass::coords};
  o.flip = true;
  o.fine_passes = false;  // 16-bit UV and coords: ~5e-6 m here, well inside the tolerance
  o.document_dpi = 30;
  render_sample(o, dir.str("flipped"), RunOptions{});
  const json meta = read_json(dir.path() / "flipped" / "meta.json");
  EXPECT_TRUE(meta["flip"].get<bool>());
  SurfaceParams sp;
  sp.level = meta["surface"]["level"];
  // The unflipped rendered surface: material point (1 - u', v') there is the mirror image
  // (x -> -x) of the point the flipped render sees with UV (u', v').
  // The flipped sample was lifted above its table plane; that plane mirrored back (x -> -x).
  const json& st = meta["stage"];
  const Eigen::Vector3d origin(-st["origin"][0].get<double>(), st["origin"][1], st["origin"][2]);
  const Eigen::Vector3d up(-st["up"][0].get<double>(), st["up"][1], st["up"][2]);
  const SheetMesh original = rendered_surface(read_sheet_obj(o.mesh_path), origin, up, sp,
                                              edge_lift_from_json(meta["surface"]))
                                 .surface;
  const UvLocator loc(original);
  const ImageF uv = read_exr((dir.path() / "flipped" / "uv.exr").string(), {"R", "G", "B"});
  const ImageF xyz = read_exr((dir.path() / "flipped" / "coords.exr").string(), {"R", "G", "B"});
  std::vector<std::pair<int, int>> px;
  for (int y = 0; y < uv.height; ++y)
    for (int x = 0; x < uv.width; ++x)
      if (uv.at(x, y, 2) > 0.5f) px.emplace_back(x, y);
  ASSERT_GT(px.size(), 2000u);
  Rng rng(11);
  double worst = 0;
  for (int i = 0; i < 500; ++i) {
    const auto [x, y] =
        px[static_cast<std::size_t>(rng.randint(0, static_cast<int>(px.size()) - 1))];
    const auto p = loc.world_point({1.0 - uv.at(x, y, 0), uv.at(x, y, 1)});
    ASSERT_TRUE(p);
    const Eigen::Vector3d mirrored(-xyz.at(x, y, 0), xyz.at(x, y, 1), xyz.at(x, y, 2));
    worst = std::max(worst, (*p - mirrored).norm());
  }
  std::cout << "[flip] 500 mask pixels: max |mirror(coords) - original(1 - u, v)| = " << worst
            << " m\n";
  EXPECT_LT(worst, 1e-4);
}

TEST(Views, KViewsDifferInEveryDrawAndShareThePage) {
  test::TempDir dir("views");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "cylinder", "cylinder.obj");
  o.seed = 2;
  o.width = 64;
  o.height = 90;
  o.quality = Quality::draft;
  o.passes = {Pass::mask};
  o.document_dpi = 30;
  const int k = 3;
  render_views(o, k, dir.str("views"), RunOptions{});
  std::vector<json> m;
  for (int v = 0; v < k; ++v) {
    const fs::path d = dir.path() / "views" / ("view_0" + std::to_string(v));
    ASSERT_TRUE(fs::exists(d / "mask.png")) << d;
    m.push_back(read_json(d / "meta.json"));
    EXPECT_EQ(m.back()["view"], v);
  }
  for (int a = 0; a < k; ++a)
    for (int b = a + 1; b < k; ++b) {
      EXPECT_NE(m[a]["camera"]["roll_deg"], m[b]["camera"]["roll_deg"]);
      EXPECT_NE(m[a]["lighting"]["rotation_deg"], m[b]["lighting"]["rotation_deg"]);
      EXPECT_NE(m[a]["lighting"]["exposure"], m[b]["lighting"]["exposure"]);
      EXPECT_NE(m[a]["background"]["noise_seed"], m[b]["background"]["noise_seed"]);
      EXPECT_NE(m[a]["paper"]["grain_seed"], m[b]["paper"]["grain_seed"]);
      EXPECT_NE(m[a]["paper"]["colour"], m[b]["paper"]["colour"]);
      EXPECT_EQ(m[a]["document"], m[b]["document"]);  // one page for every view
    }
}

}  // namespace
}  // namespace papersim::scenegen
