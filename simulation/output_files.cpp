#include "simulation/output_files.hpp"

#include <algorithm>
#include <iomanip>

#include "common/atomic_file.hpp"
#include "remesh/sheet_io.hpp"

namespace papersim::simulation {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* STAGING_NAME = ".papersim-partial";

void remove_or_throw(const fs::path& p) {
  std::error_code ec;
  fs::remove_all(p, ec);
  if (ec) throw common::OutputError("cannot remove '" + p.string() + "': " + ec.message());
}

void move_or_throw(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  if (fs::is_directory(to, ec)) remove_or_throw(to);
  fs::rename(from, to, ec);
  if (ec)
    throw common::OutputError("cannot move '" + from.string() + "' to '" + to.string() +
                              "': " + ec.message());
}

}  // namespace

const std::vector<std::string>& run_output_names() {
  static const std::vector<std::string> NAMES = {"sheet.obj", "sheet.ply", "frames", "scene.json",
                                                 "meta.json"};
  return NAMES;
}

void write_outputs(const fs::path& dir, const Scene& scene, const remesh::SheetMesh& mesh,
                   const SheetState& s) {
  remesh::write_sheet_file((dir / "sheet.obj").string(), mesh, s.positions_matrix(),
                           s.velocities_matrix(), scene.sheet.width, scene.sheet.height);
  if (scene.output.write_ply)
    remesh::write_sheet_file((dir / "sheet.ply").string(), mesh, s.positions_matrix(),
                             s.velocities_matrix(), scene.sheet.width, scene.sheet.height);
}

void write_json(const fs::path& path, const json& j) {
  // Names from outside (paths) are any bytes: those that are not UTF-8 become U+FFFD.
  const std::string text = j.dump(2, ' ', false, json::error_handler_t::replace);
  common::write_file_atomically(path, [&](std::ostream& out) { out << text << '\n'; });
}

fs::path Staging::path_for(const std::string& out_dir) { return fs::path(out_dir) / STAGING_NAME; }

Staging::Staging(const std::string& out_dir) {
  if (out_dir.empty()) return;
  m_out = out_dir;
  std::error_code ec;
  m_created = !fs::exists(m_out, ec);
  fs::create_directories(m_out, ec);
  if (ec)
    throw common::OutputError("cannot create output folder '" + out_dir + "': " + ec.message());
  m_dir = path_for(out_dir);
  remove_or_throw(m_dir);
  fs::create_directories(m_dir, ec);
  if (ec) {
    m_dir.clear();
    if (m_created) fs::remove(m_out, ec);
    throw common::OutputError("cannot create staging folder in '" + out_dir + "': " + ec.message());
  }
}

Staging::~Staging() {
  std::error_code ec;
  if (!m_dir.empty()) fs::remove_all(m_dir, ec);
  // A failed run leaves no trace: not even the folder, when this run made it.
  if (!m_committed && m_created) fs::remove_all(m_out, ec);
}

void Staging::commit() {
  std::vector<std::string> staged;
  for (const auto& e : fs::directory_iterator(m_dir))
    staged.push_back(e.path().filename().string());
  const auto is_staged = [&](const std::string& n) {
    return std::find(staged.begin(), staged.end(), n) != staged.end();
  };
  // First the old meta.json goes: from here on the folder does not claim a complete run.
  remove_or_throw(m_out / "meta.json");
  const auto is_protected = [&](const fs::path& p) {
    std::error_code ec;
    for (const fs::path& q : m_protected)
      if (fs::equivalent(p, q, ec)) return true;
    return false;
  };
  for (const std::string& name : run_output_names())
    if (!is_staged(name) && !is_protected(m_out / name)) remove_or_throw(m_out / name);
  std::sort(staged.begin(), staged.end(), [](const std::string& a, const std::string& b) {
    return (a == "meta.json") < (b == "meta.json") ||
           ((a == "meta.json") == (b == "meta.json") && a < b);
  });
  for (const std::string& name : staged) move_or_throw(m_dir / name, m_out / name);
  m_committed = true;
}

}  // namespace papersim::simulation
