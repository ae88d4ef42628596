// scenegen batch's task list: one task per (finished mesh, view), and an array task's shard made
// directly is the same slice as the shard taken from the whole list (so each array task holds
// only its own tasks in memory). A mesh list written once gives every array task the same tasks
// without a walk over the dataset, and a malformed one is refused naming its line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <fstream>
#include <functional>
#include <set>

#include "common/errors.hpp"
#include "scenegen/batch.hpp"
#include "scenegen/errors.hpp"

namespace fs = std::filesystem;
namespace sg = papersim::scenegen;

namespace {

void add_mesh(const fs::path& root, const std::string& scenario, int seed) {
  const fs::path d =
      root / "meshes" / scenario / std::to_string(seed / 1000) / std::to_string(seed);
  fs::create_directories(d);
  std::ofstream(d / "sheet.obj") << "";
}

/// A dataset of 7 finished meshes of two scenarios (sheet.obj present) and one unfinished (none).
fs::path small_dataset(const std::string& name) {
  const fs::path root =
      fs::temp_directory_path() / ("papersim_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(root);
  for (const auto& [scenario, seed] : std::vector<std::pair<std::string, int>>{{"pull", 0},
                                                                               {"pull", 1},
                                                                               {"pull", 1005},
                                                                               {"fold", 2},
                                                                               {"fold", 3},
                                                                               {"fold", 999},
                                                                               {"fold", 4000}})
    add_mesh(root, scenario, seed);
  fs::create_directories(root / "meshes" / "pull" / "0" / "7");
  return root;
}

/// The message of the InputError `f` throws; "(no error)" when it throws none.
std::string input_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const sg::InputError& e) {
    return e.what();
  }
  return "(no error)";
}

void expect_same_tasks(const papersim::batch::TaskList& a, const papersim::batch::TaskList& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].key, b[i].key);
    EXPECT_EQ(a[i].info, b[i].info);
  }
}

}  // namespace

// render_tasks writes each view's fields as text from the mesh's dumped strings: it must be the
// text of the object nlohmann would dump, for any scenario folder name (quotes, backslashes,
// letters beyond ASCII).
TEST(RenderTasks, EachTasksFieldsAreTheTextOfItsObject) {
  const fs::path root = small_dataset("render_tasks_text");
  add_mesh(root, "q\"\\ \u00e9", 12);
  sg::RenderBatchOptions o;
  o.views = 3;
  o.flip = true;
  const auto tasks = sg::render_tasks(root, o);
  ASSERT_EQ(tasks.size(), 24u);
  std::size_t odd = 0;
  for (const auto& t : tasks) {
    const nlohmann::json info = t.info_object();
    EXPECT_EQ(t.info, info.dump()) << t.key;
    const std::string scenario = info.at("scenario");
    const std::uint64_t seed = info.at("seed");
    const int view = info.at("view");
    const std::string mesh =
        "meshes/" + scenario + "/" + std::to_string(seed / 1000) + "/" + std::to_string(seed);
    EXPECT_EQ(t.key, "renders/" + mesh.substr(7) + "/view" + std::to_string(view));
    EXPECT_EQ(info, (nlohmann::json{{"scenario", scenario},
                                    {"seed", seed},
                                    {"view", view},
                                    {"flipped", view % 2 == 1},
                                    {"render_seed", sg::view_seed(scenario, seed, view)},
                                    {"mesh", mesh + "/sheet.obj"}}))
        << t.key;
    odd += view % 2;
  }
  EXPECT_EQ(odd, 8u);
  EXPECT_EQ(tasks.back().info_object().at("scenario"), "q\"\\ \u00e9");
  fs::remove_all(root);
}

TEST(RenderTasks, AShardMadeDirectlyIsTheSliceOfTheWholeList) {
  const fs::path root = small_dataset("render_tasks");
  sg::RenderBatchOptions o;
  o.views = 3;
  const auto all = sg::render_tasks(root, o);
  ASSERT_EQ(all.size(), 21u);
  EXPECT_EQ(all.front().key, "renders/fold/0/2/view0");
  EXPECT_EQ(all.back().key, "renders/pull/1/1005/view2");
  for (int count : {1, 2, 4, 25})
    for (int index = 0; index < count; ++index) {
      const auto direct = sg::render_tasks(root, o, {index, count});
      const auto sliced = papersim::batch::select_shard(all, index, count);
      ASSERT_EQ(direct.size(), sliced.size()) << index << "/" << count;
      for (std::size_t i = 0; i < direct.size(); ++i) {
        EXPECT_EQ(direct[i].key, sliced[i].key);
        EXPECT_EQ(direct[i].info, sliced[i].info);
      }
    }
  fs::remove_all(root);
}

TEST(RenderTasks, AMeshListGivesTheWalksTasksAndLooksAtNoFolder) {
  const fs::path root = small_dataset("mesh_list");
  const fs::path list = root / "slurm" / "scenegen-batch.meshes";
  fs::create_directories(list.parent_path());
  // The walk reports after each bucket folder: pull/0 (with the unfinished mesh), pull/1,
  // fold/0 and fold/4.
  std::vector<std::array<std::size_t, 3>> heard;
  ASSERT_EQ(sg::write_mesh_list(root, list,
                                [&](std::size_t done, std::size_t buckets, std::size_t meshes) {
                                  heard.push_back({done, buckets, meshes});
                                }),
            7u);
  ASSERT_EQ(heard.size(), 4u);
  for (std::size_t i = 0; i < heard.size(); ++i) {
    EXPECT_EQ(heard[i][0], i + 1);
    EXPECT_EQ(heard[i][1], 4u);
    if (i > 0) {
      EXPECT_GE(heard[i][2], heard[i - 1][2]);
    }
  }
  EXPECT_EQ(heard.back()[2], 7u);
  EXPECT_FALSE(fs::exists(list.string() + ".tmp"));
  EXPECT_EQ(sg::mesh_list_size(list), 7u);
  // A list that cannot be written is an output error naming it, and leaves nothing.
  const fs::path nowhere = root / "missing_folder" / "list";
  try {
    sg::write_mesh_list(root, nowhere);
    ADD_FAILURE() << "wrote into a missing folder";
  } catch (const papersim::common::OutputError& e) {
    EXPECT_NE(std::string(e.what()).find(nowhere.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(root / "missing_folder"));
  sg::RenderBatchOptions o;
  o.views = 2;
  o.flip = true;
  const auto walked = sg::render_tasks(root, o);
  ASSERT_EQ(walked.size(), 14u);
  expect_same_tasks(sg::render_tasks(root, o, {}, list), walked);
  // The list is the dataset as it was when it was written: a mesh added since is not rendered,
  // one whose folder has gone is still a task (its view fails when it runs), so every array task
  // shards the same list whatever happens to the folders meanwhile.
  add_mesh(root, "fold", 5);
  fs::remove_all(root / "meshes" / "pull" / "1" / "1005");
  for (int count : {1, 3, 25})
    for (int index = 0; index < count; ++index)
      expect_same_tasks(sg::render_tasks(root, o, {index, count}, list),
                        papersim::batch::select_shard(walked, index, count));
  // The walk sees the change: one mesh in, one out.
  const auto key_set = [](const papersim::batch::TaskList& tasks) {
    std::set<std::string> keys;
    for (const auto& t : tasks) keys.insert(t.key);
    return keys;
  };
  const std::set<std::string> now = key_set(sg::render_tasks(root, o)), listed = key_set(walked);
  EXPECT_EQ(now.size(), 14u);
  EXPECT_TRUE(now.count("renders/fold/0/5/view1") && !listed.count("renders/fold/0/5/view1"));
  EXPECT_TRUE(!now.count("renders/pull/1/1005/view1") && listed.count("renders/pull/1/1005/view1"));
  fs::remove_all(root);
}

TEST(RenderTasks, AMalformedMeshListIsRefusedNamingItsLine) {
  const fs::path root = small_dataset("bad_mesh_list");
  const fs::path list = root / "list";
  const std::string head = "# scenegen batch mesh list: 2 meshes\n";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"meshes/pull/0/0\nmeshes/pull/0/1\n", "line 1 is not"},
      {"# scenegen batch mesh list: two meshes\nmeshes/pull/0/0\nmeshes/pull/0/1\n",
       "line 1 is not"},
      {head + "meshes/pull/0/0\nmeshes/pull/0\n", "line 3: 'meshes/pull/0' is not"},
      {head + "meshes/pull/0/0\nmeshes/pull/../1\n", "line 3: 'meshes/pull/../1' is not"},
      {head + "meshes/pull/0/x1\nmeshes/pull/0/1\n", "line 2: 'meshes/pull/0/x1' is not"},
      {head + "renders/pull/0/0\nmeshes/pull/0/1\n", "line 2: 'renders/pull/0/0' is not"},
      {head + "meshes/pull/0/1\nmeshes/pull/0/0\n", "line 3: 'meshes/pull/0/0' is out of order"},
      {head + "meshes/pull/0/1\nmeshes/pull/1/1\n", "line 3: 'meshes/pull/1/1' is out of order"},
      {head + "meshes/pull/0/0\nmeshes/pull/0/1\nmeshes/pull/0/7\n",
       "announces 2 meshes but holds 3"},
      {head + "meshes/pull/0/0\n", "announces 2 meshes but holds 1"},
      {head + "meshes/pull/0/0\nmeshes/pu\xffll/0/1\n",
       "line 3: 'meshes/pu\xffll/0/1' is not UTF-8"},
  };
  sg::RenderBatchOptions o;
  for (const auto& [text, message] : cases) {
    std::ofstream(list, std::ios::trunc) << text;
    try {
      sg::render_tasks(root, o, {}, list);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const sg::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(list.string()), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(sg::render_tasks(root, o, {}, root / "none"), sg::InputError);
  // A folder whose name has a line break cannot be a line of the list.
  fs::create_directories(root / "meshes" / "pu\nll" / "0" / "3");
  std::ofstream(root / "meshes" / "pu\nll" / "0" / "3" / "sheet.obj") << "";
  EXPECT_THROW(sg::write_mesh_list(root, list), sg::InputError);
  fs::remove_all(root / "meshes" / "pu\nll");
  // Nor can a folder whose name is not UTF-8 be in a row: the walk refuses it, naming it.
  add_mesh(root, "pu\xffll", 3);
  EXPECT_NE(input_error([&] {
              sg::write_mesh_list(root, list);
            }).find("meshes/pu\xffll/0/3' has a name that is not UTF-8"),
            std::string::npos);
  EXPECT_NE(input_error([&] {
              sg::render_tasks(root, o);
            }).find("meshes/pu\xffll/0/3' has a name that is not UTF-8"),
            std::string::npos);
  fs::remove_all(root / "meshes" / "pu\xffll");
  // A seed in two bucket folders would give two tasks one folder: the walk refuses it.
  fs::create_directories(root / "meshes" / "pull" / "9" / "1");
  std::ofstream(root / "meshes" / "pull" / "9" / "1" / "sheet.obj") << "";
  EXPECT_NE(input_error([&] {
              sg::write_mesh_list(root, list);
            }).find("seed 1 of scenario 'pull' is in two folders"),
            std::string::npos);
  fs::remove_all(root);
}
