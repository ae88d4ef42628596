// Checkpoints (RunOptions::checkpoint_dir, resume_from): a run continued from a checkpoint ends
// in the state of the run that was not interrupted, and a checkpoint that does not fit the
// scene is refused with a message that names what is wrong. The checkpoint carries what the run
// had counted, so the continued run reports the whole run.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>

#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "tests/simulation/folded_sheet_scene.hpp"

using namespace papersim::simulation;
namespace fs = std::filesystem;

namespace {

/// A 6 x 4 cm sheet with 1 cm edges on the ground, one corner lifted 1 cm over 0.04 s:
/// 30 steps of 2 ms with contact, friction and a handle.
Scene lifted_corner() {
  Scene s;
  s.sheet.width = 0.06;
  s.sheet.height = 0.04;
  s.sheet.edge_length = 0.01;
  s.sheet.position = Eigen::Vector3d(0, 0, 1e-3);
  s.duration = 0.06;
  s.time_step = 0.002;
  HandleSpec h;
  h.material_point = Eigen::Vector2d(0.06, 0.04);
  h.keyframes = {{0.0, Eigen::Vector3d::Zero()}, {0.04, Eigen::Vector3d(0, 0, 0.01)}};
  s.handles = {h};
  return s;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("papersim_checkpoint_test_" + name);
  fs::remove_all(d);
  return d;
}

/// Options that save a checkpoint in `dir` every 10 steps, or resume from it.
RunOptions saving_to(const fs::path& dir) {
  RunOptions o;
  o.checkpoint_dir = dir.string();
  o.checkpoint_every = 10;
  return o;
}

RunOptions resuming_from(const fs::path& dir) {
  RunOptions o;
  o.resume_from = dir.string();
  return o;
}

}  // namespace

// The checkpoint holds every number the next steps read (positions, velocities, time, the
// mesh), so the continued run's end state is bit for bit the uninterrupted run's. The last
// checkpoint replaces the earlier ones.
TEST(Checkpoint, ResumedRunEndsInTheSameStateToTheBit) {
  const Scene scene = lifted_corner();
  const fs::path dir = fresh_dir("resume");
  const RunResult whole = run_scene(scene, saving_to(dir));
  ASSERT_EQ(whole.steps, 30);
  EXPECT_TRUE(fs::exists(dir / "checkpoint.json"));
  EXPECT_TRUE(fs::exists(dir / "checkpoint_00000020.ply"));
  EXPECT_FALSE(fs::exists(dir / "checkpoint_00000010.ply"));  // replaced
  const Checkpoint c = load_checkpoint(dir.string());
  EXPECT_EQ(c.step, 20);
  EXPECT_NEAR(c.time, 0.04, 1e-12);

  const RunResult continued = run_scene(scene, resuming_from(dir));
  EXPECT_EQ(continued.steps, 30);
  EXPECT_EQ(continued.state.time, whole.state.time);
  ASSERT_EQ(continued.state.positions.size(), whole.state.positions.size());
  EXPECT_EQ((continued.state.positions - whole.state.positions).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((continued.state.velocities - whole.state.velocities).cwiseAbs().maxCoeff(), 0.0);
  // Only the last 10 steps were simulated, but the checkpoint carried what the first 20
  // counted: the continued run reports the whole run (the same steps, so the same counts and
  // extremes to the bit), and its wall time includes the saved run's 20 steps.
  EXPECT_EQ(continued.totals.newton_iterations, whole.totals.newton_iterations);
  EXPECT_EQ(continued.totals.substeps, whole.totals.substeps);
  EXPECT_EQ(continued.totals.line_search_evaluations, whole.totals.line_search_evaluations);
  EXPECT_EQ(continued.sheet.vertices_start, whole.sheet.vertices_start);
  EXPECT_EQ(continued.quality.max_principal_stretch, whole.quality.max_principal_stretch);
  EXPECT_EQ(continued.quality.min_principal_stretch, whole.quality.min_principal_stretch);
  EXPECT_EQ(continued.quality.max_speed, whole.quality.max_speed);
  EXPECT_EQ(continued.quality.min_obstacle_distance, whole.quality.min_obstacle_distance);
  ASSERT_TRUE(continued.contact && whole.contact);
  EXPECT_EQ(continued.contact->max_normal_force, whole.contact->max_normal_force);
  ASSERT_TRUE(c.tally.has_value());
  EXPECT_EQ(c.tally->totals.substeps, 20);
  EXPECT_GT(c.tally->totals.newton_iterations, 0);
  EXPECT_LT(c.tally->totals.newton_iterations, whole.totals.newton_iterations);
  EXPECT_GE(continued.wall_seconds, c.tally->wall_seconds);

  // A checkpoint without the run's figures (as written before they were saved) still
  // continues, counting from the checkpoint on.
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "checkpoint.json"));
  j.erase("run");
  std::ofstream(dir / "checkpoint.json") << j.dump(1);
  const RunResult counted_from_there = run_scene(scene, resuming_from(dir));
  EXPECT_EQ((counted_from_there.state.positions - whole.state.positions).cwiseAbs().maxCoeff(),
            0.0);
  EXPECT_EQ(counted_from_there.totals.substeps, 10);
  EXPECT_EQ(counted_from_there.totals.newton_iterations + c.tally->totals.newton_iterations,
            whole.totals.newton_iterations);
  fs::remove_all(dir);
}

// A remeshed run renumbers its mesh after every pass as reading a checkpoint does
// (SheetMesh::rebuilt), so it too continues from a checkpoint to the bit; with the remesher's
// own edge numbering the continued run drifted by 4e-13 m in a step of the fold scene and by
// more as the sheet buckled.
TEST(Checkpoint, RemeshedRunResumesToTheBit) {
  Scene scene = lifted_corner();
  scene.sheet.edge_length = 0.005;
  scene.remesh.enabled = true;
  scene.remesh.params.size_min = 0.002;
  scene.remesh.params.size_max = 0.03;
  scene.remesh.params.refine_angle = 0.05;
  scene.handles[0].keyframes = {{0.0, Eigen::Vector3d::Zero()},
                                {0.04, Eigen::Vector3d(-0.03, -0.02, 0.03)}};
  const fs::path dir = fresh_dir("remeshed");
  const RunResult whole = run_scene(scene, saving_to(dir));
  ASSERT_TRUE(whole.remesh.has_value());
  // The mesh changed before the checkpoint (coarsened from its start) and after it.
  EXPECT_LT(whole.sheet.vertices, whole.sheet.vertices_start);
  EXPECT_GT(whole.remesh->passes, 3);
  std::printf("remeshed run: %d passes, %d splits, %d flips, %d collapses, %d -> %d vertices\n",
              whole.remesh->passes, whole.remesh->splits, whole.remesh->flips,
              whole.remesh->collapses, whole.sheet.vertices_start, whole.sheet.vertices);
  const RunResult continued = run_scene(scene, resuming_from(dir));
  ASSERT_EQ(continued.state.positions.size(), whole.state.positions.size());
  EXPECT_EQ(continued.mesh.faces(), whole.mesh.faces());
  EXPECT_EQ((continued.state.positions - whole.state.positions).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((continued.state.velocities - whole.state.velocities).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(continued.remesh->passes, whole.remesh->passes);
  fs::remove_all(dir);
}

// A sheet folded onto itself: the self-contact term keeps state between steps that the
// positions do not determine (its candidate pairs, found at an earlier iterate, and the pairs of
// its Hessian pattern, built when a pair last closed in). A run continued from a checkpoint
// taken while the layers touch still ends in the uninterrupted run's state to the bit.
// (Before, the continued run built another pattern and could find its candidates in another
// order: the same numbers factored and summed in another order. Here that left it 1.4e-14 m
// from the uninterrupted run after 10 steps; a crumple continued at t = 4.6 s ended 6.7 mm RMS
// from it, docs/crumple.md.)
TEST(Checkpoint, SelfContactRunResumesToTheBit) {
  const Scene s = test_scenes::sheet_folded_onto_itself(0.004, 0.7);
  const fs::path dir = fresh_dir("self_contact");
  RunOptions save = saving_to(dir);
  save.checkpoint_every = 130;  // one checkpoint, at t = 0.65 s: the top half rests on the bottom
  const RunResult whole = run_scene(s, save);
  ASSERT_TRUE(whole.self_contact.has_value());
  EXPECT_GT(whole.self_contact->max_active_pairs, 0);
  EXPECT_GT(whole.pattern_changes, 1);
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "checkpoint.json"));
  ASSERT_TRUE(j.contains("self_contact_pattern"));
  EXPECT_GT(j.at("self_contact_pattern").size(), 0u);
  const RunResult continued = run_scene(s, resuming_from(dir));
  ASSERT_EQ(continued.state.positions.size(), whole.state.positions.size());
  EXPECT_EQ((continued.state.positions - whole.state.positions).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((continued.state.velocities - whole.state.velocities).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(continued.totals.newton_iterations, whole.totals.newton_iterations);
  EXPECT_EQ(continued.pattern_changes, whole.pattern_changes);

  // A pattern that names a pair the mesh does not have, or is not a list of triples, is refused
  // by name.
  const auto refused = [&](const nlohmann::json& pattern) {
    nlohmann::json bad = j;
    bad["self_contact_pattern"] = pattern;
    std::ofstream(dir / "checkpoint.json") << bad.dump(1);
    try {
      run_scene(s, resuming_from(dir));
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(refused({{0, 5, 100000}}).find("self-contact pattern pair (0, 5, 100000)"),
            std::string::npos);
  EXPECT_NE(refused({{2, 5, 6}}).find("self-contact pattern pair (2, 5, 6)"), std::string::npos);
  EXPECT_NE(refused({{1, 2}}).find("key 'self_contact_pattern'"), std::string::npos);
  fs::remove_all(dir);
}

// With solver.max_factor_reuse a quiet step may start from the factorisation the last step
// ended with (modified Newton), so where the step ends depends on that matrix, which the
// positions at the checkpoint do not give. The checkpoint saves it (checkpoint_NNNNNNNN.factor) and
// the continued run factors it again: it takes the uninterrupted run's steps to the bit, with the
// same reuses. (Without it the continued run refactors at its first step, ending elsewhere within
// the Newton tolerance: below.)
// The scene: fall-spheres seed 0 (which sets solver.max_factor_reuse 4) at 20 mm edges, 200
// steps of 0.5 ms; the last checkpoint, at step 150, is taken in a quiet phase, between two
// steps that share a factorisation.
TEST(Checkpoint, FactorReuseRunResumesToTheBit) {
  Scene scene = make_scenario("fall-spheres", 0);
  scene.sheet.edge_length = 0.02;
  ASSERT_EQ(scene.newton.max_factor_reuse, 4);
  const fs::path dir = fresh_dir("factor_reuse");
  RunOptions save = saving_to(dir);
  save.checkpoint_every = 50;
  const RunResult whole = run_scene(scene, save);
  ASSERT_EQ(whole.steps, 200);
  EXPECT_GT(whole.totals.reused_factorizations, 0);
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "checkpoint.json"));
  ASSERT_TRUE(j.contains("reusable_factor"));
  EXPECT_EQ(j.at("reusable_factor").at("file"), "checkpoint_00000150.factor");
  EXPECT_TRUE(fs::exists(dir / "checkpoint_00000150.factor"));
  EXPECT_FALSE(fs::exists(dir / "checkpoint_00000100.factor"));  // replaced with its checkpoint
  const Checkpoint c = load_checkpoint(dir.string());
  ASSERT_TRUE(c.factor.has_value());
  EXPECT_EQ(c.factor->h, scene.time_step);
  EXPECT_EQ(c.factor->values.size(), j.at("reusable_factor").at("entries").get<size_t>());

  const RunResult continued = run_scene(scene, resuming_from(dir));
  ASSERT_EQ(continued.state.positions.size(), whole.state.positions.size());
  EXPECT_EQ((continued.state.positions - whole.state.positions).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((continued.state.velocities - whole.state.velocities).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(continued.totals.newton_iterations, whole.totals.newton_iterations);
  EXPECT_EQ(continued.totals.reused_factorizations, whole.totals.reused_factorizations);

  // The checkpoint without it (as written before it was saved) continues with a fresh
  // factorisation: fewer reuses and another end state.
  const auto write = [&](const nlohmann::json& k) {
    std::ofstream(dir / "checkpoint.json") << k.dump(1);
  };
  nlohmann::json without = j;
  without.erase("reusable_factor");
  write(without);
  const RunResult refactored = run_scene(scene, resuming_from(dir));
  const double apart = (refactored.state.positions - whole.state.positions).cwiseAbs().maxCoeff();
  std::printf("continued without the saved factorisation: %d reuses against %d, end %.3g m apart\n",
              refactored.totals.reused_factorizations, whole.totals.reused_factorizations, apart);
  EXPECT_LT(refactored.totals.reused_factorizations, whole.totals.reused_factorizations);
  EXPECT_GT(apart, 0.0);

  // A matrix file that does not match its record, or a record naming no file in the folder, is
  // refused by name; so is a matrix of another size than the run's.
  const auto refused = [&](const nlohmann::json& k) {
    write(k);
    try {
      run_scene(scene, resuming_from(dir));
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  nlohmann::json wrong_count = j;
  wrong_count["reusable_factor"]["entries"] = 7;
  EXPECT_NE(refused(wrong_count).find("checkpoint_00000150.factor holds"), std::string::npos);
  nlohmann::json elsewhere = j;
  elsewhere["reusable_factor"]["file"] = "../x.factor";
  EXPECT_NE(refused(elsewhere).find("key 'reusable_factor': 'file'"), std::string::npos);
  fs::resize_file(dir / "checkpoint_00000150.factor",
                  fs::file_size(dir / "checkpoint_00000150.factor") - 8);
  EXPECT_NE(refused(j).find("entries long"), std::string::npos);
  {  // a count no file holds is refused before anything is allocated for it
    const std::uint64_t huge = std::uint64_t(1) << 60;
    std::ofstream f(dir / "huge.factor", std::ios::binary);
    f << "papersim matrix 1\n";
    f.write(reinterpret_cast<const char*>(&huge), sizeof huge);
  }
  nlohmann::json too_many = j;
  too_many["reusable_factor"]["file"] = "huge.factor";
  too_many["reusable_factor"]["entries"] = std::uint64_t(1) << 60;
  EXPECT_NE(refused(too_many).find("huge.factor is not 1152921504606846976 entries long"),
            std::string::npos);
  Checkpoint small = c;
  small.factor->values.resize(9);
  save_checkpoint(dir.string(), scene, small.step, small.mesh, small.state, nullptr, nullptr,
                  &*small.factor);
  EXPECT_NE(refused(nlohmann::json::parse(std::ifstream(dir / "checkpoint.json")))
                .find("matrix has 9 entries"),
            std::string::npos);
  fs::remove_all(dir);
}

// A sheet file whose mesh is valid but cannot be simulated is bad input, refused by name with
// its thinnest face, from a checkpoint or from the key sheet.mesh. The sheet is fuzz_checkpoint's
// finding (tests/data/fuzz/fuzz_checkpoint/): one corner's material coordinate moved to
// x = -128 m makes a 128 m sliver face among 1 cm ones, on which the bending's edge slope system
// cannot be factored. Before, both ended in "simulation failed" (exit status 4), naming neither
// the file nor the face.
TEST(Checkpoint, ASheetThatCannotBeSimulatedIsRefusedByName) {
  std::ifstream in(std::string(PAPERSIM_TEST_DATA_DIR) +
                       "/fuzz/fuzz_checkpoint/sheet_with_a_128_m_sliver_face_bending_unfactorable",
                   std::ios::binary);
  const std::string finding(std::istreambuf_iterator<char>(in), {});
  ASSERT_GT(finding.size(), 1u);
  const std::string sheet = finding.substr(1);  // the first byte chose the file it replaces
  // The fuzz target's scene: a 4 x 4 cm sheet with 1 cm edges in free fall.
  const Scene scene = scene_from_json(
      {{"sheet",
        {{"width", 0.04}, {"height", 0.04}, {"edge_length", 0.01}, {"position", {0, 0, 0.2}}}},
       {"duration", 0.01},
       {"time_step", 0.001},
       {"solver", {{"max_factor_reuse", 4}}}},
      "fuzz_scene.json");
  const fs::path dir = fresh_dir("unusable_sheet");
  RunOptions save = saving_to(dir);
  save.checkpoint_every = 6;
  run_scene(scene, save);
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "checkpoint.json"));
  std::ofstream(dir / j.at("sheet").get<std::string>(), std::ios::binary | std::ios::trunc)
      << sheet;
  const auto refusal = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  const std::string resumed = refusal([&] { run_scene(scene, resuming_from(dir)); });
  EXPECT_NE(resumed.find("resume: the saved sheet cannot be simulated: bending:"),
            std::string::npos)
      << resumed;
  EXPECT_NE(resumed.find("face 1, of aspect ratio 1.59e-08"), std::string::npos) << resumed;
  Scene from_file = scene;
  from_file.sheet.mesh_path = (dir / "sheet.ply").string();
  std::ofstream(from_file.sheet.mesh_path, std::ios::binary | std::ios::trunc) << sheet;
  const std::string started = refusal([&] { papersim::simulation::Run run(from_file); });
  EXPECT_NE(started.find("key 'sheet.mesh': " + from_file.sheet.mesh_path + " cannot be simulated"),
            std::string::npos)
      << started;
  fs::remove_all(dir);
}

// The run figures survive the trip through checkpoint.json, infinite extremes (an obstacle not
// met yet, an energy range not begun) included.
// The barriers' stiffnesses the last step ended with are part of the state the next step reads
// (the load rule's and the adaptive self-contact stiffness).
TEST(Checkpoint, CarriesTheBarrierStiffnesses) {
  const Scene scene = lifted_corner();
  const fs::path dir = fresh_dir("stiffness");
  run_scene(scene, saving_to(dir));
  Checkpoint c = load_checkpoint(dir.string());
  c.state.contact_stiffness = 123.5;
  c.state.self_contact_stiffness = 800;
  save_checkpoint(dir.string(), scene, c.step, c.mesh, c.state);
  const Checkpoint d = load_checkpoint(dir.string());
  EXPECT_EQ(d.state.contact_stiffness, 123.5);
  EXPECT_EQ(d.state.self_contact_stiffness, 800);
  fs::remove_all(dir);
}

TEST(Checkpoint, RunFiguresRoundTripThroughJson) {
  RunTally t;
  t.wall_seconds = 12.5;
  t.totals.substeps = 7;
  t.totals.newton_iterations = 31;
  t.totals.seconds_solve = 0.25;
  t.totals.residual = 3e-5;
  t.pattern_changes = 4;
  t.sheet = {96, 150, 0, 0, 120, 200};
  t.terms.contact.max_normal_force = 1.5;
  t.terms.self_contact.max_active_pairs = 9;
  t.terms.self_contact.stiffness_doublings = 3;
  t.terms.self_contact.max_stiffness = 3200;
  t.quality.max_principal_stretch = 1.004;
  t.quality.min_principal_stretch = 0.97;
  t.quality.min_obstacle_distance = {2e-7, INF};
  t.quality.lifts = {{1, 20.5, 3e-3}};
  t.remesh.passes = 5;
  t.remesh.rescues = 1;  // a resumed run keeps the obstacle criterion a rescue turned on
  t.remesh.refusals = {{"too long", 12}, {"veto: strain", 3}};
  t.remesh.rollback_reasons = {{"obstacle", 1}};
  t.remesh.max_energy_jump_relative = 0.04;
  const RunTally u = tally_from_json(nlohmann::json::parse(tally_to_json(t).dump()));
  EXPECT_EQ(u.wall_seconds, 12.5);
  EXPECT_EQ(u.totals.substeps, 7);
  EXPECT_EQ(u.totals.newton_iterations, 31);
  EXPECT_EQ(u.totals.seconds_solve, 0.25);
  EXPECT_EQ(u.totals.residual, 3e-5);
  EXPECT_EQ(u.pattern_changes, 4);
  EXPECT_EQ(u.sheet.vertices_start, 96);
  EXPECT_EQ(u.sheet.faces_start, 150);
  EXPECT_EQ(u.sheet.vertices_max, 120);
  EXPECT_EQ(u.sheet.faces_max, 200);
  EXPECT_EQ(u.terms.contact.max_normal_force, 1.5);
  EXPECT_EQ(u.terms.self_contact.max_active_pairs, 9);
  EXPECT_EQ(u.terms.self_contact.stiffness_doublings, 3);
  EXPECT_EQ(u.terms.self_contact.max_stiffness, 3200);
  EXPECT_EQ(u.quality.max_principal_stretch, 1.004);
  EXPECT_EQ(u.quality.min_principal_stretch, 0.97);
  EXPECT_EQ(u.quality.min_obstacle_distance, t.quality.min_obstacle_distance);
  ASSERT_EQ(u.quality.lifts.size(), 1u);
  EXPECT_EQ(u.quality.lifts[0].obstacle, 1);
  EXPECT_EQ(u.quality.lifts[0].max_load, 20.5);
  EXPECT_EQ(u.quality.lifts[0].max_rise, 3e-3);
  EXPECT_EQ(u.remesh.passes, 5);
  EXPECT_EQ(u.remesh.rescues, 1);
  EXPECT_EQ(u.remesh.refusals, t.remesh.refusals);
  EXPECT_EQ(u.remesh.rollback_reasons, t.remesh.rollback_reasons);
  EXPECT_EQ(u.remesh.max_energy_jump_relative, 0.04);
  EXPECT_EQ(u.energy_min, INF);
  EXPECT_EQ(u.energy_max, -INF);
}

// A checkpoint continues at another time step when its time is a whole number of the new steps
// (to study a hard spot with smaller steps): t = 0.04 s is step 40 of 1 ms steps, and the run
// does the remaining 20 steps of 1 ms. Its end differs from the 2 ms run's by the time
// discretisation only (backward Euler's error is first order in the step; the corner is still
// settling where it was set down at 0.04 s).
TEST(Checkpoint, ResumesAtAnotherTimeStepThatDividesItsTime) {
  const Scene scene = lifted_corner();
  const fs::path dir = fresh_dir("other_step");
  const RunResult whole = run_scene(scene, saving_to(dir));
  Scene finer = scene;
  finer.time_step = 0.001;
  RunOptions resume = resuming_from(dir);
  const fs::path out = fresh_dir("other_step_out");
  resume.out_dir = out.string();
  const RunResult continued = run_scene(finer, resume);
  // meta.json names the changed key, and only it.
  const nlohmann::json resumed =
      nlohmann::json::parse(std::ifstream(out / "meta.json")).at("resumed");
  EXPECT_EQ(resumed.at("scene_changes"), nlohmann::json::array({"/time_step"}));
  EXPECT_EQ(resumed.at("step"), 40);
  fs::remove_all(out);
  EXPECT_EQ(continued.steps, 60);
  EXPECT_NEAR(continued.state.time, 0.06, 1e-12);
  EXPECT_EQ(continued.totals.substeps, 20 + 20);  // the checkpoint's 20 of 2 ms, then 20 of 1 ms
  const double moved = (continued.state.positions - whole.state.positions).cwiseAbs().maxCoeff();
  std::printf(
      "1 ms from the 2 ms run's checkpoint at 0.04 s: end state %.3g m from the 2 ms run's\n",
      moved);
  EXPECT_GT(moved, 0.0);
  EXPECT_LT(moved, 1e-3);
  fs::remove_all(dir);
}

TEST(Checkpoint, ACheckpointThatDoesNotFitIsRefusedByName) {
  const fs::path dir = fresh_dir("refuse");
  const RunOptions resume = resuming_from(dir);
  try {
    run_scene(lifted_corner(), resume);
    FAIL() << "a missing checkpoint was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("checkpoint.json"), std::string::npos) << e.what();
  }

  run_scene(lifted_corner(), saving_to(dir));
  Scene other_step = lifted_corner();
  other_step.time_step = 0.003;  // 0.04 s is not a whole number of 3 ms steps
  try {
    run_scene(other_step, resume);
    FAIL() << "a checkpoint of another time step was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("time step"), std::string::npos) << e.what();
  }

  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "checkpoint.json"));
  j["run"].erase("totals");
  std::ofstream(dir / "checkpoint.json") << j.dump(1);
  try {
    run_scene(lifted_corner(), resume);
    FAIL() << "a checkpoint with incomplete run figures was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("'run'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("totals"), std::string::npos) << e.what();
  }

  std::ofstream(dir / "checkpoint.json") << R"({"format": "something else", "step": 1})";
  try {
    run_scene(lifted_corner(), resume);
    FAIL() << "a file of another format was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("'format'"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}
