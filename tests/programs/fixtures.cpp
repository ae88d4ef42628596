#include "fixtures.hpp"

#include <fstream>
#include <stdexcept>

namespace papersim::test {

nlohmann::json small_scene(const Scratch& dir) {
  const std::string out = dir.str("drawn");
  const Outcome r = run({PAPERSIM, "scenario", "pull", "--seed", "1", "--draw-only", "--out", out});
  if (r.status != 0) throw std::runtime_error("papersim scenario failed: " + r.err);
  nlohmann::json scene = nlohmann::json::parse(read_text(out + "/scene.json"));
  scene["duration"] = 0.05;
  scene["sheet"]["edge_length"] = 0.02;
  return scene;
}

std::string write_scene(const Scratch& dir, const std::string& name, const nlohmann::json& scene) {
  const std::string path = dir.str(name);
  std::ofstream(path) << scene.dump(2) << '\n';
  return path;
}

std::string example_sheet(const Scratch& dir, const std::string& kind, const std::string& name) {
  const std::string path = dir.str(name);
  const Outcome r = run({SCENEGEN, "example", kind, "--out", path});
  if (r.status != 0) throw std::runtime_error("scenegen example failed: " + r.err);
  return path;
}

}  // namespace papersim::test
