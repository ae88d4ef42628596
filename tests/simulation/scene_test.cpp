// Scene files: errors name the key, the JSON round trip is exact, and runs leave no partial
// output.
#include "simulation/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "collision/collider_factory.hpp"
#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"
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
  EXPECT_EQ(error_of({{"sheet", {{"materal", json::object()}}}}),
            "s.json: key 'sheet.materal': unknown key");
  EXPECT_NE(
      error_of({{"sheet", {{"material", {{"poisson", 0.7}}}}}}).find("'sheet.material.poisson'"),
      std::string::npos);
  EXPECT_EQ(error_of({{"sheet", {{"material", {{"compression_limit", 0.6}}}}}}),
            "s.json: key 'sheet.material.compression_limit': value 0.6 out of range [0, 0.5]");
  EXPECT_NE(error_of({{"duration", "long"}}).find("'duration': expected a number"),
            std::string::npos);
  EXPECT_NE(error_of({{"handles", {{{"point", {0.5, 0.1}}}}}}).find("'handles[0].point'"),
            std::string::npos);
  EXPECT_NE(error_of({{"obstacles", {{{"kind", "cone"}}}}}).find("'obstacles[0].kind'"),
            std::string::npos);
  EXPECT_NE(error_of({{"time_step", 2.0}}).find("'time_step'"), std::string::npos);
  EXPECT_THROW(load_scene("/nonexistent/scene.json"), SceneError);
  EXPECT_NE(error_of({{"self_contact", {{"friction", -0.1}}}}).find("'self_contact.friction'"),
            std::string::npos);
  EXPECT_EQ(error_of({{"self_contact", {{"thicknes", 1e-3}}}}),
            "s.json: key 'self_contact.thicknes': unknown key");
  EXPECT_NE(error_of({{"self_contact", {{"enabled", 1}}}})
                .find("'self_contact.enabled': expected true or false"),
            std::string::npos);
}

TEST(Scene, SelfContactDefaultsAndKeys) {
  const Scene d = scene_from_json(json::object(), "s.json");
  EXPECT_TRUE(d.self_contact.enabled);
  EXPECT_EQ(d.self_contact.friction, 0.6);
  EXPECT_EQ(d.self_contact.dhat, 0.0) << "0 = the obstacle contact thickness";
  const Scene s = scene_from_json(
      {{"self_contact", {{"enabled", false}, {"thickness", 2e-4}, {"friction", 0.4}}}}, "s.json");
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

// What `papersim scenario` simulates, `papersim run` of the scene.json it wrote simulates to the
// bit (as a batch's samples do): the written text gives back every obstacle pose exactly. Euler
// degrees rarely give a quaternion back to the bit (a fall-gable run then ended 48 Newton
// iterations apart), so a keyframe whose degrees do not also carries `rotation_quaternion`.
TEST(Scene, ScenarioScenesRoundTripToTheBitThroughTheirText) {
  int exact_keys = 0, keys = 0;
  for (const std::string& name : scenario_names())
    for (int seed = 0; seed < 10; ++seed) {
      SCOPED_TRACE(name + " seed " + std::to_string(seed));
      const Scene s = make_scenario(name, seed);
      const json written = scene_to_json(s);
      std::ostringstream text;
      text << std::setw(2) << written << '\n';
      const Scene back = scene_from_json(json::parse(text.str()), "scene.json");
      EXPECT_EQ(scene_to_json(back), written);
      ASSERT_EQ(back.obstacles.size(), s.obstacles.size());
      for (std::size_t o = 0; o < s.obstacles.size(); ++o) {
        ASSERT_EQ(back.obstacles[o].keyframes.size(), s.obstacles[o].keyframes.size());
        for (std::size_t k = 0; k < s.obstacles[o].keyframes.size(); ++k) {
          const auto& a = s.obstacles[o].keyframes[k];
          const auto& b = back.obstacles[o].keyframes[k];
          EXPECT_EQ(a.rotation.coeffs(), b.rotation.coeffs())
              << "obstacle " << o << " keyframe " << k;
          EXPECT_EQ(a.translation, b.translation);
          EXPECT_EQ(a.scale, b.scale);
          EXPECT_EQ(a.time, b.time);
          ++keys;
          exact_keys += written["obstacles"][o]["keyframes"][k].contains("rotation_quaternion");
        }
      }
    }
  EXPECT_GT(exact_keys, 0)
      << "no scenario needed the exact rotation: the check above proves nothing new";
  EXPECT_LT(exact_keys, keys)
      << "identity rotations give their degrees back exactly and need no quaternion";
}

// `rotation_quaternion` is read as [w, x, y, z], must be a unit quaternion and, with
// rotation_deg beside it, the same rotation; errors name the key.
TEST(Scene, RotationQuaternionIsCheckedAgainstItsDegrees) {
  const auto with = [](const json& key) {
    return json{{"obstacles", {{{"kind", "cylinder"}, {"keyframes", {key}}}}}};
  };
  const double c = std::cos(M_PI / 8), sn = std::sin(M_PI / 8);  // 45 degrees about z
  const Scene s = scene_from_json(
      with({{"rotation_deg", {0, 0, 45}}, {"rotation_quaternion", {c, 0, 0, sn}}}), "s.json");
  EXPECT_EQ(s.obstacles[0].keyframes[0].rotation.coeffs(),
            Eigen::Quaterniond(c, 0, 0, sn).coeffs());
  const Scene alone = scene_from_json(with({{"rotation_quaternion", {c, 0, 0, sn}}}), "s.json");
  EXPECT_EQ(alone.obstacles[0].keyframes[0].rotation.coeffs(),
            Eigen::Quaterniond(c, 0, 0, sn).coeffs());
  EXPECT_NE(error_of(with({{"rotation_deg", {0, 0, 50}}, {"rotation_quaternion", {c, 0, 0, sn}}}))
                .find("key 'obstacles[0].keyframes[0].rotation_quaternion': is 5 degrees from "
                      "rotation_deg"),
            std::string::npos)
      << error_of(with({{"rotation_deg", {0, 0, 50}}, {"rotation_quaternion", {c, 0, 0, sn}}}));
  EXPECT_NE(
      error_of(with({{"rotation_quaternion", {1, 0, 0, 0.1}}})).find("expected a unit quaternion"),
      std::string::npos);
  EXPECT_NE(error_of(with({{"rotation_quaternion", {1, 0, 0}}}))
                .find("'obstacles[0].keyframes[0].rotation_quaternion'"),
            std::string::npos);
}

// `sheet.material.membrane_model`: read, checked with the key named, written only when not the
// default.
TEST(Scene, MembraneModelIsReadCheckedAndRoundTrips) {
  EXPECT_EQ(error_of({{"sheet", {{"material", {{"membrane_model", "arcs"}}}}}}),
            "s.json: key 'sheet.material.membrane_model': expected one of chord, arc; got 'arcs'");
  Scene s = small_scene();
  EXPECT_FALSE(scene_to_json(s)["sheet"]["material"].contains("membrane_model"))
      << "the default is not written, so default scenes keep their bytes";
  s.sheet.material.membrane_model = MembraneModel::arc;
  const json j = scene_to_json(s);
  EXPECT_EQ(j["sheet"]["material"]["membrane_model"], "arc");
  EXPECT_EQ(scene_from_json(j, "again").sheet.material.membrane_model, MembraneModel::arc);
}

// Obstacle `scale` (uniform scale of the shape, per keyframe or for the whole obstacle): read,
// range-checked with the key named, written back exactly.
TEST(Scene, ObstacleScaleIsReadCheckedAndRoundTrips) {
  const json keys = {{{"time", 0.0}}, {{"time", 1.0}, {"scale", 0.25}}};
  const Scene s = scene_from_json(
      {{"obstacles",
        {{{"kind", "inverted_sphere"}, {"radius", 0.2}, {"scale", 2.0}, {"keyframes", keys}}}}},
      "s.json");
  ASSERT_EQ(s.obstacles.size(), 1u);
  EXPECT_EQ(s.obstacles[0].kind, papersim::collision::ColliderKind::inverted_sphere);
  ASSERT_EQ(s.obstacles[0].keyframes.size(), 2u);
  EXPECT_EQ(s.obstacles[0].keyframes[0].scale, 2.0);  // the obstacle's scale is the default
  EXPECT_EQ(s.obstacles[0].keyframes[1].scale, 0.25);
  EXPECT_EQ(scene_to_json(scene_from_json(scene_to_json(s), "again")), scene_to_json(s));
  for (const json& bad : {json(0.0), json(-1.0), json("big")}) {
    const json k = {{{"time", 0.0}}, {{"time", 1.0}, {"scale", bad}}};
    EXPECT_NE(error_of({{"obstacles", {{{"kind", "sphere"}, {"keyframes", k}}}}})
                  .find("'obstacles[0].keyframes[1].scale'"),
              std::string::npos)
        << bad;
    EXPECT_NE(error_of({{"obstacles", {{{"kind", "sphere"}, {"scale", bad}}}}})
                  .find("'obstacles[0].scale'"),
              std::string::npos)
        << bad;
  }
}

TEST(Scene, ObstacleLiftIsReadCheckedAndRoundTrips) {
  const Scene s = scene_from_json(
      {{"obstacles",
        {{{"kind", "cylinder"}, {"lift", {{"load", 5.0}, {"speed", 0.2}}}}, {{"kind", "sphere"}}}}},
      "s.json");
  ASSERT_EQ(s.obstacles.size(), 2u);
  EXPECT_EQ(s.obstacles[0].lift.load, 5.0);
  EXPECT_EQ(s.obstacles[0].lift.speed, 0.2);
  EXPECT_TRUE(s.obstacles[0].lift.enabled());
  EXPECT_FALSE(s.obstacles[1].lift.enabled());  // off by default
  EXPECT_EQ(scene_to_json(scene_from_json(scene_to_json(s), "again")), scene_to_json(s));
  EXPECT_FALSE(scene_to_json(s)["obstacles"][1].contains("lift"));
  for (const json& bad : {json(0.0), json(-1.0), json("big")}) {
    EXPECT_NE(error_of({{"obstacles", {{{"kind", "sphere"}, {"lift", {{"load", bad}}}}}}})
                  .find("'obstacles[0].lift.load'"),
              std::string::npos)
        << bad;
    EXPECT_NE(
        error_of({{"obstacles", {{{"kind", "sphere"}, {"lift", {{"load", 1.0}, {"speed", bad}}}}}}})
            .find("'obstacles[0].lift.speed'"),
        std::string::npos)
        << bad;
  }
  EXPECT_NE(
      error_of({{"obstacles", {{{"kind", "sphere"}, {"lift", {{"load", 1.0}, {"sped", 1.0}}}}}}})
          .find("'obstacles[0].lift.sped'"),
      std::string::npos);
}

// crumple: the same seed draws the same scene, the cavity holds at 0.2 m until 1 s and shrinks
// to 0.05 m at 5 s, the material is SCENARIOS.md's, and every draw starts with the whole sheet
// inside the cavity (every corner at least 5 mm from its wall).
TEST(Scenario, CrumpleDrawsTheSheetInsideTheShrinkingCavity) {
  using papersim::collision::ColliderKind;
  EXPECT_EQ(scene_to_json(make_scenario("crumple", 5)), scene_to_json(make_scenario("crumple", 5)));
  EXPECT_NE(scene_to_json(make_scenario("crumple", 5)), scene_to_json(make_scenario("crumple", 6)));
  for (int seed = 0; seed < 40; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Scene s = make_scenario("crumple", seed);
    EXPECT_DOUBLE_EQ(s.duration, 5.0);
    EXPECT_FALSE(s.ground);
    EXPECT_TRUE(s.self_contact.enabled);
    EXPECT_DOUBLE_EQ(s.sheet.material.yield_curvature, 200.0);
    EXPECT_DOUBLE_EQ(s.sheet.material.weakening, 2.0);
    EXPECT_DOUBLE_EQ(s.sheet.material.damping, 1e-3);
    EXPECT_EQ(s.newton.max_iterations, 200);   // 60 does not finish the 5 s (docs/crumple.md)
    EXPECT_TRUE(s.contact.static_whole_step);  // seed 3 fails without it (docs/crumple.md)
    ASSERT_EQ(s.obstacles.size(), 1u);
    ASSERT_EQ(s.obstacles[0].kind, ColliderKind::inverted_sphere);
    const auto cavity = papersim::collision::make_collider(s.obstacles[0]);
    EXPECT_DOUBLE_EQ(0.2 * cavity->motion.scale(0.0), 0.2);
    EXPECT_DOUBLE_EQ(0.2 * cavity->motion.scale(1.0), 0.2);
    EXPECT_NEAR(0.2 * cavity->motion.scale(3.0), 0.125, 1e-15);
    EXPECT_NEAR(0.2 * cavity->motion.scale(5.0), 0.05, 1e-15);
    // Corners of the flat sheet: centre + Rz Ry Rx (+-w/2, +-h/2, 0).
    const Eigen::Vector3d a = s.sheet.rotation_deg * M_PI / 180;
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    EXPECT_GT(std::abs(a.x()) * 180 / M_PI, 81.9);  // nearly upright, as the reference starts it
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d corner((c & 1 ? 0.5 : -0.5) * s.sheet.width,
                                   (c & 2 ? 0.5 : -0.5) * s.sheet.height, 0);
      EXPECT_GT(cavity->distance(s.sheet.position + R * corner, 0.0), 5e-3);
    }
  }
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
  EXPECT_TRUE(fs::exists(dir / "sheet.obj") && fs::exists(dir / "sheet.ply") &&
              fs::exists(dir / "meta.json"));
  EXPECT_FALSE(fs::exists(dir / ".papersim-partial"));
  EXPECT_LE(r.quality.max_principal_stretch, 1.005);
  EXPECT_GT(r.quality.min_obstacle_distance.at(0), 0.0);
  EXPECT_EQ(r.quality.self_intersections, 0);
  ASSERT_TRUE(r.self_contact.has_value());
  EXPECT_EQ(r.self_contact->max_active_pairs, 0) << "a flat sheet is far from itself";
  EXPECT_GE(r.self_contact->seconds, 0.0);
  fs::remove_all(dir);
  // A step that cannot converge (one Newton iteration, no halving) fails: no folder is left.
  Scene failing = small_scene();
  failing.newton.max_iterations = 1;
  failing.newton.max_halvings = 0;
  failing.newton.tolerance = 1e-30;
  EXPECT_THROW(run_scene(failing, options_for(dir.string())), NumericError);
  EXPECT_FALSE(fs::exists(dir));
}

namespace {

/// Highest point of a scene's obstacles [m].
double highest_obstacle(const Scene& s) {
  double top = 0;
  for (const auto& o : s.obstacles)
    top = std::max(top, papersim::collision::make_collider(o)->bounds(0).hi.z());
  return top;
}

/// Horizontal heading of an obstacle's local x axis [deg in (-180, 180]] and its tilt from the
/// horizontal [deg].
Eigen::Vector2d heading_and_tilt(const papersim::collision::ColliderSpec& o) {
  const Eigen::Vector3d axis = o.keyframes.front().rotation * Eigen::Vector3d::UnitX();
  return {std::atan2(axis.y(), axis.x()) * 180 / M_PI, std::asin(std::abs(axis.z())) * 180 / M_PI};
}

}  // namespace

TEST(Scenario, FallScenariosDrawWithinTheirRangesAndReachTheirObstacles) {
  using papersim::collision::ColliderKind;
  for (const std::string name : {"fall-cylinder", "fall-gable", "fall-sphere", "fall-spheres"}) {
    EXPECT_EQ(scene_to_json(make_scenario(name, 5)), scene_to_json(make_scenario(name, 5))) << name;
    EXPECT_NE(scene_to_json(make_scenario(name, 5)), scene_to_json(make_scenario(name, 6))) << name;
    for (int seed = 0; seed < 40; ++seed) {
      const Scene s = make_scenario(name, seed);
      SCOPED_TRACE(name + " seed " + std::to_string(seed));
      EXPECT_DOUBLE_EQ(s.sheet.position.z(), 0.5);
      EXPECT_TRUE(s.ground);
      ASSERT_FALSE(s.obstacles.empty());
      // Every draw reaches its highest obstacle within 80% of the duration in free fall.
      const double fall = 0.5 * -s.gravity.z() * std::pow(0.8 * s.duration, 2);
      EXPECT_GE(fall, 0.5 - highest_obstacle(s) - 1e-12);
      const double mu = s.obstacles.front().friction;
      for (const auto& o : s.obstacles) {
        EXPECT_EQ(o.friction, mu);  // one coefficient per draw
        const Eigen::Vector3d c = o.keyframes.front().translation;
        if (name == "fall-cylinder") {
          EXPECT_EQ(o.kind, ColliderKind::cylinder);
          EXPECT_TRUE(o.radius >= 0.01 && o.radius <= 0.10);
          EXPECT_TRUE(o.length >= 0.10 && o.length <= 1.0);
          EXPECT_LE(heading_and_tilt(o)[1], 5 + 1e-9);
          EXPECT_TRUE(std::abs(c.x()) <= 0.15 && std::abs(c.y()) <= 0.2 &&
                      std::abs(c.z()) <= o.radius);
          EXPECT_DOUBLE_EQ(s.gravity.z(), -9.8);
        } else if (name == "fall-gable") {
          EXPECT_EQ(o.kind, ColliderKind::gable);
          EXPECT_TRUE(o.half_width >= 0.015 && o.half_width <= 0.075);
          EXPECT_DOUBLE_EQ(o.height, o.half_width);  // a 90 degree ridge
          EXPECT_TRUE(o.length >= 0.10 && o.length <= 0.50);
          EXPECT_NEAR(heading_and_tilt(o)[1], 0, 1e-9);
          EXPECT_TRUE(std::abs(c.x()) <= 0.12 && std::abs(c.y()) <= 0.15 && c.z() == 0);
          EXPECT_TRUE(s.gravity.z() >= -1000 && s.gravity.z() <= -100);
        } else if (name == "fall-sphere") {
          EXPECT_EQ(o.kind, ColliderKind::sphere);
          EXPECT_TRUE(o.radius >= 0.01 && o.radius <= 0.05);
          EXPECT_TRUE(std::abs(c.x()) <= 0.05 && std::abs(c.y()) <= 0.15 &&
                      std::abs(c.z()) <= o.radius);
          EXPECT_TRUE(s.gravity.z() >= -1000 && s.gravity.z() <= -9.8);
        } else {
          EXPECT_EQ(o.kind, ColliderKind::sphere);
          EXPECT_TRUE(o.radius >= 0.005 && o.radius <= 0.01);
          EXPECT_TRUE(std::abs(c.x()) <= 0.15 + 0.4 * 0.3 && std::abs(c.y()) <= 0.21 + 0.4 * 0.42);
          EXPECT_LE(std::abs(c.z()), 0.5 * o.radius);
          EXPECT_TRUE(s.gravity.z() >= -5000 && s.gravity.z() <= -1000);
        }
      }
      if (name == "fall-cylinder" || name == "fall-gable" || name == "fall-sphere") {
        EXPECT_GE(s.obstacles.size(), 1u);
        EXPECT_LE(s.obstacles.size(), 3u);
      } else {  // g^2 spheres, g = floor(sqrt(randint(30, 150))): 25 .. 144
        const int g = static_cast<int>(std::lround(std::sqrt(s.obstacles.size())));
        EXPECT_EQ(static_cast<size_t>(g * g), s.obstacles.size());
        EXPECT_TRUE(g >= 5 && g <= 12);
        EXPECT_DOUBLE_EQ(s.sheet.material.yield_curvature, 50.0);
        EXPECT_DOUBLE_EQ(s.sheet.material.weakening, 0.2);
      }
    }
  }
}

TEST(Run, ExtrapolatedProjectedStepsSaveIterationsAndKeepTheResult) {
  // Pull seed 3 at 14 mm edges over 0.4 s: the lifted sheet buckles, the exact Hessian is often
  // indefinite and projected Newton steps are short (inertia alone along the buckling modes).
  // Lengthening accepted projected steps while the energy falls (solver.max_extrapolation)
  // must save Newton iterations and end at the same state to well below the mesh scale.
  Scene scene = make_scenario("pull", 3);
  scene.sheet.edge_length = 0.014;
  scene.duration = 0.4;
  scene.newton.trust_region_cg = 0;  // projected Newton steps, the ones extrapolated
  RunOptions quiet;
  const RunResult plain = run_scene(scene, quiet);
  scene.newton.max_extrapolation = 8;
  const RunResult longer = run_scene(scene, quiet);
  const int it_plain = plain.totals.newton_iterations, it_longer = longer.totals.newton_iterations;
  EXPECT_EQ(plain.totals.extrapolations, 0);
  EXPECT_GT(longer.totals.extrapolations, 0);
  EXPECT_LT(it_longer, it_plain);
  const double diff = (plain.state.positions - longer.state.positions).cwiseAbs().maxCoeff();
  std::printf(
      "iterations %d plain, %d with extrapolation (%d extrapolated); largest coordinate difference "
      "%.3g m\n",
      it_plain, it_longer, longer.totals.extrapolations, diff);
  // Each step stops within 1e-4 m/s x h = 1 micrometre of its minimiser; 10 micrometres allows
  // 40 steps of such differences to grow through the buckling (measured: 2e-8 m).
  EXPECT_LT(diff, 1e-5);
}

TEST(Scene, NullDuplicateKeysAndHugeValuesAreErrors) {
  EXPECT_EQ(error_of(json{{"duration", nullptr}}),
            "s.json: key 'duration': null is not a value (leave the key out for its default)");
  EXPECT_EQ(error_of(json{{"duration", 1e300}}),
            "s.json: key 'duration': value 1e+300 out of range (0, 10000]");
  EXPECT_EQ(error_of(json{{"seed", 2147483648LL}}),
            "s.json: key 'seed': value 2147483648 out of range [0, 2147483647]");
  EXPECT_EQ(error_of(json{{"seed", 18446744073709551615ULL}}),
            "s.json: key 'seed': value 18446744073709551615 out of range [0, 2147483647]");
  EXPECT_EQ(error_of(json{{"sheet", {{"position", {1e300, 0, 0}}}}}),
            "s.json: key 'sheet.position': a coordinate beyond the limit of 1000 m");
  std::istringstream twice(R"({"duration": 1, "sheet": {"width": 0.1, "width": 0.2}})");
  try {
    parse_scene_text(twice, "s.json");
    FAIL() << "a repeated key was accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), "s.json: key 'width' appears twice in the same object");
  }
  // Found by fuzz_scene: a number beyond double range threw json's out_of_range past the reader.
  std::istringstream overflow(R"({"gravity": [0, 0, -121.27e674554907327]})");
  try {
    parse_scene_text(overflow, "s.json");
    FAIL() << "an overflowing number was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("s.json: not valid JSON"), std::string::npos) << e.what();
  }
  std::istringstream apart(R"({"sheet": {"width": 0.1}, "contact": {"width": 2}})");
  EXPECT_NO_THROW(parse_scene_text(apart, "s.json")) << "the same key in two objects is fine";
}

TEST(Run, PublishesThisRunsFilesOnlyAndStopsWhenAsked) {
  const fs::path dir =
      fs::temp_directory_path() / ("papersim_publish_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  Scene s = small_scene();
  s.duration = 4 * s.time_step;
  RunOptions o = options_for(dir.string());
  o.frames_every = 1;
  run_scene(s, o);
  ASSERT_TRUE(fs::exists(dir / "sheet.ply") && fs::exists(dir / "frames"));
  s.output.write_ply = false;
  run_scene(s, options_for(dir.string()));
  EXPECT_FALSE(fs::exists(dir / "sheet.ply")) << "an old sheet.ply beside the new meta.json";
  EXPECT_FALSE(fs::exists(dir / "frames")) << "old frames beside the new meta.json";
  EXPECT_TRUE(fs::exists(dir / "sheet.obj") && fs::exists(dir / "meta.json"));
  // A run stopped by poll_stop leaves the earlier run as it was.
  const auto before = fs::last_write_time(dir / "meta.json");
  RunOptions stopping = options_for(dir.string());
  int steps = 0;
  stopping.poll_stop = [&steps] {
    if (++steps == 2) throw std::runtime_error("stop");
  };
  EXPECT_THROW(run_scene(s, stopping), std::runtime_error);
  EXPECT_EQ(fs::last_write_time(dir / "meta.json"), before);
  EXPECT_FALSE(fs::exists(dir / ".papersim-partial"));
  fs::remove_all(dir);
}

TEST(Run, ReportsProgressPerPercentAndWhileStepsAreSlow) {
  // 200 steps: a call per percent by default (the first step, at 0%, and every second one after
  // it); with progress_every 0 the
  // time rule applies after every step, so a run whose steps take minutes still reports.
  Scene s = small_scene();
  s.duration = 200 * s.time_step;
  std::vector<double> fractions;
  RunOptions o;
  o.progress = [&fractions](double f, double) { fractions.push_back(f); };
  run_scene(s, o);
  EXPECT_EQ(fractions.size(), 101u);
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  fractions.clear();
  o.progress_every = 0.0;
  run_scene(s, o);
  EXPECT_EQ(fractions.size(), 200u);
  EXPECT_DOUBLE_EQ(fractions.front(), 1.0 / 200);
}

// `papersim run OUT/scene.json --out OUT` (the batch's and the scenario workflow's way): the run
// replaces an earlier run's outputs but never removes the scene file it reads.
TEST(Run, KeepsTheSceneFileItReadsInItsOutputFolder) {
  const fs::path dir = fs::temp_directory_path() / "papersim_scene_in_out";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ofstream out(dir / "scene.json");
    out << scene_to_json(small_scene()).dump(2);
  }
  std::ofstream(dir / "sheet.ply") << "an earlier run's file";
  Scene s = load_scene((dir / "scene.json").string());
  s.output.write_ply = false;
  run_scene(s, options_for(dir.string()));
  EXPECT_TRUE(fs::exists(dir / "scene.json"));
  EXPECT_TRUE(fs::exists(dir / "meta.json"));
  EXPECT_FALSE(fs::exists(dir / "sheet.ply")) << "an output this run did not write is removed";
  fs::remove_all(dir);
}

TEST(Run, ReusedFactorisationsOfAnUnchangedMatrixSaveFactoringAndKeepTheResult) {
  // fall-gable seed 0 at 20 mm edges over its first 25 ms: free fall, whose Newton matrix
  // (inertia and the flat sheet's stiffness) is the same at every iteration and step. Reusing
  // the last factorisation (solver.max_factor_reuse) must then factor fewer times and give the
  // same motion to round-off. (Reuse is limited to quiet phases because where the matrix
  // changes it costs iterations: reusing whenever Newton converged took pull seed 3 at 14 mm
  // over 0.4 s from 222 iterations to 507, 414 of them factored; docs/performance.md.)
  Scene scene = make_scenario("fall-gable", 0);
  scene.sheet.edge_length = 0.02;
  scene.duration = 0.025;
  RunOptions quiet;
  const RunResult plain = run_scene(scene, quiet);
  scene.newton.max_factor_reuse = 4;
  const RunResult reused = run_scene(scene, quiet);
  EXPECT_EQ(plain.totals.reused_factorizations, 0);
  const int factored_plain = plain.totals.newton_iterations;
  const int factored_reused = reused.totals.newton_iterations - reused.totals.reused_factorizations;
  std::printf("iterations %d plain, %d with reuse (%d reused); factorisations %d against %d\n",
              plain.totals.newton_iterations, reused.totals.newton_iterations,
              reused.totals.reused_factorizations, factored_reused, factored_plain);
  // Four of every five iterations reuse (at most 4 in a row), so at most about a third factor.
  EXPECT_LT(3 * factored_reused, factored_plain + 3);
  // The sheet falls about 0.29 m; the same matrix gives the same steps up to round-off in the
  // solve (1e-12 relative), far below a nanometre.
  EXPECT_LT((plain.state.positions - reused.state.positions).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Run, CompressionLimitHoldsAFlatStripPressedEndToEnd) {
  // A 10 x 2 cm strip between the ground and a frictionless plate 1.2 mm above it, its two
  // short edges driven towards each other by 6 mm each in 50 ms (12% of its length). Buckles
  // of at most ~0.5 mm on 5 mm edges take up about 1% of the length (a sine of wavelength
  // 10 mm and amplitude A shortens by (pi A / 10 mm)^2), so the rest must go into the membrane.
  // Without a compression limit the strip shortens in its plane by several percent; with a 5%
  // limit its smallest principal stretch stays above 0.95 and the handles' springs take the rest.
  const auto run = [](double compression_limit) {
    json handles = json::array();
    for (double y : {0.0, 0.01, 0.02})
      for (double side : {0.0, 1.0})
        handles.push_back({{"point", {0.1 * side, y}},
                           {"keyframes",
                            {{{"time", 0.0}, {"displacement", {0, 0, 0}}},
                             {{"time", 0.05}, {"displacement", {0.006 * (1 - 2 * side), 0, 0}}}}}});
    const json plate = {{"kind", "plane"},
                        {"position", {0, 0, 0.0012}},
                        {"rotation_deg", {180, 0, 0}},
                        {"friction", 0}};
    const json j = {{"sheet",
                     {{"width", 0.1},
                      {"height", 0.02},
                      {"edge_length", 0.005},
                      {"position", {0, 0, 0.0006}},
                      {"material", {{"compression_limit", compression_limit}}}}},
                    {"gravity", {0, 0, 0}},
                    {"ground_friction", 0},
                    {"obstacles", {plate}},
                    {"contact", {{"thickness", 2e-4}}},
                    {"duration", 0.06},
                    {"time_step", 0.002},
                    {"self_contact", {{"enabled", false}}},
                    {"handles", handles}};
    RunOptions quiet;
    return run_scene(scene_from_json(j, "strip.json"), quiet).quality.min_principal_stretch;
  };
  const double free = run(0.0), limited = run(0.05);
  std::printf("smallest principal stretch: %.4f without a limit, %.4f with a 5%% limit\n", free,
              limited);
  EXPECT_LT(free, 0.95);
  EXPECT_GT(limited, 0.95);
  EXPECT_LT(limited, 0.975);  // the barrier acts (from 0.975 down), not a run that never pressed
}
