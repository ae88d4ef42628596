// The task list keeps each task's bytes exactly, in order, across its blocks; views of a task
// stay valid while more are added; a copy is its own.
#include "batch/task_list.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "batch/runner.hpp"

using papersim::batch::Task;
using papersim::batch::TaskList;

namespace {

/// Task i: a key and an info of lengths that vary with i (empty ones too), with '\0' and bytes
/// above 127.
Task task_number(std::size_t i) {
  std::string key = "k" + std::to_string(i);
  std::string info(i % 97, static_cast<char>('a' + i % 26));
  if (i % 5 == 0) key += std::string(1, '\0') + "\xc3\xa9";
  if (i % 7 == 0) info.clear();
  if (i % 11 == 0) key.clear();
  return {key, info};
}

}  // namespace

TEST(TaskList, KeepsEveryTasksBytesInOrderAcrossBlocks) {
  // About 60 bytes a task: 100,000 tasks fill several 1 MiB blocks, and one task of 3 MiB is
  // larger than a block.
  constexpr std::size_t n = 100000;
  TaskList list;
  std::vector<std::string_view> early_keys;
  const std::string big(3u << 20, 'x');
  for (std::size_t i = 0; i < n; ++i) {
    const Task t = task_number(i);
    list.push_back(t);
    if (i < 10) early_keys.push_back(list.key(i));
    if (i == n / 2) list.add("big", big);
  }
  ASSERT_EQ(list.size(), n + 1);
  for (std::size_t i = 0, j = 0; i < list.size(); ++i) {
    if (i == n / 2 + 1) {
      EXPECT_EQ(list.key(i), "big");
      EXPECT_EQ(list.info(i), big);
      continue;
    }
    const Task t = task_number(j++);
    ASSERT_EQ(list.key(i), t.key) << i;
    ASSERT_EQ(list.info(i), t.info) << i;
    const Task copy = list[i];
    ASSERT_EQ(copy.key, t.key);
    ASSERT_EQ(copy.info, t.info);
  }
  // Views taken before the rest were added still show their task.
  for (std::size_t i = 0; i < early_keys.size(); ++i) EXPECT_EQ(early_keys[i], task_number(i).key);
  // Walking the list gives the same tasks.
  std::size_t walked = 0;
  for (const Task& t : list) {
    ASSERT_EQ(t.key, list.key(walked));
    ++walked;
  }
  EXPECT_EQ(walked, list.size());
  EXPECT_EQ(list.front().key, task_number(0).key);
  EXPECT_EQ(list.back().key, task_number(n - 1).key);
}

TEST(TaskList, ACopyIsItsOwn) {
  auto original = std::make_unique<TaskList>(TaskList{{"a/1", "{\"x\":1}"}, {"", ""}});
  const TaskList copy = *original;
  TaskList assigned;
  assigned = *original;
  original->add("a/2", "{}");
  original.reset();  // the copies' views must not point into the original's blocks
  for (const TaskList* l : std::vector<const TaskList*>{&copy, &assigned}) {
    ASSERT_EQ(l->size(), 2u);
    EXPECT_EQ(l->key(0), "a/1");
    EXPECT_EQ(l->info(0), "{\"x\":1}");
    EXPECT_EQ(l->key(1), "");
    EXPECT_EQ(l->info(1), "");
  }
  TaskList moved = std::move(assigned);
  EXPECT_EQ(moved.key(0), "a/1");
  moved.add("b", "{}");  // a list moved into adds where it left off
  EXPECT_EQ(moved.key(0), "a/1");
  EXPECT_EQ(moved.key(2), "b");
}

TEST(TaskList, AShardIsEveryCountthTaskFromItsIndex) {
  TaskList list;
  for (std::size_t i = 0; i < 10; ++i) list.push_back(task_number(i));
  const TaskList shard = papersim::batch::select_shard(list, 1, 3);
  ASSERT_EQ(shard.size(), 3u);
  for (std::size_t k = 0; k < shard.size(); ++k) {
    EXPECT_EQ(shard.key(k), list.key(1 + 3 * k));
    EXPECT_EQ(shard.info(k), list.info(1 + 3 * k));
  }
  EXPECT_TRUE(papersim::batch::select_shard(TaskList{}, 0, 2).empty());
}
