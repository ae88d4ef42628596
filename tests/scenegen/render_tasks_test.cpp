// scenegen batch's task list: one task per (finished mesh, view), and an array task's shard made
// directly is the same slice as the shard taken from the whole list (so each array task holds
// only its own tasks in memory).
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "scenegen/batch.hpp"

namespace fs = std::filesystem;
namespace sg = papersim::scenegen;

TEST(RenderTasks, AShardMadeDirectlyIsTheSliceOfTheWholeList) {
  const fs::path root = fs::temp_directory_path() / ("papersim_render_tasks_" + std::to_string(getpid()));
  fs::remove_all(root);
  // 7 finished meshes of two scenarios (sheet.obj present) and one unfinished (none).
  for (const auto& [scenario, seed] : std::vector<std::pair<std::string, int>>{
           {"pull", 0}, {"pull", 1}, {"pull", 1005}, {"fold", 2}, {"fold", 3}, {"fold", 999}, {"fold", 4000}}) {
    const fs::path d = root / "meshes" / scenario / std::to_string(seed / 1000) / std::to_string(seed);
    fs::create_directories(d);
    std::ofstream(d / "sheet.obj") << "";
  }
  fs::create_directories(root / "meshes" / "pull" / "0" / "7");
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
