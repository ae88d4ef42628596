// libFuzzer target: continuing a run from a checkpoint (load_checkpoint, then Run::resume and
// Run::adopt_factor as run_scene does). At start the target saves a valid checkpoint of a small
// falling sheet that carries a reusable factorisation; each input's first byte chooses which
// of its three files the rest of the input replaces (0: checkpoint.json, 1: the sheet file,
// 2: the matrix file). Bad input must end in SceneError (or the sheet readers'
// remesh::IoError / remesh::MeshError, which Run's constructor documents); any other
// exception, a crash or a sanitizer report is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "remesh/errors.hpp"
#include "simulation/errors.hpp"
#include "simulation/run.hpp"
#include "simulation/simulate.hpp"

namespace fs = std::filesystem;
namespace ps = papersim::simulation;

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << text;
}

/// The valid checkpoint's folder and its three files' names and contents.
struct Valid {
  fs::path dir;
  std::string names[3], contents[3];
};

const Valid& valid() {
  static const Valid v = [] {
    Valid v;
    v.dir = fs::temp_directory_path() / ("papersim_fuzz_checkpoint_" + std::to_string(getpid()));
    fs::remove_all(v.dir);
    // A 4 x 4 cm sheet in free fall: every step converges within two iterations on the exact
    // Hessian, so the checkpoint after step 6 carries the factorisation for step 7.
    const nlohmann::json scene = {
        {"sheet",
         {{"width", 0.04}, {"height", 0.04}, {"edge_length", 0.01}, {"position", {0, 0, 0.2}}}},
        {"duration", 0.01},
        {"time_step", 0.001},
        {"solver", {{"max_factor_reuse", 4}}}};
    ps::RunOptions o;
    o.checkpoint_dir = (v.dir / "saved").string();
    o.checkpoint_every = 6;
    ps::run_scene(ps::scene_from_json(scene, "fuzz_scene.json"), o);
    const nlohmann::json j =
        nlohmann::json::parse(std::ifstream(v.dir / "saved" / "checkpoint.json"));
    if (!j.contains("reusable_factor")) {
      std::fprintf(stderr, "fuzz_checkpoint: the valid checkpoint carries no factorisation\n");
      std::abort();
    }
    v.names[0] = "checkpoint.json";
    v.names[1] = j.at("sheet").get<std::string>();
    v.names[2] = j.at("reusable_factor").at("file").get<std::string>();
    for (int k = 0; k < 3; ++k) v.contents[k] = read_file(v.dir / "saved" / v.names[k]);
    fs::create_directories(v.dir / "input");
    return v;
  }();
  return v;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const Valid& v = valid();
  if (size == 0) return 0;
  const int replaced = data[0] % 3;
  const fs::path dir = v.dir / "input";
  for (int k = 0; k < 3; ++k)
    write_file(dir / v.names[k],
               k == replaced ? std::string(reinterpret_cast<const char*>(data) + 1, size - 1)
                             : v.contents[k]);
  try {
    const ps::Checkpoint c = ps::load_checkpoint(dir.string());
    const ps::Scene saved = ps::scene_from_json(c.scene, "checkpoint.json");
    ps::Run run(saved);
    run.resume(c.mesh, c.state, c.step, &saved, c.tally ? &*c.tally : nullptr,
               &c.self_contact_pattern);
    if (c.factor) run.adopt_factor(*c.factor);
  } catch (const ps::SceneError&) {
  } catch (const papersim::remesh::IoError&) {
  } catch (const papersim::remesh::MeshError&) {
  }
  return 0;
}
