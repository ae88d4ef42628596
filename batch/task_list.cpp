#include "batch/task_list.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace papersim::batch {

TaskList::TaskList(std::initializer_list<Task> tasks) {
  reserve(tasks.size());
  for (const Task& t : tasks) push_back(t);
}

TaskList::TaskList(const TaskList& other) {
  reserve(other.size());
  for (std::size_t i = 0; i < other.size(); ++i) add(other.key(i), other.info(i));
}

TaskList& TaskList::operator=(const TaskList& other) {
  if (this != &other) *this = TaskList(other);
  return *this;
}

void TaskList::add(std::string_view key, std::string_view info) {
  constexpr std::size_t kMax = std::numeric_limits<std::uint32_t>::max();
  if (key.size() > kMax || info.size() > kMax)
    throw std::length_error("a task's key or info is longer than 4 GiB - 1 bytes");
  const std::size_t n = key.size() + info.size();
  if (n > m_room || m_blocks.empty()) {  // a new block; a task larger than one gets its own
    const std::size_t size = std::max(n, kBlock);
    m_blocks.push_back(std::unique_ptr<char[]>(new char[size]));  // not zeroed: written next
    m_next = m_blocks.back().get();
    m_room = size;
  }
  if (!key.empty()) std::memcpy(m_next, key.data(), key.size());
  if (!info.empty()) std::memcpy(m_next + key.size(), info.data(), info.size());
  m_entries.push_back(
      {m_next, static_cast<std::uint32_t>(key.size()), static_cast<std::uint32_t>(info.size())});
  m_next += n;
  m_room -= n;
}

}  // namespace papersim::batch
