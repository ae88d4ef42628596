#pragma once
/// The tasks of a batch as text in a few large blocks: a batch holds up to ten million samples,
/// and as ten million Task objects (two strings each, twenty million allocations) they peaked at
/// 2.45 GB and took 5.2-5.7 s to free when the batch ended or was stopped (docs/batch.md).
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace papersim::batch {

/// One sample of a batch.
struct Task {
  /// The task's folder, '/'-separated, relative to the root (e.g. "meshes/pull/0/17"): unique
  /// within the batch, it names the task in rows and file names, and it exists only when the
  /// task is finished.
  std::string key;
  /// A JSON object's text (nlohmann::json::dump()), copied into manifest and failure rows.
  std::string info = "{}";

  /// `info` parsed.
  nlohmann::json info_object() const { return nlohmann::json::parse(info); }

  /// The task of `folder` with `info` as its text.
  static Task in_folder(std::string folder, const nlohmann::json& info) {
    return {std::move(folder), info.dump()};
  }
};

/// A list of tasks kept as their bytes, back to back in blocks of 1 MiB, with 16 bytes per task
/// to find them. Reading a task gives a copy (a Task) or views of its key and info, which stay
/// valid as long as the list (adding tasks does not move them).
class TaskList {
 public:
  TaskList() = default;
  TaskList(std::initializer_list<Task> tasks);
  TaskList(const TaskList& other);
  TaskList& operator=(const TaskList& other);
  TaskList(TaskList&&) noexcept = default;
  TaskList& operator=(TaskList&&) noexcept = default;
  ~TaskList() = default;

  /// Append the task of folder `key` whose info is the text `info`.
  /// @throw std::length_error when the key or the info is longer than 4 GiB - 1
  void add(std::string_view key, std::string_view info);
  void push_back(const Task& t) { add(t.key, t.info); }
  /// Room for `tasks` tasks without moving the index.
  void reserve(std::size_t tasks) { m_entries.reserve(tasks); }

  std::size_t size() const { return m_entries.size(); }
  bool empty() const { return m_entries.empty(); }
  std::string_view key(std::size_t i) const {
    const Entry& e = m_entries[i];
    return {e.text, e.key_size};
  }
  std::string_view info(std::size_t i) const {
    const Entry& e = m_entries[i];
    return {e.text + e.key_size, e.info_size};
  }
  /// A copy of task `i`.
  Task operator[](std::size_t i) const { return {std::string(key(i)), std::string(info(i))}; }
  Task front() const { return (*this)[0]; }
  Task back() const { return (*this)[size() - 1]; }

  /// Walks the tasks in order, giving a copy of each.
  class const_iterator {
   public:
    using iterator_category = std::input_iterator_tag;
    using value_type = Task;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = Task;
    const_iterator(const TaskList* list, std::size_t i) : m_list(list), m_i(i) {}
    Task operator*() const { return (*m_list)[m_i]; }
    const_iterator& operator++() {
      ++m_i;
      return *this;
    }
    bool operator==(const const_iterator& o) const { return m_i == o.m_i; }
    bool operator!=(const const_iterator& o) const { return m_i != o.m_i; }

   private:
    const TaskList* m_list;
    std::size_t m_i;
  };
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, size()}; }

 private:
  static constexpr std::size_t kBlock = std::size_t{1} << 20;

  struct Entry {
    const char* text;  ///< the key's bytes, then the info's
    std::uint32_t key_size;
    std::uint32_t info_size;
  };

  std::vector<std::unique_ptr<char[]>> m_blocks;
  char* m_next = nullptr;  ///< where the next task's bytes go, in the last block
  std::size_t m_room = 0;  ///< bytes left in the last block from m_next
  std::vector<Entry> m_entries;
};

}  // namespace papersim::batch
