// Regression tests of issue 17's failures 1, 4, 5, 6 and 7: hostile or careless input to
// papersim and scenegen gives a clear error and the documented exit status, never a crash,
// and an output folder never mixes two runs.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "fixtures.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Replace line `index` (0-based) of a text file.
void replace_line(const std::string& path, int index, const std::string& line) {
  std::istringstream in(read_text(path));
  std::ostringstream out;
  std::string l;
  for (int i = 0; std::getline(in, l); ++i) out << (i == index ? line : l) << '\n';
  std::ofstream(path) << out.str();
}

/// The first `keep` lines of a text file.
void keep_lines(const std::string& path, int keep) {
  std::istringstream in(read_text(path));
  std::ostringstream out;
  std::string l;
  for (int i = 0; i < keep && std::getline(in, l); ++i) out << l << '\n';
  std::ofstream(path) << out.str();
}

int count_lines_starting(const std::string& path, const std::string& prefix) {
  std::istringstream in(read_text(path));
  std::string l;
  int n = 0;
  while (std::getline(in, l)) n += l.rfind(prefix, 0) == 0;
  return n;
}

// --- 1: a coordinate of 1e200 crashed scenegen (exit 139) ----------------------------------

TEST(HostileInput, ScenegenHugeCoordinateIsAnErrorNamingTheLimit) {
  Scratch dir("huge");
  const std::string mesh = example_sheet(dir, "flat", "flat.obj");
  replace_line(mesh, 1, "v 1e200 0 0");
  for (const char* command : {"prepare", "render"}) {
    const Outcome r = run({SCENEGEN, command, mesh, "--out", dir.str(std::string("out_") + command),
                           "--size", "32x48"});
    EXPECT_EQ(r.status, 2) << command << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "exceeds the limit of 1000 m")) << r.err;
    EXPECT_FALSE(fs::exists(dir.str(std::string("out_") + command)));
  }
}

// --- 4: files of two runs mixed in one folder ---------------------------------------------

TEST(HostileInput, PapersimRunWithoutPlyRemovesTheOldPlyAndFrames) {
  Scratch dir("mixed");
  json scene = small_scene(dir);
  const std::string out = dir.str("out");
  scene["output"]["ply"] = true;
  Outcome r = run({PAPERSIM, "run", write_scene(dir, "a.json", scene), "--out", out, "--frames",
                   "5", "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_TRUE(fs::exists(out + "/sheet.ply"));
  ASSERT_TRUE(fs::exists(out + "/frames"));
  scene["output"]["ply"] = false;
  r = run({PAPERSIM, "run", write_scene(dir, "b.json", scene), "--out", out, "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(contains(r.out, "sheet.ply")) << r.out;
  EXPECT_EQ(listing(out), (std::vector<std::string>{"meta.json", "sheet.obj"}));
}

TEST(HostileInput, ScenarioDrawOnlyRemovesTheOutputsOfAnEarlierRun) {
  Scratch dir("drawonly");
  const std::string out = dir.str("out");
  fs::create_directories(out + "/frames");
  for (const char* f : {"sheet.obj", "sheet.ply", "meta.json", "notes.txt"})
    std::ofstream(out + "/" + f) << "old\n";
  const Outcome r = run({PAPERSIM, "scenario", "pull", "--seed", "2", "--draw-only", "--out", out});
  ASSERT_EQ(r.status, 0) << r.err;
  // The user's own file stays; every papersim output of the earlier run goes.
  EXPECT_EQ(listing(out), (std::vector<std::string>{"notes.txt", "scene.json"}));
}

TEST(HostileInput, ScenegenNoValidCameraOverAGoodSampleLeavesOnlyTheFailedMeta) {
  Scratch dir("nocamera");
  const std::string out = dir.str("out");
  fs::create_directories(out);
  for (const char* f : {"image.png", "uv.exr", "mask.png", "backward.npy", "meta.json"})
    std::ofstream(out + "/" + f) << "an earlier sample\n";
  // A sheet folded flat onto itself: no camera direction sees all of it (as in scenegen's
  // render_test).
  scenegen::ExampleSheetParams p;
  p.fold_angle_deg = 178.0;
  p.fold_x = -0.01;
  const std::string mesh = dir.str("folded.obj");
  {
    std::ofstream obj(mesh);
    scenegen::write_sheet_obj(obj, scenegen::make_example_sheet("fold", p));
  }
  const Outcome r = run({SCENEGEN, "render", mesh, "--out", out, "--size", "64x90", "--quiet"});
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_EQ(listing(out), std::vector<std::string>{"meta.json"});
  EXPECT_TRUE(contains(read_text(out + "/meta.json"), "\"failed\""))
      << read_text(out + "/meta.json");
}

// --- 5: accepted without a word ---------------------------------------------------------

TEST(HostileInput, NullForASceneKeyIsAnError) {
  Scratch dir("null");
  json scene = small_scene(dir);
  scene["sheet"]["material"]["poisson"] = nullptr;
  const Outcome r =
      run({PAPERSIM, "run", write_scene(dir, "s.json", scene), "--out", dir.str("out"), "--quiet"});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "s.json: key 'sheet.material.poisson': null")) << r.err;
  EXPECT_FALSE(fs::exists(dir.str("out")));
}

TEST(HostileInput, DuplicateSceneKeyIsAnError) {
  Scratch dir("dup");
  std::string text = small_scene(dir).dump(2);
  text.insert(text.find('{') + 1, "\n  \"duration\": 7.0,");
  std::ofstream(dir.str("s.json")) << text;
  const Outcome r = run({PAPERSIM, "run", dir.str("s.json"), "--out", dir.str("out"), "--quiet"});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "key 'duration' appears twice")) << r.err;
}

TEST(HostileInput, ScenarioSeedBeyondTheSceneRangeIsRefused) {
  Scratch dir("seed");
  const Outcome r = run({PAPERSIM, "scenario", "pull", "--seed", "2147483648", "--draw-only",
                         "--out", dir.str("out")});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "--seed")) << r.err;
  EXPECT_FALSE(fs::exists(dir.str("out")));
  const Outcome ok = run({PAPERSIM, "scenario", "pull", "--seed", "2147483647", "--draw-only",
                          "--out", dir.str("out")});
  ASSERT_EQ(ok.status, 0) << ok.err;
  json scene = json::parse(read_text(dir.str("out/scene.json")));
  scene["duration"] = 0.02;
  scene["sheet"]["edge_length"] = 0.03;
  const Outcome again =
      run({PAPERSIM, "run", write_scene(dir, "s.json", scene), "--out", dir.str("run"), "--quiet"});
  EXPECT_EQ(again.status, 0) << "the largest seed papersim draws must be one papersim runs: "
                             << again.err;
}

TEST(HostileInput, EmptyOutIsAUsageError) {
  Scratch dir("emptyout");
  const std::string scene = write_scene(dir, "s.json", small_scene(dir));
  const std::string mesh = example_sheet(dir, "flat", "flat.obj");
  const std::vector<std::vector<std::string>> commands = {
      {PAPERSIM, "run", scene, "--out", ""},
      {PAPERSIM, "scenario", "pull", "--seed", "1", "--out", ""},
      {PAPERSIM, "metrics", mesh, "--csv", ""},
      {SCENEGEN, "render", mesh, "--out", ""},
      {SCENEGEN, "prepare", mesh, "--out", ""},
      {SCENEGEN, "example", "flat", "--out", ""},
  };
  for (const auto& c : commands) {
    const Outcome r = run(c);
    EXPECT_EQ(r.status, 2) << c[1] << ": " << r.err;
    EXPECT_FALSE(contains(r.out, "wrote")) << r.out;
  }
}

TEST(HostileInput, ScenegenRefusesMalformedNumbers) {
  Scratch dir("numbers");
  const std::string mesh = example_sheet(dir, "flat", "flat.obj");
  const std::vector<std::vector<std::string>> bad = {{"--size", "128x180junk"},
                                                     {"--size", "128x"},
                                                     {"--size", "-8x8"},
                                                     {"--seed", "-1"},
                                                     {"--seed", "1.5"},
                                                     {"--threads", "-1"},
                                                     {"--dpi", "0"},
                                                     {"--backward-grid", "12x3y"}};
  for (const auto& option : bad) {
    const Outcome r =
        run({SCENEGEN, "prepare", mesh, "--out", dir.str("job"), option[0], option[1]});
    EXPECT_EQ(r.status, 2) << option[0] << " " << option[1] << ": " << r.err;
    EXPECT_TRUE(contains(r.err, option[0]) || contains(r.err, option[1])) << r.err;
    EXPECT_FALSE(fs::exists(dir.str("job")));
  }
  const Outcome p = run({SCENEGEN, "render", mesh, "--out", dir.str("out"), "--parallel", "-2"});
  EXPECT_EQ(p.status, 2) << p.err;
}

TEST(HostileInput, TruncatedObjIsRefused) {
  Scratch dir("truncated");
  const std::string mesh = example_sheet(dir, "flat", "flat.obj");
  const int faces = count_lines_starting(mesh, "f ");
  const int lines = count_lines_starting(mesh, "");
  keep_lines(mesh, lines - faces / 2);  // half the faces cut off
  const Outcome s = run({SCENEGEN, "prepare", mesh, "--out", dir.str("job")});
  EXPECT_EQ(s.status, 2) << s.err;
  EXPECT_TRUE(contains(s.err, "used by no face")) << s.err;
  const Outcome p = run({PAPERSIM, "metrics", mesh});
  EXPECT_EQ(p.status, 2) << p.err;
  EXPECT_TRUE(contains(p.err, "used by no face")) << p.err;
}

// --- 6: unbounded ---------------------------------------------------------------------------

TEST(HostileInput, HugeImageSizeIsRefusedUpFront) {
  Scratch dir("hugesize");
  const std::string mesh = example_sheet(dir, "flat", "flat.obj");
  const Outcome r =
      run({SCENEGEN, "render", mesh, "--out", dir.str("out"), "--size", "100000x100000"});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "limit of 8192")) << r.err;
  EXPECT_LT(r.seconds, 5.0);
  EXPECT_FALSE(fs::exists(dir.str("out")));
}

TEST(HostileInput, MeshBeyondTheVertexLimitIsRefusedUpFront) {
  Scratch dir("hugemesh");
  const std::string mesh = dir.str("big.obj");
  {
    std::ofstream out(mesh);
    out << "# papersim sheet 0.2 0.3\n";
    for (int i = 0; i < 500'001; ++i) out << "v 0 0 0\n";
  }
  const Outcome s = run({SCENEGEN, "prepare", mesh, "--out", dir.str("job")});
  EXPECT_EQ(s.status, 2);
  EXPECT_TRUE(contains(s.err, "250000 vertices (the limit)")) << s.err;
  const Outcome p = run({PAPERSIM, "metrics", mesh});
  EXPECT_EQ(p.status, 2);
  EXPECT_TRUE(contains(p.err, "500000 vertices")) << p.err;
}

TEST(HostileInput, TinyEdgeLengthIsRefusedWithTheVertexLimit) {
  Scratch dir("tinyedge");
  json scene = small_scene(dir);
  scene["sheet"]["edge_length"] = 1e-4;
  const Outcome r =
      run({PAPERSIM, "run", write_scene(dir, "s.json", scene), "--out", dir.str("out")});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "key 'sheet.edge_length'")) << r.err;
}

// --- 7: misleading messages and exit codes ----------------------------------------------

TEST(HostileInput, BadFaceIndexNamesFileAndLine) {
  Scratch dir("faceindex");
  const std::string mesh = example_sheet(dir, "flat", "flat.obj");
  const int lines = count_lines_starting(mesh, "");
  replace_line(mesh, lines - 1, "f 1/1 x/2 3/3");
  const Outcome r = run({PAPERSIM, "metrics", mesh});
  EXPECT_EQ(r.status, 2);
  EXPECT_FALSE(contains(r.err, "stoi")) << r.err;
  EXPECT_TRUE(contains(r.err, mesh + ":" + std::to_string(lines) + ": bad face index 'x'"))
      << r.err;
}

TEST(HostileInput, SheetMeshErrorsNameSceneFileAndKey) {
  Scratch dir("sheetmesh");
  json scene = small_scene(dir);
  scene["sheet"]["mesh"] = dir.str("missing.obj");
  const std::string path = write_scene(dir, "s.json", scene);
  const Outcome r = run({PAPERSIM, "run", path, "--out", dir.str("out")});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, path + ": key 'sheet.mesh': ")) << r.err;
}

TEST(HostileInput, ObstacleErrorsNameSceneFileAndKey) {
  Scratch dir("obstacle");
  json scene = small_scene(dir);
  scene["obstacles"] = json::array({{{"kind", "mesh"}, {"mesh", dir.str("missing.obj")}}});
  const std::string path = write_scene(dir, "s.json", scene);
  const Outcome r = run({PAPERSIM, "run", path, "--out", dir.str("out")});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, path + ": key 'obstacles[0]'")) << r.err;
}

TEST(HostileInput, FarAwaySheetIsOutOfRangeNotSelfIntersecting) {
  Scratch dir("far");
  json scene = small_scene(dir);
  scene["sheet"]["position"] = {1e300, 0, 0};
  const Outcome r =
      run({PAPERSIM, "run", write_scene(dir, "s.json", scene), "--out", dir.str("out")});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "key 'sheet.position'")) << r.err;
  EXPECT_FALSE(contains(r.err, "intersecting")) << r.err;
}

TEST(HostileInput, RangeErrorsPrintShortNumbers) {
  Scratch dir("range");
  json scene = small_scene(dir);
  scene["duration"] = 1e300;
  const Outcome r =
      run({PAPERSIM, "run", write_scene(dir, "s.json", scene), "--out", dir.str("out")});
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "value 1e+300 out of range")) << r.err;
  EXPECT_LT(r.err.size(), 200u) << r.err;
  // CLI11's NonNegativeNumber printed the largest double in full (309 digits).
  const Outcome frames = run({PAPERSIM, "run", write_scene(dir, "t.json", small_scene(dir)),
                              "--out", dir.str("out"), "--frames", "-1"});
  EXPECT_EQ(frames.status, 2);
  EXPECT_LT(frames.err.size(), 200u) << frames.err;
  // The batch runners' counts: the bad value named, nothing started.
  for (const auto& [args, message] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{PAPERSIM, "batch", "--out", dir.str("ds"), "--scenarios", "pull", "--seeds", "0-1",
             "--jobs", "-2"},
            "--jobs: Value -2 not in range 0 to 1024"},
           {{PAPERSIM, "batch", "--out", dir.str("ds"), "--scenarios", "pull", "--seeds", "0-1",
             "--time-limit", "nan"},
            "--time-limit: 'nan' is not a number"},
           {{SCENEGEN, "batch", dir.str("ds"), "--views", "0"},
            "--views: Value 0 not in range 1 to 1000"}}) {
    const Outcome b = run(args);
    EXPECT_EQ(b.status, 2) << b.err;
    EXPECT_TRUE(contains(b.err, message)) << b.err;
    EXPECT_LT(b.err.size(), 200u) << b.err;
  }
  EXPECT_FALSE(fs::exists(dir.str("ds")));
}

TEST(HostileInput, PovrayFailureDoesNotPointIntoADeletedFolder) {
  Scratch dir("povfail");
  const std::string mesh = example_sheet(dir, "flat", "flat.obj");
  const Outcome r = run({SCENEGEN, "render", mesh, "--out", dir.str("out"), "--size", "32x48",
                         "--povray", "/bin/false", "--quiet"});
  EXPECT_EQ(r.status, 6) << r.err;
  EXPECT_TRUE(contains(r.err, "POV-Ray failed")) << r.err;
  EXPECT_FALSE(contains(r.err, ".scenegen-job")) << r.err;
  EXPECT_FALSE(fs::exists(dir.str("out")));
}

// A file name or a --set value that is not UTF-8 (0xFF is never in UTF-8) made nlohmann::json
// refuse to dump meta.json, job.json, a metrics report or a manifest row: "internal error",
// exit status 1. A name is now written with U+FFFD in its place; a value that would go into a
// scene is refused.
TEST(HostileInput, NamesThatAreNotUtf8AreWrittenAndValuesRefused) {
  Scratch dir("utf8");
  const std::string name = "sheet\xff.obj", replaced = "sheet\xef\xbf\xbd.obj";
  const std::string mesh = example_sheet(dir, "flat", name);
  const Outcome prepare =
      run({SCENEGEN, "prepare", mesh, "--out", dir.str("job"), "--size", "32x48"});
  ASSERT_EQ(prepare.status, 0) << prepare.err;
  const json job = json::parse(read_text(dir.str("job") + "/job.json"));
  EXPECT_EQ(job["meta"]["mesh"]["file"], replaced);

  const Outcome metrics = run({PAPERSIM, "metrics", mesh, "--json"});
  ASSERT_EQ(metrics.status, 0) << metrics.err;
  const json report = json::parse(metrics.out);
  ASSERT_EQ(report["meshes"].size(), 1u);
  EXPECT_TRUE(contains(report["meshes"][0]["path"].get<std::string>(), replaced))
      << report["meshes"][0]["path"];

  const Outcome batch = run({PAPERSIM, "batch", "--out", dir.str("ds"), "--scenarios", "pull",
                             "--seeds", "0", "--set", "name=page\xff", "--quiet"});
  EXPECT_EQ(batch.status, 2) << batch.err;
  EXPECT_TRUE(contains(batch.err, "--set 'name=page\xff': not UTF-8")) << batch.err;
  EXPECT_FALSE(fs::exists(dir.str("ds")));
}

TEST(HostileInput, CommandLineErrorsExitWithStatus2AndHelpWith0) {
  for (const std::string& program : {PAPERSIM, SCENEGEN}) {
    EXPECT_EQ(run({program}).status, 2) << program;
    EXPECT_EQ(run({program, "no-such-command"}).status, 2) << program;
    EXPECT_EQ(run({program, "example", "--no-such-option"}).status, 2) << program;
    const Outcome help = run({program, "--help"});
    EXPECT_EQ(help.status, 0) << program;
    EXPECT_TRUE(contains(help.out, "Exit status: 0 success")) << help.out;
  }
}

}  // namespace
}  // namespace papersim::test
