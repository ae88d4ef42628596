// papersim_bench: a fixed set of scenario draws run at the defaults through `papersim` child
// processes (issue 15 item 4). Per scenario it prints the median and worst wall time, CPU time
// (the child's user + system time from wait4) and Newton iterations (meta.json `run`), the
// safety checks of every run (finite result, no penetration, no self-intersection, stretch within
// the limit, from meta.json `quality`), and with --references the RMS vertex distance to a
// converged reference of each draw at the same material points (validation/compare.hpp, as the
// run-time-against-error study), over the draws whose reference holds under refinement.
//
// Each draw is drawn once by the measured binary (`papersim scenario NAME --seed N --draw-only`)
// and run by `papersim run`. With --baseline BIN the other binary runs the same draw, interleaved
// run by run (the order alternates from draw to draw): the scene is the measured binary's draw
// with the resolution and solver keys (time_step, sheet.edge_length, solver) taken from BIN's
// own draw of the same (scenario, seed), i.e. at BIN's defaults, and keys BIN's scene reader
// does not know dropped (BIN's own draw shows which keys it writes). This keeps the obstacles,
// gravity and handles identical even when BIN draws scenes from other random streams. With
// --repeat K every binary runs each draw K times, interleaved, and a draw keeps its fastest run's
// wall and CPU time: on a shared machine the noise only adds time, and per-run CPU times of the
// same work were measured 40% apart there (docs/performance.md).
//
// --make-references DIR runs every draw at the converged settings of reference_settings() and
// again one refinement finer (the check); a draw whose reference moves by more than --target mm
// RMS under that refinement has no converged answer (a draped sheet changing fold pattern, as in
// the pull study) and is left out of the error figures.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "common/cli_checks.hpp"
#include "remesh/sheet_io.hpp"
#include "validation/compare.hpp"
#include "validation/statistics.hpp"

namespace fs = std::filesystem;
namespace pv = papersim::validation;
using nlohmann::json;

namespace {

struct BenchError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Converged settings of a scenario's references.
struct ReferenceSettings {
  double edge_mm = 5;          ///< edge length of the reference [mm]
  double step_ms = 2.5;        ///< time step of the reference (and of its check) [ms]
  double check_edge_mm = 3.5;  ///< the check's edge length [mm]
};

/// The references' settings. pull: the run-time-against-error study's (README, Measurements:
/// 5 mm edges, 2.5 ms steps, checked at 3.5 mm; its error is set by the edge length, 7 mm edges
/// at 20 / 10 / 5 ms differ by less than the 5 mm reference's own change under refinement).
/// fall-cylinder: its study's references (docs/performance.md: 5 mm, 0.5 ms, a quarter of the
/// 2 ms default it had then). The other fall scenarios: the same edges (half their 10 mm
/// default, as pull's 5 mm is 0.7 of its 7 mm) and a quarter of their default step (as pull's
/// 2.5 ms is a quarter of 10 ms), the settings their run-time studies then used.
ReferenceSettings reference_settings(const std::string& scenario) {
  if (scenario == "fall-cylinder") return {5, 0.5, 3.5};
  if (scenario == "fall-gable" || scenario == "fall-sphere") return {5, 0.25, 3.5};
  if (scenario == "fall-spheres") return {5, 0.125, 3.5};
  return {5, 2.5, 3.5};
}

/// What one child run measured.
struct Measurement {
  bool ok = false;
  std::string failure;       ///< why not ok: exit status and the end of its log
  double wall = 0, cpu = 0;  ///< [s]
  long newton = 0;
  int vertices = 0;
  std::string unsafe;   ///< the safety checks that failed ("" when all hold)
  double rms_mm = NAN;  ///< against the draw's reference (NaN: none or it does not hold)
};

/// Last `n` characters of a file (for failure messages).
std::string tail_of(const fs::path& path, std::size_t n = 400) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  const std::string t = s.str();
  return t.size() > n ? t.substr(t.size() - n) : t;
}

/// Runs argv with stdout and stderr to `log`, OMP_NUM_THREADS=1; wall and CPU time of the child.
/// Returns the exit status (128 + signal when a signal ended it).
/// @throw BenchError when the program cannot be started.
int run_child(const std::vector<std::string>& argv, const fs::path& log, double& wall,
              double& cpu) {
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) throw BenchError("cannot fork to run " + argv.front());
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    setenv("OMP_NUM_THREADS", "1", 1);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::fprintf(stderr, "cannot execute %s\n", args[0]);
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) < 0) throw BenchError("wait4 failed for " + argv.front());
  wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  cpu = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
        1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

json read_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw BenchError("cannot read " + path.string());
  json j = json::parse(in, nullptr, false);
  if (j.is_discarded()) throw BenchError(path.string() + " is not valid JSON");
  return j;
}

/// `BIN scenario NAME --seed N --out DIR --draw-only`: the drawn scene.
/// @throw BenchError when the binary fails.
json draw_scene(const std::string& bin, const std::string& scenario, long seed,
                const fs::path& dir) {
  fs::create_directories(dir);
  double wall = 0, cpu = 0;
  const fs::path log = dir.string() + ".log";
  const int status = run_child({bin, "scenario", scenario, "--seed", std::to_string(seed), "--out",
                                dir.string(), "--draw-only"},
                               log, wall, cpu);
  if (status != 0)
    throw BenchError(bin + " scenario " + scenario + " --seed " + std::to_string(seed) +
                     " failed (status " + std::to_string(status) + "): " + tail_of(log));
  return read_json(dir / "scene.json");
}

/// `scene` without the keys `known` lacks (recursively through objects and the elements of
/// arrays, each element against `known`'s first element).
json drop_unknown_keys(const json& scene, const json& known) {
  if (scene.is_object() && known.is_object()) {
    json out = json::object();
    for (auto it = scene.begin(); it != scene.end(); ++it)
      if (known.contains(it.key())) out[it.key()] = drop_unknown_keys(it.value(), known[it.key()]);
    return out;
  }
  if (scene.is_array() && known.is_array() && !known.empty()) {
    json out = json::array();
    for (const json& e : scene) out.push_back(drop_unknown_keys(e, known.front()));
    return out;
  }
  return scene;
}

/// The keys that set the resolution and the solver (a binary's defaults), as JSON pointers.
const std::vector<std::string> SETTING_KEYS = {"/time_step", "/sheet/edge_length", "/solver"};

/// The draw `scene` (obstacles, gravity, handles, material) at the settings of `own` (another
/// binary's draw of the same scenario and seed), in the keys that binary knows.
json with_settings_of(const json& scene, const json& own) {
  json out = drop_unknown_keys(scene, own);
  for (const std::string& key : SETTING_KEYS) {
    const json::json_pointer p(key);
    if (own.contains(p)) out[p] = own[p];
  }
  return out;
}

/// Reads meta.json's counts and safety checks into `m`.
void read_meta(const fs::path& dir, Measurement& m) {
  const json meta = read_json(dir / "meta.json");
  m.newton = meta.at("run").at("newton_iterations").get<long>();
  m.vertices = meta.at("sheet").at("vertices").get<int>();
  const json& q = meta.at("quality");
  std::string unsafe;
  if (!(q.at("max_principal_stretch").get<double>() <= 1 + q.at("strain_limit").get<double>()))
    unsafe += "stretch ";
  for (const json& d : q.at("min_obstacle_distance"))
    if (!(d.is_number() && d.get<double>() > 0)) {
      unsafe += "penetration ";
      break;
    }
  if (q.at("self_intersections").get<int>() != 0) unsafe += "self-intersection ";
  m.unsafe = unsafe.empty() ? "" : unsafe.substr(0, unsafe.size() - 1);
}

/// Writes `scene` to DIR/scene.json and runs `BIN run DIR/scene.json --out DIR --quiet`.
Measurement run_scene(const std::string& bin, const json& scene, const fs::path& dir) {
  fs::create_directories(dir);
  const fs::path scene_path = dir.string() + ".scene.json";
  papersim::common::write_text_atomically(scene_path, scene.dump(2) + "\n");
  Measurement m;
  const fs::path log = dir.string() + ".log";
  const int status = run_child({bin, "run", scene_path.string(), "--out", dir.string(), "--quiet"},
                               log, m.wall, m.cpu);
  if (status != 0) {
    m.failure = "status " + std::to_string(status) + ": " + tail_of(log, 200);
    return m;
  }
  read_meta(dir, m);
  m.ok = true;
  return m;
}

pv::SheetGeometry read_geometry(const fs::path& obj) {
  const auto d = papersim::remesh::read_sheet(obj.string());
  return {d.mesh.material_coords(), d.positions, d.mesh.faces()};
}

/// A draw's reference and whether it holds under refinement.
struct Reference {
  bool present = false, holds = false;
  pv::SheetGeometry sheet;
};

/// DIR/SCENARIO/seed_N: reference/, check/ and reference.json ({"holds", "check_rms_mm", ...}).
fs::path reference_dir(const fs::path& root, const std::string& scenario, long seed) {
  return root / scenario / ("seed_" + std::to_string(seed));
}

Reference load_reference(const fs::path& root, const std::string& scenario, long seed) {
  Reference r;
  const fs::path dir = reference_dir(root, scenario, seed);
  if (!fs::exists(dir / "reference.json")) return r;
  r.present = true;
  r.holds = read_json(dir / "reference.json").at("holds").get<bool>();
  r.sheet = read_geometry(dir / "reference" / "sheet.obj");
  return r;
}

/// Options of a benchmark run.
struct BenchOptions {
  std::string papersim, baseline;
  std::vector<std::string> scenarios;
  std::vector<long> seeds;
  fs::path work, references, make_references;
  double duration = 0;  ///< override of every scene's duration [s] (0: the scenario's)
  std::vector<std::pair<json::json_pointer, json>>
      sets;  ///< --set: keys of the test binary's scenes
  double target_mm = 2;
  ReferenceSettings reference_override;  ///< fields > 0 replace reference_settings()
  std::string csv;
  int repeat = 1;  ///< runs per draw and binary; the fastest one's times are kept
};

json with_duration(json scene, double duration) {
  if (duration > 0) scene["duration"] = duration;
  return scene;
}

/// --set KEY=VALUE: a dotted scene key (solver.max_factor_reuse) and a JSON value.
/// @throw BenchError for an item without '=' or a value that is not JSON.
std::vector<std::pair<json::json_pointer, json>> parse_sets(const std::vector<std::string>& items) {
  std::vector<std::pair<json::json_pointer, json>> out;
  for (const std::string& item : items) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw BenchError("--set: '" + item + "' is not KEY=VALUE");
    std::string pointer = "/" + item.substr(0, eq);
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    const json value = json::parse(item.substr(eq + 1), nullptr, false);
    if (value.is_discarded())
      throw BenchError("--set: the value of '" + item + "' is not JSON (a number, true, \"text\")");
    out.emplace_back(json::json_pointer(pointer), value);
  }
  return out;
}

/// The test binary's scene: the drawn one with the duration override and the --set keys.
/// @throw BenchError when a --set key is not a key of the drawn scene.
json test_scene(const BenchOptions& o, const json& drawn) {
  json scene = with_duration(drawn, o.duration);
  for (const auto& [key, value] : o.sets) {
    if (!scene.contains(key)) {
      std::string dotted = key.to_string().substr(1);
      std::replace(dotted.begin(), dotted.end(), '/', '.');
      throw BenchError("--set: '" + dotted + "' is not a key of the drawn scene");
    }
    scene[key] = value;
  }
  return scene;
}

/// Makes (or keeps, when made from the same scene) one draw's reference and its check.
void make_reference(const BenchOptions& o, const std::string& scenario, long seed,
                    const json& drawn) {
  ReferenceSettings s = reference_settings(scenario);
  if (o.reference_override.edge_mm > 0) s.edge_mm = o.reference_override.edge_mm;
  if (o.reference_override.step_ms > 0) s.step_ms = o.reference_override.step_ms;
  if (o.reference_override.check_edge_mm > 0) s.check_edge_mm = o.reference_override.check_edge_mm;
  json scene = with_duration(drawn, o.duration);
  scene["time_step"] = 1e-3 * s.step_ms;
  scene["sheet"]["edge_length"] = 1e-3 * s.edge_mm;
  json check = scene;
  check["sheet"]["edge_length"] = 1e-3 * s.check_edge_mm;
  const fs::path dir = reference_dir(o.make_references, scenario, seed);
  if (fs::exists(dir / "reference.json") &&
      read_json(dir / "reference.json").value("scene", json()) == scene) {
    std::printf("%s seed %ld: reference kept (made from the same scene)\n", scenario.c_str(), seed);
    return;
  }
  fs::remove(dir / "reference.json");
  const Measurement ref = run_scene(o.papersim, scene, dir / "reference");
  if (!ref.ok)
    throw BenchError(scenario + " seed " + std::to_string(seed) + ": the reference run failed, " +
                     ref.failure);
  const Measurement chk = run_scene(o.papersim, check, dir / "check");
  if (!chk.ok)
    throw BenchError(scenario + " seed " + std::to_string(seed) + ": the check run failed, " +
                     chk.failure);
  const pv::SheetDifference d = pv::compare_sheets(read_geometry(dir / "check" / "sheet.obj"),
                                                   read_geometry(dir / "reference" / "sheet.obj"));
  const bool holds = 1e3 * d.rms <= o.target_mm;
  const json info = {{"holds", holds},
                     {"check_rms_mm", 1e3 * d.rms},
                     {"check_max_mm", 1e3 * d.max},
                     {"target_mm", o.target_mm},
                     {"edge_mm", s.edge_mm},
                     {"step_ms", s.step_ms},
                     {"check_edge_mm", s.check_edge_mm},
                     {"reference_cpu_seconds", ref.cpu},
                     {"check_cpu_seconds", chk.cpu},
                     {"scene", scene}};
  papersim::common::write_text_atomically(dir / "reference.json", info.dump(2) + "\n");
  std::printf(
      "%s seed %ld: reference %g mm / %g ms (%d vertices, CPU %.1f s), check at %g mm (CPU %.1f "
      "s): RMS %.3f "
      "mm, max %.3f mm: %s\n",
      scenario.c_str(), seed, s.edge_mm, s.step_ms, ref.vertices, ref.cpu, s.check_edge_mm, chk.cpu,
      1e3 * d.rms, 1e3 * d.max, holds ? "holds" : "does NOT hold");
  std::fflush(stdout);
}

/// One run of the benchmark, as printed and written to the CSV.
struct Row {
  std::string scenario, binary;  ///< binary: "test" or "baseline"
  long seed = 0;
  Measurement m;
};

/// One run's line; `run` is "" or "run k/K" when each draw runs several times.
void print_row(const Row& r, const std::string& run = "") {
  const std::string suffix = run.empty() ? "" : " " + run;
  if (!r.m.ok) {
    std::printf("%-13s %5ld %-8s FAILED %s%s\n", r.scenario.c_str(), r.seed, r.binary.c_str(),
                r.m.failure.c_str(), suffix.c_str());
  } else {
    char rms[32] = "-";
    if (!std::isnan(r.m.rms_mm)) std::snprintf(rms, sizeof rms, "%.3f", r.m.rms_mm);
    std::printf("%-13s %5ld %-8s %8d %9.2f %9.2f %8ld %10s %s%s\n", r.scenario.c_str(), r.seed,
                r.binary.c_str(), r.m.vertices, r.m.wall, r.m.cpu, r.m.newton, rms,
                r.m.unsafe.empty() ? "safe" : ("UNSAFE " + r.m.unsafe).c_str(), suffix.c_str());
  }
  std::fflush(stdout);
}

/// Median and worst of a list.
struct Spread {
  double median = NAN, worst = NAN;
};

Spread spread(const std::vector<double>& v) {
  if (v.empty()) return {};
  return {pv::median(v), *std::max_element(v.begin(), v.end())};
}

/// Per-scenario figures of one binary.
struct Summary {
  int runs = 0, failed = 0, unsafe = 0, with_error = 0;
  Spread wall, cpu, newton, rms;
};

Summary summarise(const std::vector<Row>& rows, const std::string& scenario,
                  const std::string& binary) {
  Summary s;
  std::vector<double> wall, cpu, newton, rms;
  for (const Row& r : rows) {
    if (r.scenario != scenario || r.binary != binary) continue;
    ++s.runs;
    if (!r.m.ok) {
      ++s.failed;
      continue;
    }
    if (!r.m.unsafe.empty()) ++s.unsafe;
    wall.push_back(r.m.wall);
    cpu.push_back(r.m.cpu);
    newton.push_back(static_cast<double>(r.m.newton));
    if (!std::isnan(r.m.rms_mm)) rms.push_back(r.m.rms_mm);
  }
  s.with_error = static_cast<int>(rms.size());
  s.wall = spread(wall), s.cpu = spread(cpu), s.newton = spread(newton), s.rms = spread(rms);
  return s;
}

void print_summary(const std::string& scenario, const std::string& binary, const Summary& s) {
  std::printf("%-13s %-8s %4d %6d %6d %9.2f %9.2f %9.2f %9.2f %9.0f %9.0f", scenario.c_str(),
              binary.c_str(), s.runs, s.failed, s.unsafe, s.wall.median, s.wall.worst, s.cpu.median,
              s.cpu.worst, s.newton.median, s.newton.worst);
  if (s.with_error > 0)
    std::printf(" %9.3f %9.3f %3d\n", s.rms.median, s.rms.worst, s.with_error);
  else
    std::printf(" %9s %9s %3d\n", "-", "-", 0);
}

void write_csv(const std::string& path, const std::vector<Row>& rows) {
  std::ostringstream out;
  out << "scenario,seed,binary,ok,vertices,wall_seconds,cpu_seconds,newton_iterations,rms_error_mm,"
         "safety,failure\n";
  for (const Row& r : rows) {
    std::string failure = r.m.failure;
    std::replace(failure.begin(), failure.end(), ',', ';');
    std::replace(failure.begin(), failure.end(), '\n', ' ');
    out << r.scenario << ',' << r.seed << ',' << r.binary << ',' << (r.m.ok ? "yes" : "no") << ','
        << r.m.vertices << ',' << r.m.wall << ',' << r.m.cpu << ',' << r.m.newton << ','
        << r.m.rms_mm << ',' << (r.m.unsafe.empty() ? "safe" : r.m.unsafe) << ',' << failure
        << '\n';
  }
  papersim::common::write_text_atomically(path, out.str());
}

/// The error of `m` against the draw's reference, when it holds.
void measure_error(const Reference& ref, const fs::path& dir, Measurement& m) {
  if (!m.ok || !ref.holds) return;
  m.rms_mm = 1e3 * pv::compare_sheets(ref.sheet, read_geometry(dir / "sheet.obj")).rms;
}

/// Every draw of one scenario: the test binary's run and, interleaved, the baseline's.
void bench_scenario(const BenchOptions& o, const std::string& scenario, std::vector<Row>& rows) {
  for (std::size_t k = 0; k < o.seeds.size(); ++k) {
    const long seed = o.seeds[k];
    const fs::path dir = o.work / scenario / ("seed_" + std::to_string(seed));
    const json drawn = draw_scene(o.papersim, scenario, seed, dir / "draw");
    const Reference ref =
        o.references.empty() ? Reference{} : load_reference(o.references, scenario, seed);
    if (!o.references.empty() && !ref.present)
      throw BenchError("--references: no reference for " + scenario + " seed " +
                       std::to_string(seed) + " in " + o.references.string() +
                       " (make it with --make-references)");
    std::vector<std::pair<std::string, json>> runs = {{"test", test_scene(o, drawn)}};
    if (!o.baseline.empty()) {
      const json own = draw_scene(o.baseline, scenario, seed, dir / "baseline_draw");
      runs.emplace_back("baseline", with_duration(with_settings_of(drawn, own), o.duration));
      if (k % 2 == 1) std::swap(runs[0], runs[1]);  // alternate the order from draw to draw
    }
    // With --repeat K every binary runs the draw K times, interleaved, the order turned each round.
    // A row keeps the first run's results and the fastest run's wall and CPU time (the machine's
    // noise only adds time); a repeat whose Newton iterations differ fails the row, since the
    // same binary on the same scene must do the same work.
    std::vector<Row> draw_rows;
    for (int k_run = 0; k_run < o.repeat; ++k_run) {
      for (std::size_t i = 0; i < runs.size(); ++i) {
        const auto& [binary_name, scene] = runs[k_run % 2 == 0 ? i : runs.size() - 1 - i];
        const std::string& binary = binary_name;  // a lambda below captures it
        const std::string run =
            o.repeat > 1 ? "run " + std::to_string(k_run + 1) + "/" + std::to_string(o.repeat) : "";
        const fs::path out = dir / (k_run == 0 ? binary : binary + "_repeat");
        Row r{scenario, binary, seed, {}};
        r.m = run_scene(binary == "test" ? o.papersim : o.baseline, scene, out);
        if (k_run == 0) measure_error(ref, out, r.m);
        print_row(r, run);
        if (k_run == 0) {
          draw_rows.push_back(r);
          continue;
        }
        fs::remove_all(out);
        Row& first = *std::find_if(draw_rows.begin(), draw_rows.end(),
                                   [&](const Row& d) { return d.binary == binary; });
        if (!first.m.ok) continue;
        if (!r.m.ok || r.m.newton != first.m.newton) {
          first.m.ok = false;
          first.m.failure =
              run + (r.m.ok
                         ? " took " + std::to_string(r.m.newton) + " Newton iterations against " +
                               std::to_string(first.m.newton) + " in run 1 (not reproducible)"
                         : " failed: " + r.m.failure);
          continue;
        }
        first.m.wall = std::min(first.m.wall, r.m.wall);
        first.m.cpu = std::min(first.m.cpu, r.m.cpu);
      }
    }
    if (o.repeat > 1)
      for (const Row& r : draw_rows) print_row(r, "fastest of " + std::to_string(o.repeat));
    rows.insert(rows.end(), draw_rows.begin(), draw_rows.end());
  }
}

double ratio(double a, double b) { return b > 0 ? a / b : NAN; }

void print_summaries(const BenchOptions& o, const std::vector<Row>& rows) {
  std::printf("\n%-13s %-8s %4s %6s %6s %9s %9s %9s %9s %9s %9s %9s %9s %3s\n", "scenario",
              "binary", "runs", "failed", "unsafe", "wall_med", "wall_max", "cpu_med", "cpu_max",
              "newt_med", "newt_max", "rms_med", "rms_max", "n");
  for (const std::string& s : o.scenarios) {
    print_summary(s, "test", summarise(rows, s, "test"));
    if (!o.baseline.empty()) print_summary(s, "baseline", summarise(rows, s, "baseline"));
  }
  if (o.baseline.empty()) return;
  std::printf(
      "\nratios test / baseline (medians; worst wall time over median wall time per binary)\n");
  std::printf("%-13s %9s %9s %9s %9s %11s %11s\n", "scenario", "wall", "cpu", "newton", "rms",
              "worst/med", "base w/m");
  for (const std::string& s : o.scenarios) {
    const Summary t = summarise(rows, s, "test"), b = summarise(rows, s, "baseline");
    std::printf("%-13s %9.3f %9.3f %9.3f %9.3f %11.2f %11.2f\n", s.c_str(),
                ratio(t.wall.median, b.wall.median), ratio(t.cpu.median, b.cpu.median),
                ratio(t.newton.median, b.newton.median), ratio(t.rms.median, b.rms.median),
                ratio(t.wall.worst, t.wall.median), ratio(b.wall.worst, b.wall.median));
  }
}

/// "0-4" or "0,2,7" (non-negative integers).
std::vector<long> parse_seeds(const std::string& text) {
  std::vector<long> seeds;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    long a = 0, b = 0;
    int used = 0;
    if (std::sscanf(item.c_str(), "%ld-%ld%n", &a, &b, &used) == 2 &&
        used == static_cast<int>(item.size()) && a >= 0 && b >= a && b - a < 100000) {
      for (long s = a; s <= b; ++s) seeds.push_back(s);
    } else if (std::sscanf(item.c_str(), "%ld%n", &a, &used) == 1 &&
               used == static_cast<int>(item.size()) && a >= 0) {
      seeds.push_back(a);
    } else {
      throw BenchError("--seeds: '" + item +
                       "' is not a seed (N) or a range (A-B) of non-negative integers");
    }
  }
  if (seeds.empty()) throw BenchError("--seeds: no seed given");
  return seeds;
}

std::vector<std::string> parse_scenarios(const std::string& text) {
  static const std::vector<std::string> known = {"pull",        "fall-cylinder", "fall-gable",
                                                 "fall-sphere", "fall-spheres",  "fold"};
  std::vector<std::string> out;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ','))
    if (std::find(known.begin(), known.end(), item) == known.end())
      throw BenchError("--scenarios: unknown scenario '" + item +
                       "' (pull, fall-cylinder, fall-gable, fall-sphere, fall-spheres, fold)");
    else
      out.push_back(item);
  if (out.empty()) throw BenchError("--scenarios: no scenario given");
  return out;
}

/// An executable file, or BenchError naming the option.
std::string executable(const std::string& path, const char* option) {
  if (access(path.c_str(), X_OK) != 0 || fs::is_directory(path))
    throw BenchError(std::string(option) + ": '" + path + "' is not an executable file");
  return fs::absolute(path).string();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_bench: scenario draws at the defaults through papersim child processes: median and "
      "worst "
      "wall time, CPU time and Newton iterations per scenario, safety checks, error against "
      "converged "
      "references, and ratios against a baseline binary"};
  BenchOptions o;
  std::string seeds = "0-4", scenarios = "pull,fall-cylinder,fall-gable,fall-sphere,fall-spheres",
              work, papersim = PAPERSIM_EXE;
  std::string make_references, references;
  app.add_option("--papersim", papersim, "the papersim binary measured")->capture_default_str();
  app.add_option("--scenarios", scenarios, "scenarios, comma separated")->capture_default_str();
  app.add_option("--seeds", seeds, "seeds: N, A-B, comma separated")->capture_default_str();
  app.add_option("--baseline", o.baseline,
                 "another papersim binary run on the same draws at its own defaults, "
                 "interleaved run by run; prints the ratios");
  app.add_option(
      "--work", work,
      "folder for the runs' outputs (default: a new folder under the temporary directory, "
      "removed at the end)");
  app.add_option("--references", references,
                 "folder made by --make-references: the error of every run against its "
                 "draw's reference (draws whose reference holds)");
  app.add_option("--make-references", make_references,
                 "make the references of the draws in this folder (the converged "
                 "settings of docs/performance.md, each checked one refinement finer) and stop");
  app.add_option("--target", o.target_mm,
                 "with --make-references: a reference holds when the check run is within "
                 "this RMS distance [mm]")
      ->capture_default_str()
      ->check(papersim::common::positive());
  app.add_option("--reference-edge", o.reference_override.edge_mm,
                 "override the references' edge length [mm]")
      ->check(papersim::common::positive());
  app.add_option("--reference-step", o.reference_override.step_ms,
                 "override the references' time step [ms]")
      ->check(papersim::common::positive());
  app.add_option("--check-edge", o.reference_override.check_edge_mm,
                 "override the checks' edge length [mm]")
      ->check(papersim::common::positive());
  app.add_option("--duration", o.duration,
                 "override every scene's duration [s] (short runs for tests)")
      ->check(papersim::common::positive());
  app.add_option("--repeat", o.repeat,
                 "run every draw K times with each binary, interleaved, and keep the fastest "
                 "run's wall and CPU time (the other results are the first run's; a repeat with "
                 "other Newton "
                 "iterations fails the draw)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--csv", o.csv, "also write every draw as CSV (with --repeat, its fastest times)");
  std::vector<std::string> sets;
  app.add_option("--set", sets,
                 "KEY=VALUE: set a key of the measured binary's scenes (dotted, e.g. "
                 "solver.max_factor_reuse=4; the value is JSON), repeatable; not applied to the "
                 "baseline or the "
                 "references");
  app.footer(
      "Exit status: 0 every run succeeded and passed the safety checks; 1 a run failed or is "
      "unsafe; 2 bad "
      "option or input.");
  CLI11_PARSE(app, argc, argv);
  fs::path scratch;
  try {
    o.papersim = executable(papersim, "--papersim");
    if (!o.baseline.empty()) o.baseline = executable(o.baseline, "--baseline");
    o.seeds = parse_seeds(seeds);
    o.sets = parse_sets(sets);
    o.scenarios = parse_scenarios(scenarios);
    if (!references.empty() && !make_references.empty())
      throw BenchError("--references and --make-references cannot be given together");
    if (!references.empty() && !fs::is_directory(references))
      throw BenchError("--references: '" + references + "' is not a folder");
    o.references = references;
    o.make_references = make_references;
    if (work.empty()) {
      char name[] = "/tmp/papersim_bench_XXXXXX";
      if (!mkdtemp(name)) throw BenchError("cannot create a folder under /tmp");
      scratch = name;
      work = name;
    }
    o.work = fs::absolute(work);
  } catch (const BenchError& e) {
    std::fprintf(stderr, "papersim_bench: %s\n", e.what());
    return 2;
  }
  int status = 0;
  try {
    if (!o.make_references.empty()) {
      for (const std::string& s : o.scenarios)
        for (long seed : o.seeds)
          make_reference(o, s, seed,
                         draw_scene(o.papersim, s, seed,
                                    o.work / s / ("seed_" + std::to_string(seed)) / "draw"));
    } else {
      std::vector<Row> rows;
      std::printf("%-13s %5s %-8s %8s %9s %9s %8s %10s %s\n", "scenario", "seed", "binary",
                  "vertices", "wall_s", "cpu_s", "newton", "rms_mm", "safety");
      for (const std::string& s : o.scenarios) bench_scenario(o, s, rows);
      print_summaries(o, rows);
      if (!o.csv.empty()) write_csv(o.csv, rows);
      for (const Row& r : rows)
        if (!r.m.ok || !r.m.unsafe.empty()) status = 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_bench: %s\n", e.what());
    status = 2;
  }
  if (!scratch.empty()) fs::remove_all(scratch);
  return status;
}
