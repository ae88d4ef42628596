#pragma once
/// The files of a run: a staging folder whose files are published into the output folder only
/// when the run succeeded, and the writers of sheet.obj / sheet.ply / meta.json.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "remesh/sheet_mesh.hpp"
#include "simulation/scene.hpp"
#include "simulation/sheet_state.hpp"

namespace papersim::simulation {

/// Write sheet.obj (and sheet.ply when the scene asks for it) of state `s` into `dir`.
/// @throw remesh::IoError when a file cannot be written
void write_outputs(const std::filesystem::path& dir, const Scene& scene,
                   const remesh::SheetMesh& mesh, const SheetState& s);

/// Write `j` (indented) to `path` through a temporary file. @throw remesh::IoError
void write_json(const std::filesystem::path& path, const nlohmann::json& j);

/// A staging folder inside out_dir; its files move into out_dir only when the run succeeded.
class Staging {
 public:
  /// An empty out_dir stages nothing (active() is false).
  explicit Staging(const std::string& out_dir);
  ~Staging();
  Staging(const Staging&) = delete;
  Staging& operator=(const Staging&) = delete;
  bool active() const { return !m_dir.empty(); }
  const std::filesystem::path& dir() const { return m_dir; }
  /// Move every staged file into the output folder.
  void commit();

 private:
  std::filesystem::path m_out, m_dir;
  bool m_created = false, m_committed = false;
};

}  // namespace papersim::simulation
