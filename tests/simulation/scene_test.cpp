// Scene files: errors name the key, the JSON round trip is exact, and runs leave no partial
// output.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"
#include "simulation/scene.hpp"
#include "simulation/simulate.hpp"

using namespace papersim::simulation;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string error_of(const json& j) {
  try {
    scene_from_json(j, "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

/// A small, quick scene: a 6 x 6 cm sheet falling 2 mm onto the ground.
RunOptions options_for(const std::string& out_dir) {
  RunOptions o;
  o.out_dir = out_dir;
  return o;
}

Scene small_scene() {
  Scene s;
  s.sheet.width = s.sheet.height = 0.06;
  s.sheet.edge_length = 0.01;
  s.sheet.position = Eigen::Vector3d(0, 0, 2e-3);
  s.duration = 0.02;
  s.time_step = 0.01;
  return s;
}

}  // namespace

TEST(Scene, ErrorsNameTheFileAndTheKey) {
  EXPECT_EQ(error_of({{"sheet", {{"materal", json::object()}}}}), "s.json: key 'sheet.materal': unknown key");
  EXPECT_NE(error_of({{"sheet", {{"material", {{"poisson", 0.7}}}}}}).find("'sheet.material.poisson'"),
            std::string::npos);
  EXPECT_NE(error_of({{"duration", "long"}}).find("'duration': expected a number"), std::string::npos);
  EXPECT_NE(error_of({{"handles", {{{"point", {0.5, 0.1}}}}}}).find("'handles[0].point'"),
            std::string::npos);
  EXPECT_NE(error_of({{"obstacles", {{{"kind", "cone"}}}}}).find("'obstacles[0].kind'"),
            std::string::npos);
  EXPECT_NE(error_of({{"time_step", 2.0}}).find("'time_step'"), std::string::npos);
  EXPECT_THROW(load_scene("/nonexistent/scene.json"), SceneError);
  EXPECT_NE(error_of({{"self_contact", {{"friction", -0.1}}}}).find("'self_contact.friction'"), std::string::npos);
  EXPECT_EQ(error_of({{"self_contact", {{"thicknes", 1e-3}}}}), "s.json: key 'self_contact.thicknes': unknown key");
  EXPECT_NE(error_of({{"self_contact", {{"enabled", 1}}}}).find("'self_contact.enabled': expected true or false"),
            std::string::npos);
}

TEST(Scene, SelfContactDefaultsAndKeys) {
  const Scene d = scene_from_json(json::object(), "s.json");
  EXPECT_TRUE(d.self_contact.enabled);
  EXPECT_EQ(d.self_contact.friction, 0.6);
  EXPECT_EQ(d.self_contact.dhat, 0.0) << "0 = the obstacle contact thickness";
  const Scene s = scene_from_json({{"self_contact", {{"enabled", false}, {"thickness", 2e-4}, {"friction", 0.4}}}}, "s.json");
  EXPECT_FALSE(s.self_contact.enabled);
  EXPECT_EQ(s.self_contact.dhat, 2e-4);
  EXPECT_EQ(s.self_contact.friction, 0.4);
}

TEST(Scene, JsonRoundTripIsExact) {
  Scene s = make_scenario("pull", 3);
  papersim::collision::ColliderSpec c;
  c.kind = papersim::collision::ColliderKind::sphere;
  c.radius = 0.02;
  c.keyframes = {{0.0, Eigen::Vector3d(0, 0, 0.1), Eigen::Quaterniond::Identity()}};
  s.obstacles.push_back(c);
  s.self_contact.dhat = 2.5e-4;
  s.self_contact.friction = 0.45;
  const json once = scene_to_json(s);
  const json twice = scene_to_json(scene_from_json(once, "round trip"));
  EXPECT_EQ(once, twice);
}

TEST(Scenario, SameSeedSameSceneDifferentSeedDifferentScene) {
  EXPECT_EQ(scene_to_json(make_scenario("pull", 5)), scene_to_json(make_scenario("pull", 5)));
  EXPECT_NE(scene_to_json(make_scenario("pull", 5)), scene_to_json(make_scenario("pull", 6)));
  EXPECT_THROW(make_scenario("no-such-scenario", 1), SceneError);
  // Draws within SCENARIOS.md's ranges.
  for (int seed = 0; seed < 50; ++seed) {
    const Scene s = make_scenario("pull", seed);
    EXPECT_GE(s.gravity.z(), -100);
    EXPECT_LE(s.gravity.z(), -9.8);
    EXPECT_TRUE(s.handles.size() == 1 || s.handles.size() == 2);
    for (const auto& h : s.handles) {
      const double lift = h.keyframes.back().displacement.z();
      EXPECT_GE(lift, 0.03);
      EXPECT_LE(lift, 0.08);
    }
    if (s.handles.size() == 2) {  // reachable by an inextensible sheet
      const double r = (s.handles[0].material_point - s.handles[1].material_point).norm();
      const double dz = s.handles[0].keyframes.back().displacement.z() -
                        s.handles[1].keyframes.back().displacement.z();
      EXPECT_LE(std::abs(dz), 0.8 * r) << "seed " << seed;
    }
  }
}

TEST(Run, WritesOutputsAndLeavesNothingOnFailure) {
  const fs::path dir = fs::temp_directory_path() / ("papersim_run_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const RunResult r = run_scene(small_scene(), options_for(dir.string()));
  EXPECT_TRUE(fs::exists(dir / "sheet.obj") && fs::exists(dir / "sheet.ply") && fs::exists(dir / "meta.json"));
  EXPECT_FALSE(fs::exists(dir / ".papersim-partial"));
  EXPECT_LE(r.meta["quality"]["max_principal_stretch"].get<double>(), 1.005);
  EXPECT_GT(r.meta["quality"]["min_obstacle_distance"][0].get<double>(), 0.0);
  EXPECT_EQ(r.meta["quality"]["self_intersections"].get<int>(), 0);
  EXPECT_EQ(r.meta["run"]["self_contact"]["max_active_pairs"].get<int>(), 0) << "a flat sheet is far from itself";
  EXPECT_GE(r.meta["run"]["self_contact"]["seconds"].get<double>(), 0.0);
  fs::remove_all(dir);
  // A step that cannot converge (one Newton iteration, no halving) fails: no folder is left.
  Scene failing = small_scene();
  failing.newton.max_iterations = 1;
  failing.newton.max_halvings = 0;
  failing.newton.tolerance = 1e-30;
  EXPECT_THROW(run_scene(failing, options_for(dir.string())), NumericError);
  EXPECT_FALSE(fs::exists(dir));
}
