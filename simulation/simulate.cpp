#include "simulation/simulate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <sstream>

#include "common/atomic_file.hpp"
#include "common/errors.hpp"
#include "remesh/errors.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/errors.hpp"
#include "simulation/linear_solver.hpp"
#include "simulation/output_files.hpp"
#include "simulation/run.hpp"

#ifndef PAPERSIM_VERSION_STRING
#define PAPERSIM_VERSION_STRING "unknown"
#endif

namespace papersim::simulation {

namespace fs = std::filesystem;
using nlohmann::json;

const char* version() { return PAPERSIM_VERSION_STRING; }

namespace {

constexpr const char* CHECKPOINT_FORMAT = "papersim checkpoint 1";

// One writer and one reader per record, shared by meta.json and a checkpoint's `run`.

/// A number that may be infinite (an extreme not met yet): null in JSON.
json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double number_or(const json& v, double missing) { return v.is_null() ? missing : v.get<double>(); }

json step_stats_json(const StepStats& s) {
  return {{"substeps", s.substeps},
          {"failed_solves", s.failed_solves},
          {"projected_hessians", s.projected_hessians},
          {"exact_skipped", s.exact_skipped},
          {"newton_iterations", s.newton_iterations},
          {"line_search_evaluations", s.line_search_evaluations},
          {"extrapolations", s.extrapolations},
          {"trust_region_steps", s.trust_region_steps},
          {"reused_factorizations", s.reused_factorizations},
          {"following_iterations", s.following_iterations},
          {"seconds_assembly", s.seconds_assembly},
          {"seconds_solve", s.seconds_solve},
          {"seconds_line_search", s.seconds_line_search},
          {"residual", s.residual}};
}

StepStats step_stats_from_json(const json& s) {
  StepStats o;
  o.substeps = s.at("substeps").get<int>();
  o.failed_solves = s.at("failed_solves").get<int>();
  o.projected_hessians = s.at("projected_hessians").get<int>();
  o.exact_skipped = s.at("exact_skipped").get<int>();
  o.newton_iterations = s.at("newton_iterations").get<int>();
  o.line_search_evaluations = s.at("line_search_evaluations").get<int>();
  o.extrapolations = s.at("extrapolations").get<int>();
  o.trust_region_steps = s.value("trust_region_steps", 0);  // absent from older checkpoints
  o.reused_factorizations = s.at("reused_factorizations").get<int>();
  o.following_iterations = s.at("following_iterations").get<int>();
  o.seconds_assembly = s.at("seconds_assembly").get<double>();
  o.seconds_solve = s.at("seconds_solve").get<double>();
  o.seconds_line_search = s.at("seconds_line_search").get<double>();
  o.residual = s.at("residual").get<double>();
  return o;
}

json contact_json(const ContactStatistics& c) {
  return {{"seconds", c.seconds},
          {"max_friction_points", c.max_friction_points},
          {"max_normal_force", c.max_normal_force}};
}

ContactStatistics contact_from_json(const json& c) {
  ContactStatistics o;
  o.seconds = c.at("seconds").get<double>();
  o.max_friction_points = c.at("max_friction_points").get<int>();
  o.max_normal_force = c.at("max_normal_force").get<double>();
  return o;
}

json self_contact_json(const SelfContactStatistics& c) {
  return {{"seconds", c.seconds},
          {"max_active_pairs", c.max_active_pairs},
          {"pattern_changes", c.pattern_changes},
          {"stiffness_doublings", c.stiffness_doublings},
          {"max_stiffness", c.max_stiffness}};
}

SelfContactStatistics self_contact_from_json(const json& c) {
  SelfContactStatistics o;
  o.seconds = c.at("seconds").get<double>();
  o.max_active_pairs = c.at("max_active_pairs").get<int>();
  o.pattern_changes = c.at("pattern_changes").get<int>();
  // absent before the adaptive stiffness
  o.stiffness_doublings = c.value("stiffness_doublings", 0);
  o.max_stiffness = c.value("max_stiffness", 0.0);
  return o;
}

json remesh_json(const RemeshTotals& r) {
  return {{"passes", r.passes},
          {"rollbacks", r.rollbacks},
          {"rescues", r.rescues},
          {"rollback_reasons", r.rollback_reasons},
          {"splits", r.splits},
          {"flips", r.flips},
          {"collapses", r.collapses},
          {"refusals", r.refusals},
          {"seconds_remesh", r.seconds_remesh},
          {"seconds_rebuild", r.seconds_rebuild},
          {"max_energy_jump", r.max_energy_jump},
          {"max_energy_jump_relative", r.max_energy_jump_relative}};
}

RemeshTotals remesh_from_json(const json& r) {
  RemeshTotals x;
  x.passes = r.at("passes").get<int>();
  x.rollbacks = r.at("rollbacks").get<int>();
  x.rescues = r.value("rescues", 0);  // absent from checkpoints written before rescues
  x.rollback_reasons = r.at("rollback_reasons").get<std::map<std::string, int>>();
  x.splits = r.at("splits").get<int>();
  x.flips = r.at("flips").get<int>();
  x.collapses = r.at("collapses").get<int>();
  x.refusals = r.at("refusals").get<std::map<std::string, int>>();
  x.seconds_remesh = r.at("seconds_remesh").get<double>();
  x.seconds_rebuild = r.at("seconds_rebuild").get<double>();
  x.max_energy_jump = r.at("max_energy_jump").get<double>();
  x.max_energy_jump_relative = r.at("max_energy_jump_relative").get<double>();
  return x;
}

json lifts_json(const std::vector<RunQuality::LiftExtremes>& lifts) {
  json a = json::array();
  for (const auto& l : lifts)
    a.push_back({{"obstacle", l.obstacle}, {"max_load", l.max_load}, {"max_rise", l.max_rise}});
  return a;
}

/// The running extremes of RunQuality (not the figures measured at the end).
json quality_extremes_json(const RunQuality& q) {
  json distances = json::array();
  for (double d : q.min_obstacle_distance) distances.push_back(finite_or_null(d));
  return {{"max_principal_stretch", q.max_principal_stretch},
          {"min_principal_stretch", q.min_principal_stretch},
          {"max_speed", q.max_speed},
          {"min_obstacle_distance", distances},
          {"lifts", lifts_json(q.lifts)}};
}

RunQuality quality_extremes_from_json(const json& q) {
  RunQuality o;
  o.max_principal_stretch = q.at("max_principal_stretch").get<double>();
  o.min_principal_stretch = q.at("min_principal_stretch").get<double>();
  o.max_speed = q.at("max_speed").get<double>();
  for (const json& d : q.at("min_obstacle_distance"))
    o.min_obstacle_distance.push_back(number_or(d, INF));
  for (const json& l : q.at("lifts"))
    o.lifts.push_back({l.at("obstacle").get<int>(), l.at("max_load").get<double>(),
                       l.at("max_rise").get<double>()});
  return o;
}

}  // namespace

json meta_json(const Scene& scene, const RunResult& r, const json& extra) {
  json m;
  m["program"] = "papersim";
  m["version"] = version();
  if (const std::string k = blas_kernels(); !k.empty()) m["blas_kernels"] = k;
  m["scene"] = scene_to_json(scene);
  if (!scene.scenario.empty()) m["scenario"] = scene.scenario;
  if (scene.seed >= 0) m["seed"] = scene.seed;
  const MeshCounts& c = r.sheet;
  m["sheet"] = {{"width", scene.sheet.width},
                {"height", scene.sheet.height},
                {"vertices", c.vertices},
                {"faces", c.faces},
                {"vertices_start", c.vertices_start},
                {"faces_start", c.faces_start},
                {"vertices_max", c.vertices_max},
                {"faces_max", c.faces_max}};
  json& run = m["run"] = step_stats_json(r.totals);
  run["wall_seconds"] = r.wall_seconds;
  run["steps"] = r.steps;
  run["time_step"] = r.time_step;
  run["pattern_changes"] = r.pattern_changes;
  if (r.contact) run["contact"] = contact_json(*r.contact);
  if (r.self_contact) run["self_contact"] = self_contact_json(*r.self_contact);
  if (r.remesh) {
    const RemeshTotals& rm = *r.remesh;
    run["remesh"] = remesh_json(rm);
    run["remesh"]["share_of_wall_time"] =
        r.wall_seconds > 0 ? (rm.seconds_remesh + rm.seconds_rebuild) / r.wall_seconds : 0.0;
  }
  const RunQuality& q = r.quality;
  m["quality"] = {{"max_principal_stretch", q.max_principal_stretch},
                  {"min_principal_stretch", q.min_principal_stretch},
                  {"strain_limit", q.strain_limit},
                  {"max_speed", q.max_speed},
                  {"min_obstacle_distance", q.min_obstacle_distance},
                  {"self_intersections", q.self_intersections}};
  if (q.max_handle_error) m["quality"]["max_handle_error"] = *q.max_handle_error;
  if (!q.lifts.empty()) m["quality"]["lifts"] = lifts_json(q.lifts);
  const EnergyBreakdown& e = r.energy;
  m["energy"] = {
      {"stretch", e.stretch}, {"bend", e.bend}, {"gravity", e.gravity}, {"kinetic", e.kinetic}};
  for (auto it = extra.begin(); it != extra.end(); ++it) m[it.key()] = it.value();
  return m;
}

json tally_to_json(const RunTally& t) {
  return {{"wall_seconds", t.wall_seconds},
          {"totals", step_stats_json(t.totals)},
          {"pattern_changes", t.pattern_changes},
          {"sheet",
           {{"vertices_start", t.sheet.vertices_start},
            {"faces_start", t.sheet.faces_start},
            {"vertices_max", t.sheet.vertices_max},
            {"faces_max", t.sheet.faces_max}}},
          {"contact", contact_json(t.terms.contact)},
          {"self_contact", self_contact_json(t.terms.self_contact)},
          {"quality", quality_extremes_json(t.quality)},
          {"remesh", remesh_json(t.remesh)},
          {"energy_min", finite_or_null(t.energy_min)},
          {"energy_max", finite_or_null(t.energy_max)}};
}

RunTally tally_from_json(const json& j) {
  RunTally t;
  t.wall_seconds = j.at("wall_seconds").get<double>();
  t.totals = step_stats_from_json(j.at("totals"));
  t.pattern_changes = j.at("pattern_changes").get<long>();
  const json& m = j.at("sheet");
  t.sheet.vertices_start = m.at("vertices_start").get<int>();
  t.sheet.faces_start = m.at("faces_start").get<int>();
  t.sheet.vertices_max = m.at("vertices_max").get<int>();
  t.sheet.faces_max = m.at("faces_max").get<int>();
  t.terms.contact = contact_from_json(j.at("contact"));
  t.terms.self_contact = self_contact_from_json(j.at("self_contact"));
  t.quality = quality_extremes_from_json(j.at("quality"));
  t.remesh = remesh_from_json(j.at("remesh"));
  t.energy_min = number_or(j.at("energy_min"), INF);
  t.energy_max = number_or(j.at("energy_max"), -INF);
  return t;
}

namespace {

// The matrix of a checkpoint's reusable factorisation: this header, the number of entries
// (uint64), then the entries (doubles), both in the machine's byte order.
constexpr char MATRIX_HEADER[] = "papersim matrix 1\n";
constexpr size_t MATRIX_HEADER_SIZE = sizeof MATRIX_HEADER - 1;

void write_matrix_file(const fs::path& file, const std::vector<double>& values) {
  common::write_file_atomically(file, [&](std::ostream& out) {
    const std::uint64_t n = values.size();
    out.write(MATRIX_HEADER, MATRIX_HEADER_SIZE);
    out.write(reinterpret_cast<const char*>(&n), sizeof n);
    out.write(reinterpret_cast<const char*>(values.data()),
              static_cast<std::streamsize>(n * sizeof(double)));
  });
}

/// @throw std::runtime_error saying what is wrong with the file
std::vector<double> read_matrix_file(const fs::path& file, std::uint64_t entries) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot be read");
  std::string header(MATRIX_HEADER_SIZE, '\0');
  std::uint64_t n = 0;
  in.read(header.data(), static_cast<std::streamsize>(header.size()));
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  if (!in || header != MATRIX_HEADER) throw std::runtime_error("is not a papersim matrix file");
  if (n != entries)
    throw std::runtime_error("holds " + std::to_string(n) + " entries, checkpoint.json says " +
                             std::to_string(entries));
  // The size first, so that a count no file could hold allocates nothing.
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(file, ec);
  if (ec || n > (size - MATRIX_HEADER_SIZE - sizeof n) / sizeof(double) ||
      size != MATRIX_HEADER_SIZE + sizeof n + n * sizeof(double))
    throw std::runtime_error("is not " + std::to_string(n) + " entries long");
  std::vector<double> values(n);
  in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(n * sizeof(double)));
  if (!in) throw std::runtime_error("is not " + std::to_string(n) + " entries long");
  return values;
}

std::string checkpoint_file_name(int step, const char* extension) {
  std::ostringstream name;
  name << "checkpoint_" << std::setw(8) << std::setfill('0') << step << extension;
  return name.str();
}

}  // namespace

void save_checkpoint(const std::string& dir, const Scene& scene, int step,
                     const remesh::SheetMesh& mesh, const SheetState& state, const RunTally* tally,
                     const std::vector<std::array<int, 3>>* self_contact_pattern,
                     const ReusableFactor* factor) {
  const fs::path d(dir);
  std::error_code ec;
  fs::create_directories(d, ec);
  if (ec) throw common::OutputError(dir + ": cannot create the checkpoint folder: " + ec.message());
  std::vector<std::string> previous;  // the files the checkpoint it replaces names
  try {
    const json p = json::parse(std::ifstream(d / "checkpoint.json"));
    previous.push_back(p.at("sheet").get<std::string>());
    if (p.contains("reusable_factor"))
      previous.push_back(p.at("reusable_factor").at("file").get<std::string>());
  } catch (const std::exception&) {
  }
  const std::string name = checkpoint_file_name(step, ".ply");
  remesh::write_sheet_file((d / name).string(), mesh, state.positions_matrix(),
                           state.velocities_matrix(), scene.sheet.width, scene.sheet.height);
  json j = {{"format", CHECKPOINT_FORMAT},
            {"step", step},
            {"time", state.time},
            {"sheet", name},
            {"version", version()},
            {"scene", scene_to_json(scene)},
            {"contact_stiffness", state.contact_stiffness},
            {"self_contact_stiffness", state.self_contact_stiffness}};
  if (tally) j["run"] = tally_to_json(*tally);
  if (self_contact_pattern && !self_contact_pattern->empty())
    j["self_contact_pattern"] = *self_contact_pattern;
  std::vector<std::string> current = {name};
  if (factor) {
    const std::string matrix = checkpoint_file_name(step, ".factor");
    write_matrix_file(d / matrix, factor->values);
    j["reusable_factor"] = {{"file", matrix},
                            {"h", factor->h},
                            {"reused", factor->reused},
                            {"entries", factor->values.size()}};
    current.push_back(matrix);
  }
  common::write_text_atomically(d / "checkpoint.json", j.dump(1) + "\n");
  for (const std::string& p : previous)
    if (!p.empty() && p.find('/') == std::string::npos &&
        std::find(current.begin(), current.end(), p) == current.end())
      fs::remove(d / p, ec);
}

Checkpoint load_checkpoint(const std::string& dir) {
  const fs::path file = fs::path(dir) / "checkpoint.json";
  const std::string where = file.string() + ": ";
  std::ifstream in(file);
  if (!in) throw SceneError(where + "cannot be read (no checkpoint in " + dir + ")");
  Checkpoint c;
  std::string sheet;
  try {
    const json j = json::parse(in);
    if (j.value("format", std::string()) != CHECKPOINT_FORMAT)
      throw SceneError(where + "key 'format' is not \"" + CHECKPOINT_FORMAT + "\"");
    c.step = j.at("step").get<int>();
    c.time = j.at("time").get<double>();
    c.state.contact_stiffness = j.value("contact_stiffness", 0.0);  // absent before the load rule
    // absent before the adaptive stiffness
    c.state.self_contact_stiffness = j.value("self_contact_stiffness", 0.0);
    sheet = j.at("sheet").get<std::string>();
    c.scene = j.at("scene");
    if (j.contains("self_contact_pattern")) {  // absent before it was saved, and when empty
      try {
        c.self_contact_pattern =
            j.at("self_contact_pattern").get<std::vector<std::array<int, 3>>>();
      } catch (const json::exception& e) {
        throw SceneError(where + "key 'self_contact_pattern': " + e.what());
      }
    }
    if (j.contains("reusable_factor")) {  // absent without one, and before it was saved
      const std::string key = where + "key 'reusable_factor': ";
      std::string file;
      std::uint64_t entries = 0;
      try {
        const json& f = j.at("reusable_factor");
        file = f.at("file").get<std::string>();
        entries = f.at("entries").get<std::uint64_t>();
        c.factor = ReusableFactor{f.at("h").get<double>(), f.at("reused").get<int>(), {}};
      } catch (const json::exception& e) {
        throw SceneError(key + e.what());
      }
      if (file.empty() || file.find('/') != std::string::npos)
        throw SceneError(key + "'file' is not a file name in the checkpoint folder");
      try {
        c.factor->values = read_matrix_file(fs::path(dir) / file, entries);
      } catch (const std::runtime_error& e) {
        throw SceneError(key + file + " " + e.what());
      }
    }
    if (j.contains("run")) {
      try {
        c.tally = tally_from_json(j.at("run"));
      } catch (const json::exception& e) {
        throw SceneError(where + "key 'run': " + e.what());
      }
    }
  } catch (const json::exception& e) {
    throw SceneError(where + e.what());
  }
  if (sheet.empty() || sheet.find('/') != std::string::npos)
    throw SceneError(where + "key 'sheet' is not a file name in the checkpoint folder");
  try {
    remesh::SheetData d = remesh::read_sheet((fs::path(dir) / sheet).string());
    c.mesh = std::move(d.mesh);
    c.state.positions = flatten(d.positions);
    c.state.velocities = flatten(d.velocities);
    c.state.time = c.time;
  } catch (const std::runtime_error& e) {  // remesh::IoError, remesh::MeshError
    throw SceneError(where + "key 'sheet': " + e.what());
  }
  return c;
}

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  const auto t_start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  double wall_before = 0.0;  // wall time of the run before the checkpoint it continues from [s]
  Run run(scene, options.trace);
  json resumed;
  if (!options.resume_from.empty()) {
    const Checkpoint c = load_checkpoint(options.resume_from);
    const Scene saved =
        scene_from_json(c.scene, (fs::path(options.resume_from) / "checkpoint.json").string());
    // Another time step continues from the step at the checkpoint's time (Run::resume refuses
    // a time that is not a whole number of the scene's steps).
    const int step = saved.time_step == scene.time_step
                         ? c.step
                         : static_cast<int>(std::lround(c.time / run.time_step()));
    run.resume(c.mesh, c.state, step, &saved, c.tally ? &*c.tally : nullptr,
               &c.self_contact_pattern);
    if (c.tally) wall_before = c.tally->wall_seconds;
    // Numbers that differ only in rounding are not changes: the keyframes of an obstacle that
    // yields are rebuilt from its motion, whose Euler angles come back within 1e-13 degrees.
    json changes = json::array();
    for (const auto& patch : json::diff(c.scene, scene_to_json(run.scene()))) {
      const json::json_pointer at(patch.at("path").get<std::string>());
      if (patch.at("op") == "replace" && patch.at("value").is_number() && c.scene.contains(at) &&
          c.scene.at(at).is_number()) {
        const double a = c.scene.at(at).get<double>(), b = patch.at("value").get<double>();
        if (std::abs(a - b) <= 1e-12 * std::max({1.0, std::abs(a), std::abs(b)})) continue;
      }
      changes.push_back(patch.at("path"));
    }
    // The same scene's next step starts from the factorisation the saved run would have
    // started from; a changed scene (other solver settings or time step) factors its own.
    if (c.factor && changes.empty()) run.adopt_factor(*c.factor);
    resumed = {{"from", options.resume_from},
               {"step", step},
               {"time", c.time},
               {"scene_changes", changes},
               {"whole_run", c.tally.has_value()}};
  }
  Staging staging(options.out_dir);
  if (!scene.source.empty()) staging.protect(scene.source);
  const int frames_every =
      options.frames_every >= 0 ? options.frames_every : scene.output.frames_every;
  if (staging.active() && frames_every > 0) fs::create_directories(staging.dir() / "frames");
  const int steps = run.steps_total();
  int last_percent = -1;
  double last_report = 0.0;            // elapsed() at the last progress call
  const int first = run.steps_done();  // > 0 when resumed
  for (int k = first + 1; k <= steps; ++k) {
    run.step();
    if (options.poll_stop) options.poll_stop();
    if (options.checkpoint_every > 0 && k % options.checkpoint_every == 0 && k < steps) {
      const RunTally tally = run.tally(wall_before + elapsed());
      const std::vector<std::array<int, 3>> pattern = run.self_contact_pattern();
      const std::optional<ReusableFactor> factor = run.reusable_factor();
      save_checkpoint(options.checkpoint_dir, run.scene(), k, run.mesh(), run.state(), &tally,
                      &pattern, factor ? &*factor : nullptr);
    }
    if (options.on_step) {
      StepReport report;
      report.step = k;
      report.state = &run.state();
      report.mesh = &run.mesh();
      report.mechanical_energy = run.energies().mechanical();
      report.remesh_energy_change = run.remesh_energy_change();
      report.max_stretch = run.step_stretch();
      report.obstacle_distance = run.step_obstacle_distance();
      options.on_step(report);
    }
    if (staging.active() && frames_every > 0 && k % frames_every == 0) {
      std::ostringstream name;
      name << "frame_" << std::setw(6) << std::setfill('0') << k << ".obj";
      remesh::write_sheet_file((staging.dir() / "frames" / name.str()).string(), run.mesh(),
                               run.state().positions_matrix(), run.state().velocities_matrix(),
                               scene.sheet.width, scene.sheet.height);
    }
    const double fraction = double(k - first) / (steps - first);
    const int percent = static_cast<int>(100.0 * fraction);
    if (options.progress &&
        (percent != last_percent || elapsed() - last_report >= options.progress_every)) {
      last_percent = percent;
      last_report = elapsed();
      options.progress(fraction, last_report);
    }
  }
  RunResult r = run.result(wall_before + elapsed());
  if (staging.active()) {
    write_outputs(staging.dir(), scene, r.mesh, r.state);
    for (const auto& [name, text] : options.extra_files)
      common::write_text_atomically(staging.dir() / name, text);
    json extra = options.extra_meta;
    if (!resumed.is_null()) extra["resumed"] = resumed;
    write_json(staging.dir() / "meta.json", meta_json(scene, r, extra));
    staging.commit();
  }
  return r;
}

}  // namespace papersim::simulation
