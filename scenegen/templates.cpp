#include "scenegen/templates.hpp"

#include <fstream>
#include <sstream>

#include "scenegen/errors.hpp"
#include "scenegen/templates_data.hpp"

namespace papersim::scenegen {

std::vector<std::string> template_names() {
  std::vector<std::string> names;
  for (const auto& t : EMBEDDED_TEMPLATES) names.emplace_back(t.name);
  return names;
}

std::string template_text(const std::string& name, const std::string& dir) {
  if (!dir.empty()) {
    std::ifstream in(dir + "/" + name);
    if (!in) throw IoError("cannot read template '" + dir + "/" + name + "'");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  for (const auto& t : EMBEDDED_TEMPLATES)
    if (name == t.name) return t.text;
  throw IoError("no template named '" + name + "'");
}

}  // namespace papersim::scenegen
