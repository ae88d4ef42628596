#include "simulation/trace.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <stdexcept>

namespace papersim::simulation {

void Trace::operator()(Topic t, const char* format, ...) const {
  if (!on(t)) return;
  va_list args, copy;
  va_start(args, format);
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::string text(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(text.data(), text.size() + 1, format, args);
  va_end(args);
  line(t, text);
}

void Trace::line(Topic t, const std::string& text) const {
  if (!on(t)) return;
  if (m_write) {
    m_write(text);
    return;
  }
  std::fputs(text.c_str(), stderr);
  std::fputc('\n', stderr);
}

const std::vector<std::pair<std::string, Trace::Topic>>& Trace::names() {
  static const std::vector<std::pair<std::string, Topic>> n = {
      {"newton", newton}, {"model", model},     {"line-search", line_search}, {"inf", inf},
      {"solver", solver}, {"contact", contact}, {"intersect", intersect},     {"lift", lift},
      {"remesh", remesh}};
  return n;
}

unsigned Trace::parse(const std::string& list) {
  unsigned topics = 0;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t end = std::min(list.find(',', start), list.size());
    const std::string name = list.substr(start, end - start);
    bool known = false;
    if (name == "all") {
      for (const auto& [n, t] : names()) topics |= t;
      known = true;
    }
    for (const auto& [n, t] : names())
      if (n == name) topics |= t, known = true;
    if (!known) {
      std::string all = "all";
      for (const auto& [n, t] : names()) all += ", " + n;
      throw std::invalid_argument("unknown trace topic '" + name + "' (topics: " + all + ")");
    }
    start = end + 1;
  }
  return topics;
}

}  // namespace papersim::simulation
