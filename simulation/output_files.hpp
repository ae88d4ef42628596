#pragma once
/// The files of a run: a staging folder whose files are published into the output folder only
/// when the run succeeded, and the writers of sheet.obj / sheet.ply / meta.json.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "remesh/sheet_mesh.hpp"
#include "simulation/scene.hpp"
#include "simulation/sheet_state.hpp"

namespace papersim::simulation {

/// Every name a papersim run may publish in its output folder. Publishing a run removes those
/// of them it did not write, so that a folder never mixes the files of two runs.
const std::vector<std::string>& run_output_names();

/// Write sheet.obj (and sheet.ply when the scene asks for it) of state `s` into `dir`.
/// @throw common::OutputError when a file cannot be written
void write_outputs(const std::filesystem::path& dir, const Scene& scene,
                   const remesh::SheetMesh& mesh, const SheetState& s);

/// Write `j` (indented) to `path` atomically. @throw common::OutputError
void write_json(const std::filesystem::path& path, const nlohmann::json& j);

/// A staging folder (OUT/.papersim-partial) whose files move into OUT only on commit(). A run
/// that fails or is interrupted leaves OUT as it was (and removes OUT when it created it).
class Staging {
 public:
  /// The staging folder of output folder `out_dir`. A run killed with SIGKILL may leave it
  /// behind; the next Staging for the same output removes it.
  static std::filesystem::path path_for(const std::string& out_dir);

  /// An empty out_dir stages nothing (active() is false).
  /// @throw common::OutputError when OUT or the staging folder cannot be created
  explicit Staging(const std::string& out_dir);
  ~Staging();
  Staging(const Staging&) = delete;
  Staging& operator=(const Staging&) = delete;
  bool active() const { return !m_dir.empty(); }
  const std::filesystem::path& dir() const { return m_dir; }

  /// Publish: remove the run_output_names() of OUT that were not staged, move every staged
  /// file into OUT (meta.json last, so a folder with a meta.json is complete) and remove the
  /// staging folder. @throw common::OutputError when a file cannot be moved
  void commit();
  /// A file that commit() never removes even when its name is a run output: the scene file the
  /// run reads, when it lies in OUT (`papersim run OUT/scene.json --out OUT`).
  void protect(const std::filesystem::path& path) { m_protected.push_back(path); }

 private:
  std::filesystem::path m_out, m_dir;
  bool m_created = false, m_committed = false;
  std::vector<std::filesystem::path> m_protected;
};

}  // namespace papersim::simulation
