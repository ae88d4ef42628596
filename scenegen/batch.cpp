#include "scenegen/batch.hpp"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <sstream>

#include "batch/cli.hpp"
#include "common/atomic_file.hpp"
#include "common/utf8.hpp"
#include "scenegen/errors.hpp"

namespace papersim::scenegen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ULL;
  return h;
}

bool all_digits(const std::string& s) {
  return !s.empty() && s.size() < 19 && s.find_first_not_of("0123456789") == std::string::npos;
}

struct MeshEntry {
  std::string scenario;
  std::uint64_t seed = 0;
  std::string dir;  ///< '/'-separated, relative to the root (not a fs::path: a million of them)
};

/// Finished meshes: meshes/<scenario>/<bucket>/<seed>/ holding sheet.obj, sorted by scenario, then
/// seed. One `stat` a mesh (sheet.obj's). The bucket folders are listed first, so that `progress`
/// hears after each of them how many of them are done.
/// @throw InputError when a seed of a scenario is in two bucket folders, or a mesh folder's name
/// is not UTF-8
std::vector<MeshEntry> finished_meshes(const fs::path& root, const ListProgress& progress) {
  std::vector<std::pair<std::string, fs::path>> buckets;  // (scenario, folder)
  std::error_code ec;
  for (const auto& sc : fs::directory_iterator(root / "meshes", ec)) {
    if (!sc.is_directory()) continue;
    for (const auto& bucket : fs::directory_iterator(sc.path(), ec))
      if (bucket.is_directory()) buckets.emplace_back(sc.path().filename().string(), bucket.path());
  }
  std::vector<MeshEntry> out;
  for (std::size_t i = 0; i < buckets.size(); ++i) {
    const auto& [scenario, bucket] = buckets[i];
    for (const auto& d : fs::directory_iterator(bucket, ec)) {
      const std::string name = d.path().filename().string();
      if (!d.is_directory() || !all_digits(name) || !fs::exists(d.path() / "sheet.obj")) continue;
      // The folder relative to the root, composed (fs::relative resolves links: 8 readlink
      // calls a mesh, which dominated the walk over a large dataset).
      out.push_back({scenario, std::stoull(name),
                     "meshes/" + scenario + '/' + bucket.filename().string() + '/' + name});
      if (!common::is_utf8(out.back().dir))
        throw InputError("mesh folder '" + (root / out.back().dir).string() +
                         "' has a name that is not UTF-8: its rows cannot be written (the "
                         "manifests are UTF-8 JSON)");
    }
    if (progress) progress(i + 1, buckets.size(), out.size());
  }
  const auto before = [](const MeshEntry& a, const MeshEntry& b) {
    return a.scenario != b.scenario ? a.scenario < b.scenario : a.seed < b.seed;
  };
  std::sort(out.begin(), out.end(), before);
  const auto twin =
      std::adjacent_find(out.begin(), out.end(),
                         [&](const MeshEntry& a, const MeshEntry& b) { return !before(a, b); });
  if (twin != out.end())
    throw InputError("seed " + std::to_string(twin->seed) + " of scenario '" + twin->scenario +
                     "' is in two folders: " + (root / twin->dir).string() + " and " +
                     (root / std::next(twin)->dir).string());
  return out;
}

constexpr const char* MESH_LIST_HEAD = "# scenegen batch mesh list: ";

/// The entry of one line "meshes/<scenario>/<bucket>/<seed>" of a mesh list, or an empty scenario
/// when the line is not one.
MeshEntry parse_mesh_line(const std::string& line) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (std::size_t slash; (slash = line.find('/', start)) != std::string::npos; start = slash + 1)
    parts.push_back(line.substr(start, slash - start));
  parts.push_back(line.substr(start));
  const auto name = [](const std::string& s) { return !s.empty() && s != "." && s != ".."; };
  if (parts.size() != 4 || parts[0] != "meshes" || !name(parts[1]) || !name(parts[2]) ||
      !all_digits(parts[3]))
    return {};
  return {parts[1], std::stoull(parts[3]), line};
}

/// The meshes of a list written by write_mesh_list, checked line by line (format, order, count).
/// @throw InputError naming the file and the line
std::vector<MeshEntry> read_mesh_list(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError("mesh list '" + file.string() + "' cannot be read");
  std::string line;
  std::getline(in, line);
  const std::string head = MESH_LIST_HEAD;
  std::size_t count = 0;
  {
    const std::string tail =
        line.compare(0, head.size(), head) == 0 ? line.substr(head.size()) : "";
    const std::size_t space = tail.find(' ');
    if (space == std::string::npos || !all_digits(tail.substr(0, space)) ||
        tail.substr(space) != " meshes")
      throw InputError("mesh list '" + file.string() + "': line 1 is not '" + head + "N meshes'");
    count = std::stoull(tail.substr(0, space));
  }
  std::vector<MeshEntry> out;
  out.reserve(std::min<std::size_t>(count, 10000000));
  for (std::size_t n = 2; std::getline(in, line); ++n) {
    MeshEntry e = parse_mesh_line(line);
    const auto where = [&] {
      return "mesh list '" + file.string() + "', line " + std::to_string(n) + ": ";
    };
    if (e.scenario.empty())
      throw InputError(where() + "'" + line + "' is not meshes/<scenario>/<bucket>/<seed>");
    if (!common::is_utf8(line)) throw InputError(where() + "'" + line + "' is not UTF-8 text");
    if (!out.empty() && !(out.back().scenario < e.scenario ||
                          (out.back().scenario == e.scenario && out.back().seed < e.seed)))
      throw InputError(where() + "'" + line +
                       "' is out of order (the list is sorted by scenario, then seed, " +
                       "each once)");
    out.push_back(std::move(e));
  }
  if (in.bad()) throw InputError("mesh list '" + file.string() + "' cannot be read");
  if (out.size() != count)
    throw InputError("mesh list '" + file.string() + "' announces " + std::to_string(count) +
                     " meshes but holds " + std::to_string(out.size()) + " (cut short?)");
  return out;
}

void write_obj_file(const fs::path& path, const SheetMesh& mesh) {
  std::ofstream out(path);
  write_sheet_obj(out, mesh);
  if (!out.flush()) throw IoError("cannot write '" + path.string() + "'");
}

}  // namespace

SheetMesh flipped_sheet(const SheetMesh& mesh) {
  SheetMesh f = mesh;
  f.positions.col(0) = -mesh.positions.col(0);
  f.positions.col(2) = -mesh.positions.col(2);
  f.uv.col(0) = Eigen::VectorXd::Ones(mesh.uv.rows()) - mesh.uv.col(0);
  // u -> 1 - u turns every face's UV area negative: reverse the faces so the printed side
  // faces along the face normal again (the convention of parse_sheet_obj).
  f.faces.col(1) = mesh.faces.col(2);
  f.faces.col(2) = mesh.faces.col(1);
  return f;
}

std::uint64_t view_seed(const std::string& scenario, std::uint64_t seed, int view) {
  return batch::splitmix64(fnv1a(scenario) ^
                           batch::splitmix64(seed * 64 + static_cast<std::uint64_t>(view))) >>
         33;
}

std::size_t write_mesh_list(const fs::path& root, const fs::path& file,
                            const ListProgress& progress) {
  const std::vector<MeshEntry> meshes = finished_meshes(root, progress);
  for (const MeshEntry& m : meshes)
    if (m.dir.find_first_of("\n\r") != std::string::npos)
      throw InputError("mesh folder '" + (root / m.dir).string() +
                       "' has a line break in its path: it cannot be listed");
  common::write_file_atomically(file, [&](std::ostream& out) {
    out << MESH_LIST_HEAD << meshes.size() << " meshes\n";
    for (const MeshEntry& m : meshes) out << m.dir << '\n';
  });
  return meshes.size();
}

std::size_t mesh_list_size(const fs::path& file) { return read_mesh_list(file).size(); }

batch::TaskList render_tasks(const fs::path& root, const RenderBatchOptions& o,
                             const batch::Shard& shard, const fs::path& mesh_list,
                             const ListProgress& progress) {
  if (o.views < 1) throw InputError("--views must be >= 1");
  const std::vector<MeshEntry> meshes =
      mesh_list.empty() ? finished_meshes(root, progress) : read_mesh_list(mesh_list);
  // The shard's positions p < n with p % count == index.
  const std::size_t n = meshes.size() * static_cast<std::size_t>(o.views);
  const auto index = static_cast<std::size_t>(shard.index);
  const auto count = static_cast<std::size_t>(shard.count);
  batch::TaskList tasks;
  tasks.reserve(n > index ? (n - index + count - 1) / count : 0);
  // Each task's fields are the text json{{"scenario", ...}, {"seed", ...}, {"view", k},
  // {"flipped", ...}, {"render_seed", ...}, {"mesh", ...}}.dump() writes (keys in order), put
  // together from the mesh's dumped strings: building and dumping an object per view was most of
  // the start of a million meshes' views.
  std::size_t position = 0;
  std::string folder, info, mesh_text, scenario_text;
  const std::string* scenario = nullptr;
  for (const MeshEntry& m : meshes) {
    const std::size_t first = position;
    position += static_cast<std::size_t>(o.views);
    bool any = false;
    for (std::size_t p = first; p < position && !any; ++p) any = shard.holds(p);
    if (!any) continue;
    if (scenario == nullptr || *scenario != m.scenario) {
      scenario = &m.scenario;
      scenario_text = json(m.scenario).dump();
    }
    mesh_text = json(m.dir + "/sheet.obj").dump();
    const std::string seed = std::to_string(m.seed);
    const std::string bucket = std::to_string(m.seed / 1000) + '/' + seed;
    for (int k = 0; k < o.views; ++k) {
      if (!shard.holds(first + static_cast<std::size_t>(k))) continue;
      const std::string view = std::to_string(k);
      folder.assign("renders/").append(m.scenario).append(1, '/').append(bucket);
      folder.append("/view").append(view);
      info.assign("{\"flipped\":").append(o.flip && k % 2 == 1 ? "true" : "false");
      info.append(",\"mesh\":").append(mesh_text);
      info.append(",\"render_seed\":").append(std::to_string(view_seed(m.scenario, m.seed, k)));
      info.append(",\"scenario\":").append(scenario_text).append(",\"seed\":").append(seed);
      info.append(",\"view\":").append(view).append(1, '}');
      tasks.add(folder, info);
    }
  }
  return tasks;
}

batch::BatchSpec render_batch_spec(const fs::path& root, const fs::path& scenegen,
                                   const RenderBatchOptions& o) {
  batch::BatchSpec spec;
  spec.root = root;
  spec.manifest_name = "renders.jsonl";
  spec.failures_name = "renders_failures.jsonl";
  spec.items = "views";
  spec.prepare = [root](const batch::Task& t, const fs::path& stage) {
    const nlohmann::json info = t.info_object();
    if (!info.at("flipped").get<bool>()) return;
    const SheetMesh mesh = read_sheet_obj((root / info.at("mesh").get<std::string>()).string());
    write_obj_file(stage / "flipped.obj", flipped_sheet(mesh));
  };
  spec.commands = [root, scenegen, o](const batch::Task& t, const fs::path& stage) {
    const nlohmann::json info = t.info_object();
    const bool flipped = info.at("flipped").get<bool>();
    const fs::path mesh =
        flipped ? stage / "flipped.obj" : root / info.at("mesh").get<std::string>();
    std::vector<std::string> argv{scenegen.string(),
                                  "render",
                                  mesh.string(),
                                  "--out",
                                  (stage / "out").string(),
                                  "--seed",
                                  std::to_string(info.at("render_seed").get<std::uint64_t>()),
                                  "--size",
                                  o.size,
                                  "--quality",
                                  o.quality,
                                  "--passes",
                                  o.passes,
                                  "--parallel",
                                  "1",
                                  "--threads",
                                  std::to_string(o.threads),
                                  "--quiet"};
    if (o.dpi > 0) argv.insert(argv.end(), {"--dpi", std::to_string(o.dpi)});
    if (!o.documents_dir.empty()) argv.insert(argv.end(), {"--documents", o.documents_dir});
    if (!o.backgrounds_dir.empty()) argv.insert(argv.end(), {"--backgrounds", o.backgrounds_dir});
    return std::vector<batch::Command>{{argv, {}}};
  };
  spec.finalize = [](const batch::Task&, const batch::Attempt& a) {
    fs::path out = a.stage / "out";
    if (!fs::exists(out / "meta.json")) throw IoError("missing meta.json");
    return out;
  };
  spec.manifest_row = [](const batch::Task&, const fs::path&, double wall) {
    return json{{"wall_seconds", wall >= 0 ? json(wall) : json(nullptr)}};
  };
  spec.failure_reason = [](int code, const std::string&) -> std::string {
    if (code == 3) return "no valid camera";
    if (code == 2) return "render failed";
    return "";
  };
  return spec;
}

}  // namespace papersim::scenegen
