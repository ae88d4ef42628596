// Mix files, scene overrides, seed ranges and dataset statistics of papersim batch.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "batch/dataset_stats.hpp"
#include "batch/runner.hpp"
#include "parsed_rows.hpp"
#include "simulation/batch.hpp"
#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"

namespace fs = std::filesystem;
namespace ps = papersim::simulation;
using nlohmann::json;

namespace {

/// The message of the SceneError `f` throws ("" when it does not throw).
template <class F>
std::string scene_error(F f) {
  try {
    f();
  } catch (const ps::SceneError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Overrides, SetDottedKeysAndRefuseUnknownOnesByName) {
  const ps::Scene base = ps::make_scenario("pull", 3);
  const ps::Scene s = ps::apply_overrides(
      base, ps::parse_overrides({"duration=0.2", "sheet.edge_length=0.02"}), "--set");
  EXPECT_EQ(s.duration, 0.2);
  EXPECT_EQ(s.sheet.edge_length, 0.02);
  EXPECT_EQ(s.time_step, base.time_step);
  EXPECT_NE(scene_error([&] {
              ps::apply_overrides(base, ps::parse_overrides({"sheet.edge_lenght=0.02"}), "--set");
            }).find("sheet.edge_lenght"),
            std::string::npos);
  EXPECT_NE(scene_error([&] {
              ps::apply_overrides(base, ps::parse_overrides({"duration=-1"}), "--set");
            }).find("duration"),
            std::string::npos);
  EXPECT_NE(scene_error([] { ps::parse_overrides({"duration"}); }).find("KEY=VALUE"),
            std::string::npos);
  // A key written to scene files only when not at its default can be set too.
  EXPECT_EQ(base.sheet.material.membrane_model, ps::MembraneModel::chord);
  EXPECT_EQ(
      ps::apply_overrides(base, ps::parse_overrides({"sheet.material.membrane_model=arc"}), "--set")
          .sheet.material.membrane_model,
      ps::MembraneModel::arc);
}

TEST(Mix, ParsesWeightsAndOverridesAndRefusesBadKeys) {
  const ps::Mix m = ps::mix_from_json(
      json::parse(
          R"({"scenarios": {"pull": 3, "fall-sphere": {"weight": 1, "set": {"duration": 0.5}}},
                      "set": {"sheet.edge_length": 0.01}})"),
      "mix.json");
  ASSERT_EQ(m.scenarios.size(), 2u);
  const std::size_t pull = m.scenarios[0] == "pull" ? 0 : 1;
  EXPECT_EQ(m.scenarios[1 - pull], "fall-sphere");
  EXPECT_EQ(m.weights[pull], 3.0);
  EXPECT_EQ(m.overrides[pull], json::object());
  EXPECT_EQ(m.overrides[1 - pull]["duration"], 0.5);
  EXPECT_EQ(m.common["sheet.edge_length"], 0.01);
  EXPECT_NE(scene_error([] {
              ps::mix_from_json(json::parse(R"({"scenarios": {"pul": 1}})"), "m.json");
            }).find("pul"),
            std::string::npos);
  EXPECT_NE(scene_error([] {
              ps::mix_from_json(json::parse(R"({"scenarios": {"pull": 0}})"), "m.json");
            }).find("weight"),
            std::string::npos);
  EXPECT_NE(scene_error([] {
              ps::mix_from_json(json::parse(R"({"scenario": {"pull": 1}})"), "m.json");
            }).find("scenario"),
            std::string::npos);
  // Each weight finite, their sum not: every seed drew the last scenario.
  EXPECT_NE(scene_error([] {
              ps::mix_from_json(json::parse(R"({"scenarios": {"pull": 1e308, "fold": 1e308}})"),
                                "m.json");
            }).find("the weights add up to more than the largest number"),
            std::string::npos);
  // Just below that, the draw still splits them.
  const ps::Mix big =
      ps::mix_from_json(json::parse(R"({"scenarios": {"pull": 8e307, "fold": 8e307}})"), "m.json");
  std::set<std::size_t> picked;
  for (std::uint64_t seed = 0; seed < 64; ++seed) picked.insert(ps::mix_pick(big, seed));
  EXPECT_EQ(picked.size(), 2u);
}

TEST(Mix, DrawsScenariosInProportionToTheirWeights) {
  ps::Mix m;
  m.scenarios = {"pull", "fall-sphere"};
  m.weights = {3, 1};
  m.overrides = {json::object(), json::object()};
  int pulls = 0;
  const int n = 20000;
  for (int seed = 0; seed < n; ++seed)
    pulls += ps::mix_pick(m, static_cast<std::uint64_t>(seed)) == 0;
  // Binomial(20000, 0.75): standard deviation 61; 5 sigma.
  EXPECT_NEAR(pulls, 0.75 * n, 5 * 61.2);
  EXPECT_EQ(ps::mix_pick(m, 12345), ps::mix_pick(m, 12345));
}

TEST(Selection, ProductOfScenariosAndSeedsWithFoldersPerSeed) {
  ps::MeshBatchSelection sel;
  sel.scenarios = {"pull", "fall-gable"};
  sel.seeds = {ps::parse_seed_range("998-1001")};
  const auto draws = ps::draw_samples(sel);
  ASSERT_EQ(draws.size(), 8u);
  EXPECT_EQ(draws[1].scenario, "fall-gable");
  EXPECT_EQ(draws[1].seed, 998u);
  const auto tasks = ps::mesh_tasks(draws);
  EXPECT_EQ(tasks[0].key, "meshes/pull/0/998");
  EXPECT_EQ(tasks[0].info_object(), (json{{"scenario", "pull"}, {"seed", 998}}));
  EXPECT_EQ(tasks[7].key, "meshes/fall-gable/1/1001");
  for (const char* bad : {"5-1", "a-3", "-3", "1-", ""})
    EXPECT_NE(scene_error([&] { ps::parse_seed_range(bad); }).find("--seeds"), std::string::npos)
        << bad;
}

// mesh_tasks writes each task's fields as text put together from pieces dumped once per run of
// draws: it must be the text of the object {scenario, seed, set (when there are overrides)},
// whatever the order of scenarios and shared or separate overrides.
TEST(Selection, EachTasksFieldsAreTheTextOfItsObject) {
  const auto some = std::make_shared<const json>(
      json{{"duration", 0.05}, {"sheet.edge_length", 0.04}, {"name", "q\"\\ \u00e9\n"}});
  const auto other = std::make_shared<const json>(json{{"duration", 0.5}});
  const auto none = std::make_shared<const json>(json::object());
  const std::uint64_t top = std::numeric_limits<std::uint64_t>::max();
  std::vector<ps::SampleDraw> draws;
  for (const auto& [scenario, seed, overrides] :
       std::vector<std::tuple<std::string, std::uint64_t, std::shared_ptr<const json>>>{
           {"pull", 0, nullptr},
           {"pull", 1, some},
           {"pull", 2, some},
           {"fall-sphere", 2, some},
           {"fall-sphere", 999, other},
           {"pull", 1000, other},
           {"pull", 1001, none},
           {"fold", top, nullptr},
           {"fold", 7, some}}) {
    ps::SampleDraw d;
    d.scenario = scenario;
    d.seed = seed;
    d.overrides = overrides;
    draws.push_back(d);
  }
  const auto tasks = ps::mesh_tasks(draws);
  ASSERT_EQ(tasks.size(), draws.size());
  for (std::size_t i = 0; i < draws.size(); ++i) {
    json expected = {{"scenario", draws[i].scenario}, {"seed", draws[i].seed}};
    if (draws[i].overrides && !draws[i].overrides->empty()) expected["set"] = *draws[i].overrides;
    EXPECT_EQ(tasks[i].info, expected.dump()) << i;
    EXPECT_EQ(tasks[i].info_object(), expected) << i;
    EXPECT_EQ(tasks[i].key, "meshes/" + draws[i].scenario + "/" +
                                std::to_string(draws[i].seed / 1000) + "/" +
                                std::to_string(draws[i].seed));
  }
}

TEST(Selection, SeedListsDrawTheirSeedsInOrderAndRefuseOverlaps) {
  using Ranges = std::vector<std::pair<std::uint64_t, std::uint64_t>>;
  EXPECT_EQ(ps::parse_seeds("3,7,12-13"), (Ranges{{3, 3}, {7, 7}, {12, 13}}));
  EXPECT_EQ(ps::parse_seeds("0-999999"), (Ranges{{0, 999999}}));
  ps::MeshBatchSelection sel;
  sel.scenarios = {"pull"};
  sel.seeds = ps::parse_seeds("12-13,3");
  const auto draws = ps::draw_samples(sel);
  ASSERT_EQ(draws.size(), 3u);
  EXPECT_EQ(draws[0].seed, 12u);
  EXPECT_EQ(draws[1].seed, 13u);
  EXPECT_EQ(draws[2].seed, 3u);
  // Each refusal names the option and the part at fault.
  for (const auto& [bad, part] :
       std::vector<std::pair<std::string, std::string>>{{"3,,7", "''"},
                                                        {"3,7-5", "'7-5'"},
                                                        {"1-10,5", "'5'"},
                                                        {"4,2-4", "'2-4'"},
                                                        {"3,x", "'x'"}}) {
    const std::string& seeds = bad;  // a lambda captures it (not a structured binding)
    const std::string e = scene_error([&] { ps::parse_seeds(seeds); });
    EXPECT_NE(e.find("--seeds"), std::string::npos) << bad << ": " << e;
    EXPECT_NE(e.find(part), std::string::npos) << bad << ": " << e;
  }
}

// An array task draws only its shard's samples: the same slice, task for task, as the shard
// taken from the whole selection's tasks (select_shard), with a mix and with scenarios. The tasks
// written while drawing (mesh_tasks of the selection, as a batch makes them) are those of the
// draws kept.
TEST(Selection, AShardDrawnDirectlyIsTheSliceOfTheWholeSelection) {
  for (const bool mix : {false, true}) {
    ps::MeshBatchSelection sel;
    if (mix)
      sel.mix_path = TINY_MIX;
    else
      sel.scenarios = {"pull", "fall-gable", "fold"};
    sel.seeds = ps::parse_seeds("3-9,20,100-104");
    sel.overrides = {{"duration", 0.05}};
    const auto all = ps::mesh_tasks(ps::draw_samples(sel));
    ASSERT_EQ(all.size(), mix ? 13u : 39u);
    for (int count : {1, 2, 5, 40})
      for (int index = 0; index < count; ++index) {
        sel.shard = {index, count};
        const auto direct = ps::mesh_tasks(ps::draw_samples(sel));
        const auto streamed = ps::mesh_tasks(sel);
        EXPECT_EQ(ps::count_samples(sel), direct.size());
        const auto sliced = papersim::batch::select_shard(all, index, count);
        ASSERT_EQ(direct.size(), sliced.size()) << index << "/" << count;
        ASSERT_EQ(streamed.size(), sliced.size()) << index << "/" << count;
        for (std::size_t i = 0; i < direct.size(); ++i) {
          EXPECT_EQ(direct.key(i), sliced.key(i));
          EXPECT_EQ(direct.info(i), sliced.info(i));
          EXPECT_EQ(streamed.key(i), sliced.key(i));
          EXPECT_EQ(streamed.info(i), sliced.info(i));
        }
      }
  }
}

// Drawing the samples tells its progress every 65,536 samples, with the shard's share of the
// selection as the total, and the tasks are those drawn without it.
TEST(Selection, DrawingTellsHowManySamplesAreDrawnOfHowMany) {
  ps::MeshBatchSelection sel;
  sel.scenarios = {"pull", "fall-gable"};
  sel.seeds = ps::parse_seeds("0-99999");
  for (int count : {1, 2}) {
    sel.shard = {0, count};
    std::vector<std::pair<double, double>> told;
    const auto tasks = ps::mesh_tasks(
        sel, [&told](const std::string& what, double done, double total, const std::string& unit) {
          EXPECT_EQ(what, "drawing the samples");
          EXPECT_EQ(unit, "samples");
          told.emplace_back(done, total);
        });
    ASSERT_EQ(tasks.size(), 200000u / count);
    ASSERT_EQ(told.size(), tasks.size() / 65536);  // 3 of 200,000; 1 of 100,000
    for (std::size_t i = 0; i < told.size(); ++i) {
      EXPECT_EQ(told[i].first, 65536.0 * (i + 1));
      EXPECT_EQ(told[i].second, 200000.0 / count);
    }
    const auto quiet = ps::mesh_tasks(sel);
    ASSERT_EQ(quiet.size(), tasks.size());
    EXPECT_EQ(quiet.key(tasks.size() - 1), tasks.key(tasks.size() - 1));
  }
}

// A batch command draws every sample before the first runs, so a selection of more than
// MAX_BATCH_SAMPLES is refused before any is drawn: a typo of ten billion seeds, seed ranges whose
// sum passes the bound, and two scenarios that double a range below it. Each is refused at once.
TEST(Selection, MoreSamplesThanOneCommandDrawsAreRefusedBeforeAnyIsDrawn) {
  const std::uint64_t max = ps::MAX_BATCH_SAMPLES;
  const std::uint64_t top = std::numeric_limits<std::uint64_t>::max();
  for (const auto& [scenarios, seeds] :
       std::vector<std::pair<std::vector<std::string>,
                             std::vector<std::pair<std::uint64_t, std::uint64_t>>>>{
           {{"pull"}, {{0, 9999999999u}}},
           {{"pull"}, {{0, top}}},
           {{"pull"}, {{0, max / 2 - 1}, {max, max + max / 2}}},
           {{"pull", "fold"}, {{0, max / 2}}}}) {
    ps::MeshBatchSelection sel;
    sel.scenarios = scenarios;
    sel.seeds = seeds;
    const auto start = std::chrono::steady_clock::now();
    const std::string e = scene_error([&] { ps::draw_samples(sel); });
    EXPECT_NE(e.find("--seeds: more than 10000000 samples"), std::string::npos) << e;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
  }
  // The largest seed alone is one sample.
  ps::MeshBatchSelection one;
  one.scenarios = {"pull"};
  one.seeds = {{top, top}};
  EXPECT_EQ(ps::draw_samples(one).size(), 1u);
}

// With checkpoints, a running sample's share done is its last checkpoint's time over the
// scene's duration; without one (or without checkpoints) it is unknown.
TEST(MeshBatch, ARunningSamplesShareIsItsLastCheckpointsTime) {
  const fs::path root = fs::temp_directory_path() / ("papersim_share_" + std::to_string(getpid()));
  fs::remove_all(root);
  papersim::batch::Task t;
  t.key = "meshes/fold/0/3";
  EXPECT_FALSE(ps::mesh_batch_spec(root, "papersim", false).running_share);
  const auto spec = ps::mesh_batch_spec(root, "papersim", false, 5);
  ASSERT_TRUE(spec.running_share);
  EXPECT_LT(spec.running_share(t), 0.0);
  const fs::path dir = ps::checkpoint_folder(root, t);
  EXPECT_EQ(dir, root / ".checkpoints" / "meshes_fold_0_3");
  fs::create_directories(dir);
  std::ofstream(dir / "checkpoint.json")
      << R"({"step": 410, "time": 4.1, "scene": {"duration": 10.0}})";
  EXPECT_DOUBLE_EQ(spec.running_share(t), 0.41);
  std::ofstream(dir / "checkpoint.json") << R"({"step": 410, "time": "4.1"})";  // not one of ours
  EXPECT_LT(spec.running_share(t), 0.0);
  fs::remove_all(root);
}

// A sample's manifest fields come from its meta.json and metrics.json; a file that is not theirs
// (missing, not JSON, a part missing or of another type) is named, with what is wrong, so that a
// batch restoring the row can say which sample folder is damaged.
TEST(MeshBatch, ManifestFieldsNameTheFileTheyCannotBeMadeFrom) {
  const fs::path dir = fs::temp_directory_path() / ("papersim_fields_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "meta.json") << R"({"run": {"steps": 20, "newton_iterations": 41,
      "wall_seconds": 0.25}, "quality": {"max_principal_stretch": 1.002, "self_intersections": 0,
      "min_obstacle_distance": [0.3, 0.1, null]}, "sheet": {"vertices": 682}})";
  std::ofstream(dir / "metrics.json") << R"({"meshes": [{"metrics": {"creases":
      {"total_length": 0.12}, "developability": {"angle_defect_integral": 0.5}}}]})";
  const json f = ps::mesh_manifest_fields(dir);
  EXPECT_EQ(f["vertices"], 682);
  EXPECT_EQ(f["steps"], 20);
  EXPECT_EQ(f["newton_iterations"], 41);
  EXPECT_EQ(f["sim_wall_seconds"], 0.25);
  EXPECT_EQ(f["max_stretch"], 1.002);
  EXPECT_EQ(f["closest_obstacle_distance"], 0.1);
  EXPECT_EQ(f["self_intersections"], 0);
  EXPECT_EQ(f["crease_length"], 0.12);
  EXPECT_EQ(f["abs_curvature_integral"], 0.5);
  const auto refused = [&dir](const std::string& meta, const std::string& metrics,
                              const std::string& file, const std::string& what) {
    if (!meta.empty()) std::ofstream(dir / "meta.json") << meta;
    if (metrics.empty()) {
      fs::remove(dir / "metrics.json");
    } else {
      std::ofstream(dir / "metrics.json") << metrics;
    }
    try {
      ps::mesh_manifest_fields(dir);
      ADD_FAILURE() << meta << " " << metrics << " was taken";
    } catch (const std::runtime_error& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("'" + (dir / file).string() + "'"), std::string::npos) << m;
      EXPECT_NE(m.find(what), std::string::npos) << m;
    }
  };
  const std::string parts = R"({"run": {}, "quality": {}, "sheet": {}})";
  refused("{", "", "meta.json", "is not valid JSON");
  refused("[1]", "", "meta.json", "has no object \"run\"");
  refused(R"({"run": {}, "quality": [], "sheet": {}})", "", "meta.json",
          "has no object \"quality\"");
  refused(R"({"run": {}, "quality": {}, "sheet": 3})", "", "meta.json", "has no object \"sheet\"");
  refused(parts, "5", "metrics.json", "holds no metrics object");
  refused(parts, R"({"creases": []})", "metrics.json", "has no object \"creases\"");
  refused(parts, R"({"meshes": [{"metrics": {"developability": 1}}]})", "metrics.json",
          "has no object \"developability\"");
  fs::remove(dir / "meta.json");
  refused("", "", "meta.json", "cannot read");
  // Counts of another type are unknown, not a failure: the fields of a partial meta.json.
  std::ofstream(dir / "meta.json") << R"({"run": {"steps": "x"}, "quality": {}, "sheet": {}})";
  fs::remove(dir / "metrics.json");
  const json partial = ps::mesh_manifest_fields(dir);
  EXPECT_EQ(partial["steps"], 0);
  EXPECT_EQ(partial["max_stretch"], -1);
  EXPECT_TRUE(partial["crease_length"].is_null());
  fs::remove_all(dir);
}

TEST(DatasetStats, CountsLatestStatePerSampleAndQuantiles) {
  const fs::path root = fs::temp_directory_path() / ("papersim_stats_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  for (int i = 0; i < 5; ++i)
    papersim::batch::append_line(
        root / "manifest.jsonl",
        json{{"key", "p" + std::to_string(i)}, {"scenario", "pull"}, {"wall_seconds", i + 1.0}}
            .dump());
  papersim::batch::append_line(
      root / "manifest.jsonl",
      json{{"key", "p0"}, {"scenario", "pull"}, {"wall_seconds", 99.0}}.dump());
  papersim::batch::append_line(
      root / "failures.jsonl",
      json{{"key", "p1"}, {"scenario", "pull"}, {"reason", "time limit"}}.dump());
  papersim::batch::append_line(
      root / "failures.jsonl",
      json{{"key", "f0"}, {"scenario", "fall-sphere"}, {"reason", "time limit"}}.dump());
  papersim::batch::append_line(
      root / "failures.jsonl",
      json{{"key", "f1"}, {"scenario", "fall-sphere"}, {"reason", "simulation failed"}}.dump());
  const auto parts = papersim::batch::read_dataset(root);
  ASSERT_EQ(parts.size(), 1u);
  const auto& p = parts[0];
  EXPECT_EQ(p.done.at("pull"), 5);
  EXPECT_EQ(p.failed.count("pull"), 0u) << "a failure later finished counts as done";
  EXPECT_EQ(p.failed.at("fall-sphere"), 2);
  EXPECT_EQ(p.reasons.at("time limit"), 1);
  EXPECT_EQ(p.failed_attempts, 3);
  const auto d = papersim::batch::distribution(p.values.at("wall_seconds").at("pull").to_vector());
  EXPECT_EQ(d.count, 5u);  // the duplicate row counts once
  EXPECT_DOUBLE_EQ(d.median, 3.0);
  EXPECT_DOUBLE_EQ(d.p90, 4.6);
  EXPECT_DOUBLE_EQ(d.sum, 15.0);
  fs::remove_all(root);
}

// The quantiles come from order statistics selected, not sorted: the same values as from the
// sorted vector (exactly: the same two values interpolated by the same formula), with ties and
// at every small size; the sum in the order read within rounding of the sorted sum.
TEST(DatasetStats, DistributionIsThatOfTheSortedValues) {
  std::mt19937_64 rng(7);
  for (std::size_t n : {1, 2, 3, 4, 5, 9, 10, 11, 19, 20, 21, 100, 1001, 100000}) {
    for (int ties : {0, 1}) {
      std::vector<double> v(n);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      for (double& x : v) x = ties ? std::floor(4 * u(rng)) : std::exp(5 * u(rng));
      std::vector<double> s = v;
      std::sort(s.begin(), s.end());
      const auto q = [&s](double p) {
        const double pos = p * static_cast<double>(s.size() - 1);
        const auto i = static_cast<std::size_t>(std::floor(pos));
        const std::size_t j = std::min(i + 1, s.size() - 1);
        return s[i] + (pos - static_cast<double>(i)) * (s[j] - s[i]);
      };
      const auto d = papersim::batch::distribution(v);
      EXPECT_EQ(d.count, n);
      EXPECT_EQ(d.min, s.front()) << n;
      EXPECT_EQ(d.max, s.back()) << n;
      EXPECT_EQ(d.p10, q(0.1)) << n << " " << ties;
      EXPECT_EQ(d.median, q(0.5)) << n << " " << ties;
      EXPECT_EQ(d.p90, q(0.9)) << n << " " << ties;
      double sum = 0, size = 0;
      for (double x : s) {
        sum += x;
        size += std::abs(x);
      }
      EXPECT_NEAR(d.sum, sum, 1e-15 * static_cast<double>(n) * size) << n;
      EXPECT_DOUBLE_EQ(d.mean, d.sum / static_cast<double>(n));
    }
  }
}

// The plots appear whole or not at all: with gnuplot at hand every SVG, its data and the script
// are in the folder and no staging folder is left; with no gnuplot on the PATH the call fails
// and the folder holds only what it held before.
TEST(DatasetStats, PlotsAppearWholeOrNotAtAll) {
  const fs::path root =
      fs::temp_directory_path() / ("papersim_stats_plots_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  for (int i = 0; i < 5; ++i)
    papersim::batch::append_line(
        root / "manifest.jsonl",
        json{{"key", "p" + std::to_string(i)}, {"scenario", "pull"}, {"wall_seconds", i + 1.0}}
            .dump());
  const auto parts = papersim::batch::read_dataset(root);
  const auto names = [](const fs::path& dir) {
    std::set<std::string> n;
    for (const auto& e : fs::directory_iterator(dir)) n.insert(e.path().filename().string());
    return n;
  };

  const fs::path failed = root / "failed";
  fs::create_directories(failed);
  std::ofstream(failed / "kept.txt") << "from before\n";
  const char* path = std::getenv("PATH");
  const std::string saved = path ? path : "";
  ::setenv("PATH", "/nonexistent", 1);
  EXPECT_THROW(papersim::batch::write_dataset_plots(failed, parts), papersim::batch::GnuplotError);
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_EQ(names(failed), (std::set<std::string>{"kept.txt"}));

  if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) GTEST_SKIP() << "no gnuplot";
  const fs::path plots = root / "plots";
  const auto written = papersim::batch::write_dataset_plots(plots, parts);
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(names(plots), (std::set<std::string>{"meshes_wall_seconds.dat",
                                                 "meshes_wall_seconds.svg", "stats.gp"}));
  std::ifstream svg(written[0]);
  std::stringstream text;
  text << svg.rdbuf();
  EXPECT_NE(text.str().find("</svg>"), std::string::npos);
  // A file where the folder should be: an output error naming it, and the file left alone.
  EXPECT_THROW(papersim::batch::write_dataset_plots(root / "manifest.jsonl", parts),
               papersim::batch::PlotsOutputError);
  EXPECT_EQ(papersim::batch::read_dataset(root).at(0).done.at("pull"), 5);
  fs::remove_all(root);
}

// Lines that are not a JSON object with a string key (a line cut short by a killed writer, a
// hand edit) are left out and counted, never a crash; a dataset path that is not a folder is a
// DatasetError.
TEST(DatasetStats, LeavesOutAndCountsMalformedLines) {
  const fs::path root =
      fs::temp_directory_path() / ("papersim_stats_bad_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  std::ofstream(root / "manifest.jsonl")
      << "{\"key\": \"a\", \"scenario\": \"pull\", \"wall_seconds\": 1}\n"
      << "{\"key\": 5, \"scenario\": \"pull\"}\n"
      << "{\"key\": \"b\", \"scenario\": 7}\n"
      << "[1, 2]\n\n{\"key\": \"c\", \"scen";
  std::ofstream(root / "failures.jsonl")
      << "{\"key\": \"d\", \"scenario\": \"pull\", \"reason\": 3}\n";
  const auto parts = papersim::batch::read_dataset(root);
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].done.at("pull"), 1);
  EXPECT_EQ(parts[0].failed_attempts, 0);
  EXPECT_EQ(parts[0].skipped_lines, 5);
  std::ostringstream report;
  papersim::batch::write_dataset_report(report, parts);
  EXPECT_NE(report.str().find("5 lines left out"), std::string::npos) << report.str();
  EXPECT_THROW(papersim::batch::read_dataset(root / "manifest.jsonl"),
               papersim::batch::DatasetError);
  fs::remove_all(root);
}

// A manifest that is a folder (or a FIFO) was read as no rows: "0 done", exit 0.
TEST(DatasetStats, AManifestThatIsNotAFileIsNamed) {
  const fs::path root =
      fs::temp_directory_path() / ("papersim_stats_dir_" + std::to_string(getpid()));
  for (const char* name : {"manifest.jsonl", "failures.jsonl", "renders.jsonl"}) {
    fs::remove_all(root);
    fs::create_directories(root / name);
    try {
      papersim::batch::read_dataset(root);
      ADD_FAILURE() << name << " was read";
    } catch (const papersim::batch::DatasetError& e) {
      EXPECT_EQ(std::string(e.what()), "'" + (root / name).string() + "' is not a file");
    }
  }
  fs::remove_all(root);
}

// The report reads each row as a stream of JSON events and keeps only its key, scenario, reason
// and figures. On rows written to catch a reader that looks at the wrong level or the wrong
// occurrence, it must give exactly what parsing every row into a JSON object gives: a name given
// twice takes its last value, a "key" inside a nested object is not the row's key, escapes are
// decoded, a figure that is not a number (a string, a bool, null, an object) is left out, and a
// line with trailing text, a top-level array or string, or a line cut short is left out and
// counted.
TEST(DatasetStats, StreamedRowsGiveWhatParsingEveryRowGives) {
  const fs::path root =
      fs::temp_directory_path() / ("papersim_stats_stream_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  const std::vector<std::string> manifest = {
      R"({"key": "a", "scenario": "pull", "wall_seconds": 1, "vertices": 100})",
      R"({"key": "a", "scenario": "pull", "wall_seconds": 50})",           // a duplicate
      R"({"key": 5, "key": "b", "scenario": "fold", "wall_seconds": 2})",  // last "key" wins
      R"({"key": "c", "key": 5, "scenario": "fold", "wall_seconds": 3})",  // last is a number
      R"({"meta": {"key": "d", "scenario": "x"}, "key": "e", "scenario": "fold"})",  // nested names
      R"({"meta": {"key": "f"}, "scenario": "fold"})",                               // only nested
      R"({"key": "g\/h\u0041", "scenario": "fo\"ld", "wall_seconds": 4.5e0})",       // escapes
      R"({"key": "i", "scenario": "pull", "wall_seconds": "7", "cpu_seconds": true, "vertices": null})",
      R"({"key": "j", "scenario": "pull", "wall_seconds": {"s": 1}, "cpu_seconds": [1, 2], "vertices": 18446744073709551615})",
      R"({"key": "k", "scenario": "pull", "wall_seconds": 8, "wall_seconds": "x", "cpu_seconds": "x", "cpu_seconds": -3})",
      R"({"key": "l", "scenario": null})",
      R"({"key": "m", "scenario": ["pull"]})",
      R"({"key": "n"})",  // no scenario
      R"({"key": "o", "scenario": "pull"} trailing)",
      R"(["key", "p"])",
      R"("key")",
      "{\"key\": \"q\", \"scenario\": \"pull\", \"newton_iterations\": 12}\r",  // CRLF
      "   ",
      R"({"key": "r", "scenario": "pull", "wall_sec)"};
  const std::vector<std::string> failures = {
      R"({"key": "b", "scenario": "fold", "reason": "time limit"})",  // done later
      R"({"key": "s", "scenario": "fold", "reason": "time limit"})",
      R"({"key": "s", "scenario": "fold", "reason": "simulation failed"})",  // the latest counts
      R"({"key": "t", "scenario": "fold"})",                                 // no reason
      R"({"key": "u", "scenario": "fold", "reason": {"r": "x"}})",
      R"({"reason": "x", "nested": {"key": "v"}})"};
  for (const auto& [name, lines] :
       {std::pair{"manifest.jsonl", manifest}, std::pair{"failures.jsonl", failures}}) {
    std::ofstream out(root / name);
    for (const auto& l : lines) out << l << "\n";
  }

  // What parsing every row into a JSON object gives.
  const std::vector<std::string> figures = {"wall_seconds", "cpu_seconds", "vertices",
                                            "newton_iterations"};
  const auto joined = [](const std::vector<std::string>& lines) {
    std::string text;
    for (const auto& l : lines) text += l + "\n";
    return text;
  };
  const papersim::batch::PartStats want =
      papersim::batch::testing::parse_every_line(joined(manifest), joined(failures), figures);

  const auto got = papersim::batch::read_part("meshes", root / "manifest.jsonl",
                                              root / "failures.jsonl", figures);
  EXPECT_EQ(got.done, want.done);
  EXPECT_EQ(got.failed, want.failed);
  EXPECT_EQ(got.reasons, want.reasons);
  EXPECT_EQ(got.failed_attempts, want.failed_attempts);
  EXPECT_EQ(got.skipped_lines, want.skipped_lines);
  EXPECT_EQ(got.values, want.values);
  // And the figures themselves, so that the oracle above cannot hide a shared mistake.
  EXPECT_EQ(got.done,
            (std::map<std::string, long long>{{"pull", 5}, {"fold", 2}, {"fo\"ld", 1}, {"?", 1}}));
  EXPECT_EQ(got.skipped_lines, 10);  // 8 in the manifest, 2 in the failures
  EXPECT_EQ(got.values.at("wall_seconds"), (std::map<std::string, papersim::batch::FigureValues>{
                                               {"pull", {1}}, {"fold", {2}}, {"fo\"ld", {4.5}}}));
  EXPECT_EQ(got.values.at("cpu_seconds"),
            (std::map<std::string, papersim::batch::FigureValues>{{"pull", {-3}}}));
  EXPECT_EQ(got.values.at("vertices"), (std::map<std::string, papersim::batch::FigureValues>{
                                           {"pull", {100, 18446744073709551615.0}}}));
  EXPECT_EQ(got.values.at("newton_iterations"),
            (std::map<std::string, papersim::batch::FigureValues>{{"pull", {12}}}));
  EXPECT_EQ(got.failed, (std::map<std::string, long long>{{"fold", 2}}));
  EXPECT_EQ(got.reasons, (std::map<std::string, long long>{{"simulation failed", 1}, {"?", 1}}));
  EXPECT_EQ(got.failed_attempts, 4);
  fs::remove_all(root);
}

// The progress of a long read: told every 4,096 lines the bytes read so far (exactly those of the
// lines before) of the total size of the dataset's files.
TEST(DatasetStats, ReadingTellsItsProgressInBytes) {
  const fs::path root =
      fs::temp_directory_path() / ("papersim_stats_progress_" + std::to_string(getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  std::vector<std::uintmax_t> ends;  // byte offset after each line
  std::uintmax_t at = 0;
  {
    std::ofstream out(root / "manifest.jsonl");
    for (int i = 0; i < 10000; ++i) {
      const std::string line = json{{"key", "k" + std::to_string(i)}, {"scenario", "pull"}}.dump();
      out << line << '\n';
      ends.push_back(at += line.size() + 1);
    }
  }
  std::ofstream(root / "renders.jsonl") << R"({"key": "r", "scenario": "pull"})" << '\n';
  const std::uintmax_t total =
      fs::file_size(root / "manifest.jsonl") + fs::file_size(root / "renders.jsonl");
  std::vector<std::pair<std::uintmax_t, std::uintmax_t>> told;
  const auto parts = papersim::batch::read_dataset(
      root, [&](std::uintmax_t read, std::uintmax_t of) { told.emplace_back(read, of); });
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].done.at("pull"), 10000);
  ASSERT_EQ(told.size(), 2u);
  EXPECT_EQ(told[0], std::make_pair(ends[4095], total));
  EXPECT_EQ(told[1], std::make_pair(ends[8191], total));
  fs::remove_all(root);
}
