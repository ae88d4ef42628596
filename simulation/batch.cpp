#include "simulation/batch.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include "batch/cli.hpp"
#include "common/utf8.hpp"
#include "simulation/errors.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"

namespace papersim::simulation {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

void check_scenario(const std::string& name, const std::string& where) {
  const auto names = scenario_names();
  if (std::find(names.begin(), names.end(), name) != names.end()) return;
  std::string known;
  for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
  throw SceneError(where + ": unknown scenario '" + name + "' (known: " + known + ")");
}

/// One mix entry: a weight, or {"weight": w, "set": {...}}.
void add_mix_entry(Mix& mix, const std::string& name, const json& v, const std::string& source) {
  const std::string where = source + ": scenarios." + name;
  check_scenario(name, source + ": scenarios");
  double weight = 1.0;
  json set = json::object();
  if (v.is_number()) {
    weight = v.get<double>();
  } else if (v.is_object()) {
    for (const auto& [k, x] : v.items())
      if (k != "weight" && k != "set") throw SceneError(where + ": unknown key '" + k + "'");
    if (v.contains("weight")) {
      if (!v["weight"].is_number()) throw SceneError(where + ".weight: not a number");
      weight = v["weight"].get<double>();
    }
    if (v.contains("set")) {
      if (!v["set"].is_object()) throw SceneError(where + ".set: not an object of scene keys");
      set = v["set"];
    }
  } else {
    throw SceneError(where + ": a weight or {\"weight\": W, \"set\": {...}}");
  }
  if (!(weight > 0) || !std::isfinite(weight)) throw SceneError(where + ": weight must be > 0");
  mix.scenarios.push_back(name);
  mix.weights.push_back(weight);
  mix.overrides.push_back(set);
}

/// The JSON node at a dotted key; every part must exist (array parts are indices).
json& node_at(json& root, const std::string& key, const std::string& source) {
  json* node = &root;
  std::stringstream parts(key);
  std::string part, walked;
  while (std::getline(parts, part, '.')) {
    walked += (walked.empty() ? "" : ".") + part;
    if (node->is_object() && node->contains(part)) {
      node = &(*node)[part];
    } else if (node->is_array() && !part.empty() &&
               part.find_first_not_of("0123456789") == std::string::npos &&
               std::stoul(part) < node->size()) {
      node = &(*node)[std::stoul(part)];
    } else {
      throw SceneError(source + ": '" + key + "' is not a key of the scene ('" + walked +
                       "' does not exist)");
    }
  }
  return *node;
}

std::string seed_bucket(std::uint64_t seed) { return std::to_string(seed / 1000); }

double number_or(const json& j, const char* key, double fallback) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
}

/// The whole file, or "" when it cannot be read.
std::string read_text_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return in ? text.str() : std::string();
}

json read_json_file(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read '" + path.string() + "'");
  json j = json::parse(in, nullptr, false);
  if (j.is_discarded()) throw std::runtime_error("'" + path.string() + "' is not valid JSON");
  return j;
}

}  // namespace

Mix mix_from_json(const json& j, const std::string& source) {
  if (!j.is_object()) throw SceneError(source + ": a mix file is a JSON object");
  for (const auto& [k, v] : j.items())
    if (k != "scenarios" && k != "set") throw SceneError(source + ": unknown key '" + k + "'");
  if (!j.contains("scenarios") || !j["scenarios"].is_object() || j["scenarios"].empty())
    throw SceneError(source + ": 'scenarios' must be a non-empty object {name: weight}");
  Mix mix;
  for (const auto& [name, v] : j["scenarios"].items()) add_mix_entry(mix, name, v, source);
  // mix_pick divides by the sum: an infinite one (two weights of 1e308) gave every weight the
  // share 0, and every seed the last scenario.
  double total = 0;
  for (const double w : mix.weights) total += w;
  if (!std::isfinite(total))
    throw SceneError(source + ": the weights add up to more than the largest number (" +
                     std::to_string(mix.weights.size()) + " weights): scale them down");
  if (j.contains("set")) {
    if (!j["set"].is_object()) throw SceneError(source + ": 'set' must be an object of scene keys");
    mix.common = j["set"];
  }
  return mix;
}

Mix load_mix(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError("--mix: cannot read '" + path + "'");
  const json j = json::parse(in, nullptr, false);
  if (j.is_discarded()) throw SceneError("--mix: '" + path + "' is not valid JSON");
  return mix_from_json(j, path);
}

std::size_t mix_pick(const Mix& mix, std::uint64_t seed) {
  double total = 0;
  for (double w : mix.weights) total += w;
  const double u =
      static_cast<double>(batch::splitmix64(seed ^ 0x6d69785f7069636bULL) >> 11) * 0x1.0p-53;
  double acc = 0;
  for (std::size_t i = 0; i < mix.weights.size(); ++i) {
    acc += mix.weights[i] / total;
    if (u < acc) return i;
  }
  return mix.weights.size() - 1;
}

json parse_overrides(const std::vector<std::string>& pairs) {
  json out = json::object();
  for (const auto& p : pairs) {
    const auto eq = p.find('=');
    if (eq == std::string::npos || eq == 0)
      throw SceneError("--set '" + p + "': expected KEY=VALUE (e.g. duration=0.2)");
    if (!common::is_utf8(p))
      throw SceneError("--set '" + p + "': not UTF-8 text (scene files and rows are UTF-8 JSON)");
    const std::string value = p.substr(eq + 1);
    json v = json::parse(value, nullptr, false);
    out[p.substr(0, eq)] = v.is_discarded() ? json(value) : v;
  }
  return out;
}

Scene apply_overrides(const Scene& scene, const json& overrides, const std::string& source) {
  if (overrides.empty()) return scene;
  json j = scene_to_json(scene, true);  // keys written only when not at their default too
  for (const auto& [key, value] : overrides.items()) node_at(j, key, source) = value;
  return scene_from_json(j, source);
}

namespace {

/// Each sample of a selection (draw_samples), given to `visit` in order, after `reserve` was told
/// how many there are at most.
template <class Reserve, class Visit>
void draw_each(const MeshBatchSelection& sel, Reserve reserve, Visit visit) {
  if (sel.seeds.empty()) throw SceneError("--seeds: no seed given");
  for (const auto& [first, last] : sel.seeds)
    if (last < first) throw SceneError("--seeds: the last seed is below the first");
  if (sel.scenarios.empty() == sel.mix_path.empty())
    throw SceneError("give either --scenarios or --mix");
  Mix mix;
  if (!sel.mix_path.empty()) {
    mix = load_mix(sel.mix_path);
  } else {
    for (const auto& s : sel.scenarios) {
      check_scenario(s, "--scenarios");
      mix.scenarios.push_back(s);
      mix.weights.push_back(1.0);
      mix.overrides.push_back(json::object());
    }
  }
  // Every sample is drawn before the first runs (an array task keeps its shard's): bound their
  // number.
  const std::uint64_t per_seed = sel.mix_path.empty() ? mix.scenarios.size() : 1;
  std::uint64_t samples = 0;
  for (const auto& [first, last] : sel.seeds) {
    const std::uint64_t n = last - first;  // one less than the range's seeds; no overflow
    if (n >= MAX_BATCH_SAMPLES || (samples += (n + 1) * per_seed) > MAX_BATCH_SAMPLES)
      throw SceneError(
          "--seeds: more than " + std::to_string(MAX_BATCH_SAMPLES) +
          " samples in one batch command (each is drawn before the first runs); split the seeds "
          "over several commands on the same dataset, each with at most " +
          std::to_string(MAX_BATCH_SAMPLES) + " samples");
  }
  std::vector<json> merged(mix.scenarios.size());
  for (std::size_t i = 0; i < merged.size(); ++i) {
    merged[i] = mix.common;
    merged[i].update(mix.overrides[i]);
    merged[i].update(sel.overrides);
  }
  std::vector<std::shared_ptr<const json>> shared(merged.size());
  for (std::size_t i = 0; i < merged.size(); ++i)
    if (!merged[i].empty()) shared[i] = std::make_shared<const json>(merged[i]);
  const auto shards = static_cast<std::uint64_t>(sel.shard.count);
  reserve(static_cast<std::size_t>((samples + shards - 1) / shards));
  std::set<std::size_t> checked;
  std::size_t position = 0;  // in the whole selection, for the shard
  const auto draw_seed = [&](std::uint64_t seed) {
    std::vector<std::size_t> picks;
    if (sel.mix_path.empty()) {
      for (std::size_t i = 0; i < mix.scenarios.size(); ++i) picks.push_back(i);
    } else {
      picks.push_back(mix_pick(mix, seed));
    }
    for (std::size_t i : picks) {
      // An override that is not a scene key fails here, before any sample runs.
      if (checked.insert(i).second)
        apply_overrides(make_scenario(mix.scenarios[i], seed), merged[i],
                        sel.mix_path.empty() ? "--set" : sel.mix_path + " / --set");
      if (sel.shard.holds(position++)) visit(SampleDraw{mix.scenarios[i], seed, shared[i]});
    }
  };
  // Each range to `last` inclusive, which may be the largest seed.
  for (const auto& [first, last] : sel.seeds)
    for (std::uint64_t seed = first;; ++seed) {
      draw_seed(seed);
      if (seed == last) break;
    }
}

/// Appends the task of each draw to a list. Each task's fields are the text
/// json{{"scenario", S}, {"seed", N}, {"set", O}}.dump() writes (its keys in order), put together
/// from the scenario's and the overrides' texts, each dumped once for a run of draws that share
/// them: building and dumping an object per sample took 17 s of ten million samples' start.
class MeshTaskWriter {
 public:
  explicit MeshTaskWriter(batch::TaskList& tasks) : m_tasks(tasks) {}

  void add(const SampleDraw& d) {
    if (m_first || m_scenario != d.scenario) {
      m_scenario = d.scenario;
      m_scenario_text = "{\"scenario\":" + json(d.scenario).dump() + ",\"seed\":";
    }
    // The overrides are shared by the draws of one scenario and outlive them.
    if (m_first || d.overrides.get() != m_overrides) {
      m_overrides = d.overrides.get();
      m_set_text =
          m_overrides && !m_overrides->empty() ? ",\"set\":" + m_overrides->dump() + "}" : "}";
    }
    m_first = false;
    const std::string seed = std::to_string(d.seed);
    m_folder.assign("meshes/").append(d.scenario).append(1, '/').append(seed_bucket(d.seed));
    m_folder.append(1, '/').append(seed);
    m_info.assign(m_scenario_text).append(seed).append(m_set_text);
    m_tasks.add(m_folder, m_info);
  }

 private:
  batch::TaskList& m_tasks;
  bool m_first = true;
  std::string m_scenario;
  const json* m_overrides = nullptr;
  std::string m_scenario_text, m_set_text, m_folder, m_info;
};

}  // namespace

std::vector<SampleDraw> draw_samples(const MeshBatchSelection& sel) {
  std::vector<SampleDraw> draws;
  draw_each(
      sel, [&](std::size_t n) { draws.reserve(n); },
      [&](const SampleDraw& d) { draws.push_back(d); });
  return draws;
}

std::size_t count_samples(const MeshBatchSelection& sel) {
  std::size_t n = 0;
  draw_each(
      sel, [](std::size_t) {}, [&n](const SampleDraw&) { ++n; });
  return n;
}

batch::TaskList mesh_tasks(const std::vector<SampleDraw>& draws) {
  batch::TaskList tasks;
  tasks.reserve(draws.size());
  MeshTaskWriter writer(tasks);
  for (const auto& d : draws) writer.add(d);
  return tasks;
}

batch::TaskList mesh_tasks(const MeshBatchSelection& sel, const batch::StepProgressFn& progress) {
  batch::TaskList tasks;
  MeshTaskWriter writer(tasks);
  std::size_t total = 0;
  draw_each(
      sel,
      [&](std::size_t n) {
        tasks.reserve(n);
        total = n;
      },
      [&](const SampleDraw& d) {
        writer.add(d);
        if (progress && tasks.size() % 65536 == 0)
          progress("drawing the samples", static_cast<double>(tasks.size()),
                   static_cast<double>(total), "samples");
      });
  return tasks;
}

json mesh_manifest_fields(const fs::path& dir) {
  const fs::path meta_path = dir / "meta.json";
  const json meta = read_json_file(meta_path);
  const auto part = [&](const json& j, const fs::path& file, const char* key) -> const json& {
    if (!j.is_object() || !j.contains(key) || !j[key].is_object())
      throw std::runtime_error("'" + file.string() + "' has no object \"" + key + "\"");
    return j[key];
  };
  const json& run = part(meta, meta_path, "run");
  const json& q = part(meta, meta_path, "quality");
  const json& sheet = part(meta, meta_path, "sheet");
  const auto count = [](const json& j, const char* key, long long fallback) {
    return j.contains(key) && j[key].is_number_integer() ? j[key].get<long long>() : fallback;
  };
  double closest = std::numeric_limits<double>::infinity();
  if (q.contains("min_obstacle_distance") && q["min_obstacle_distance"].is_array())
    for (const auto& d : q["min_obstacle_distance"])
      if (d.is_number()) closest = std::min(closest, d.get<double>());
  json row = {{"vertices", count(sheet, "vertices", 0)},
              {"steps", count(run, "steps", 0)},
              {"newton_iterations", count(run, "newton_iterations", 0)},
              {"sim_wall_seconds", number_or(run, "wall_seconds", -1)},
              {"max_stretch", number_or(q, "max_principal_stretch", -1)},
              {"closest_obstacle_distance", std::isfinite(closest) ? json(closest) : json(nullptr)},
              {"self_intersections", count(q, "self_intersections", -1)},
              {"crease_length", nullptr},
              {"abs_curvature_integral", nullptr}};
  const fs::path metrics_path = dir / "metrics.json";
  if (fs::exists(metrics_path)) {
    const json m = read_json_file(metrics_path);
    const bool listed =
        m.is_object() && m.contains("meshes") && m["meshes"].is_array() && !m["meshes"].empty();
    const json& entry = listed ? m["meshes"][0] : m;
    const json& mesh = entry.is_object() && entry.contains("metrics") ? entry["metrics"] : entry;
    if (!mesh.is_object())
      throw std::runtime_error("'" + metrics_path.string() + "' holds no metrics object");
    if (mesh.contains("creases"))
      row["crease_length"] = number_or(part(mesh, metrics_path, "creases"), "total_length", 0.0);
    if (mesh.contains("developability"))
      row["abs_curvature_integral"] =
          number_or(part(mesh, metrics_path, "developability"), "angle_defect_integral", 0.0);
  }
  return row;
}

fs::path checkpoint_folder(const fs::path& root, const batch::Task& task) {
  return root / ".checkpoints" / batch::safe_name(task.key);
}

namespace {

/// The scene a checkpoint folder was started with (written by the batch beside the
/// checkpoint), compared as text with the sample's scene.json.
constexpr const char* CHECKPOINT_SCENE = "batch_scene.json";

/// Whether `cdir` holds a readable checkpoint of this very scene.json; removes the folder's
/// contents otherwise (another scene, or a checkpoint a crash left unreadable), so the run
/// starts over and saves its own.
bool usable_checkpoint(const fs::path& cdir, const fs::path& scene_file) {
  bool usable = fs::exists(cdir / "checkpoint.json") && fs::exists(cdir / CHECKPOINT_SCENE) &&
                read_text_file(cdir / CHECKPOINT_SCENE) == read_text_file(scene_file);
  if (usable) {
    try {
      load_checkpoint(cdir.string());  // the sheet file read whole (milliseconds)
    } catch (const std::exception&) {
      usable = false;
    }
  }
  if (!usable) {
    std::error_code ec;
    fs::remove_all(cdir, ec);
    fs::create_directories(cdir);
    batch::write_file_atomically(cdir / CHECKPOINT_SCENE, read_text_file(scene_file));
  }
  return usable;
}

}  // namespace

batch::BatchSpec mesh_batch_spec(const fs::path& root, const fs::path& papersim, bool with_metrics,
                                 int checkpoint_every) {
  batch::BatchSpec spec;
  spec.root = root;
  spec.prepare = [](const batch::Task& t, const fs::path& stage) {
    const json info = t.info_object();
    const Scene scene = apply_overrides(
        make_scenario(info.at("scenario").get<std::string>(), info.at("seed").get<std::uint64_t>()),
        info.value("set", json::object()), "--set");
    fs::create_directories(stage / "out");
    std::ostringstream text;
    text << std::setw(2) << scene_to_json(scene) << '\n';
    batch::write_file_atomically(stage / "out" / "scene.json", text.str());
  };
  spec.commands = [papersim, with_metrics, checkpoint_every, root](const batch::Task& t,
                                                                   const fs::path& stage) {
    const fs::path out = stage / "out";
    std::vector<batch::Command> c{{{papersim.string(), "run", (out / "scene.json").string(),
                                    "--out", out.string(), "--quiet"},
                                   {}}};
    if (checkpoint_every > 0) {
      const fs::path cdir = checkpoint_folder(root, t);
      std::vector<std::string>& run = c[0].argv;
      if (usable_checkpoint(cdir, out / "scene.json"))
        run.insert(run.end(), {"--resume", cdir.string()});
      run.insert(run.end(), {"--checkpoint", cdir.string(), "--checkpoint-every",
                             std::to_string(checkpoint_every)});
    }
    if (with_metrics)
      c.push_back({{papersim.string(), "metrics", (out / "sheet.ply").string(), "--json"},
                   stage / "metrics.json"});
    return c;
  };
  spec.finalize = [with_metrics, root](const batch::Task& t, const batch::Attempt& a) {
    fs::path out = a.stage / "out";
    for (const char* f : {"scene.json", "sheet.obj", "sheet.ply", "meta.json"})
      if (!fs::exists(out / f)) throw std::runtime_error(std::string("missing ") + f);
    if (with_metrics) {
      json m = read_json_file(a.stage / "metrics.json");  // throws when incomplete
      // The mesh path names the staging folder: make it relative to the sample folder.
      if (m.contains("meshes") && !m["meshes"].empty()) m["meshes"][0]["path"] = "sheet.ply";
      std::ostringstream text;
      text << std::setw(2) << m << '\n';
      batch::write_file_atomically(out / "metrics.json", text.str());
    }
    // The sample is whole: its checkpoint (also one left by an earlier run with checkpoints,
    // when this one has none) is not needed again.
    std::error_code ec;
    fs::remove_all(checkpoint_folder(root, t), ec);
    return out;
  };
  if (checkpoint_every > 0)
    spec.running_share = [root](const batch::Task& t) {  // the time of the last checkpoint
      try {
        const json c = json::parse(read_text_file(checkpoint_folder(root, t) / "checkpoint.json"));
        const double duration = c.at("scene").at("duration").get<double>();
        return duration > 0 ? std::clamp(c.at("time").get<double>() / duration, 0.0, 1.0) : -1.0;
      } catch (const json::exception&) {  // no checkpoint yet, or not one of ours
        return -1.0;
      }
    };
  spec.manifest_row = [](const batch::Task&, const fs::path& dir, double wall) {
    json row = mesh_manifest_fields(dir);
    row["wall_seconds"] = wall >= 0 ? wall : row["sim_wall_seconds"].get<double>();
    return row;
  };
  spec.failure_reason = [](int code, const std::string&) -> std::string {
    if (code == 2) return "bad scene";
    if (code == 3) return "simulation failed";
    return "";
  };
  return spec;
}

namespace {

/// Read the seed range `text` ("A-B" or "A") into `range`; what is wrong with it, or "".
std::string read_seed_range(const std::string& text,
                            std::pair<std::uint64_t, std::uint64_t>& range) {
  const auto dash = text.find('-');
  const std::string a = text.substr(0, dash),
                    b = dash == std::string::npos ? a : text.substr(dash + 1);
  for (const std::string& s : {a, b})
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos)
      return "is not A-B or A (non-negative integers, B >= A)";
  if (a.size() > 18 || b.size() > 18)
    return "has a seed of more than 18 digits (the largest seed is 999999999999999999)";
  range = {std::stoull(a), std::stoull(b)};
  return range.second < range.first ? "has its last seed below the first" : "";
}

}  // namespace

std::pair<std::uint64_t, std::uint64_t> parse_seed_range(const std::string& text) {
  std::pair<std::uint64_t, std::uint64_t> range;
  const std::string problem = read_seed_range(text, range);
  if (!problem.empty()) throw SceneError("--seeds '" + text + "' " + problem);
  return range;
}

std::vector<std::pair<std::uint64_t, std::uint64_t>> parse_seeds(const std::string& text) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    std::pair<std::uint64_t, std::uint64_t> range;
    const std::string problem = read_seed_range(part, range);
    if (!problem.empty()) throw SceneError("--seeds '" + text + "': '" + part + "' " + problem);
    ranges.push_back(range);
    for (std::size_t i = 0; i + 1 < ranges.size(); ++i)
      if (ranges[i].first <= ranges.back().second && ranges.back().first <= ranges[i].second)
        throw SceneError("--seeds '" + text + "': '" + part + "' overlaps an earlier part");
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return ranges;
}

}  // namespace papersim::simulation
