// libFuzzer target: the scene reader (JSON text -> Scene). Bad input must end in SceneError;
// any other exception, a crash or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "simulation/errors.hpp"
#include "simulation/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const papersim::simulation::Scene scene = papersim::simulation::scene_from_json(
        papersim::simulation::parse_scene_text(in, "fuzz.json"), "fuzz.json");
    // What was read must write back and read again.
    papersim::simulation::scene_from_json(papersim::simulation::scene_to_json(scene), "again.json");
  } catch (const papersim::simulation::SceneError&) {
  }
  return 0;
}
