#include "simulation/output_files.hpp"

#include <fstream>
#include <iomanip>

#include "remesh/errors.hpp"
#include "remesh/sheet_io.hpp"

namespace papersim::simulation {

namespace fs = std::filesystem;
using nlohmann::json;

void write_outputs(const fs::path& dir, const Scene& scene, const remesh::SheetMesh& mesh,
                   const SheetState& s) {
  remesh::write_sheet_file((dir / "sheet.obj").string(), mesh, s.positions_matrix(),
                           s.velocities_matrix(), scene.sheet.width, scene.sheet.height);
  if (scene.output.write_ply)
    remesh::write_sheet_file((dir / "sheet.ply").string(), mesh, s.positions_matrix(),
                             s.velocities_matrix(), scene.sheet.width, scene.sheet.height);
}

void write_json(const fs::path& path, const json& j) {
  const fs::path tmp = path.string() + ".tmp";
  std::ofstream out(tmp);
  out << std::setw(2) << j << '\n';
  if (!out) throw remesh::IoError(path.string() + ": cannot write");
  out.close();
  fs::rename(tmp, path);
}

Staging::Staging(const std::string& out_dir) {
  if (out_dir.empty()) return;
  m_out = out_dir;
  m_created = !fs::exists(m_out);
  fs::create_directories(m_out);
  m_dir = m_out / ".papersim-partial";
  fs::remove_all(m_dir);
  fs::create_directories(m_dir);
}

Staging::~Staging() {
  std::error_code ec;
  if (!m_dir.empty()) fs::remove_all(m_dir, ec);
  // A failed run leaves no trace: not even the folder, when this run made it.
  if (!m_committed && m_created) fs::remove(m_out, ec);
}

void Staging::commit() {
  for (const auto& e : fs::directory_iterator(m_dir)) {
    const fs::path target = m_out / e.path().filename();
    if (fs::is_directory(target)) fs::remove_all(target);
    fs::rename(e.path(), target);
  }
  m_committed = true;
}

}  // namespace papersim::simulation
