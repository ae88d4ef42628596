#include "validation/metrics_command.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <nlohmann/json.hpp>
#include <ostream>
#include <set>

#include "common/atomic_file.hpp"
#include "remesh/sheet_io.hpp"
#include "validation/metrics.hpp"
#include "validation/metrics_plots.hpp"

namespace papersim::validation {
namespace {

namespace fs = std::filesystem;

/// Pooled per-element values for plots stay below this many per quantity.
constexpr std::size_t MAX_POOLED_SAMPLES = 2'000'000;

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool is_mesh_file(const fs::path& path) {
  const std::string ext = lower_extension(path);
  return ext == ".obj" || ext == ".ply";
}

/// Mesh files below a folder, a PLY winning over an OBJ of the same name.
std::vector<std::string> meshes_in_folder(const fs::path& folder) {
  std::vector<fs::path> found;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    if (entry.is_regular_file() && is_mesh_file(entry.path())) found.push_back(entry.path());
  std::set<fs::path> plys;
  for (const fs::path& p : found)
    if (lower_extension(p) == ".ply") plys.insert(fs::path(p).replace_extension());
  std::vector<std::string> files;
  for (const fs::path& p : found)
    if (lower_extension(p) == ".ply" || plys.count(fs::path(p).replace_extension()) == 0)
      files.push_back(p.string());
  std::sort(files.begin(), files.end());
  return files;
}

/// The outcome for one mesh.
struct MeshResult {
  std::string path;
  bool ok = false;
  std::string error;
  MeshMetrics metrics;
  MetricsSamples samples;
};

MeshResult measure(const std::string& path, const MetricsOptions& options, bool keep_samples) {
  MeshResult result;
  result.path = path;
  // A bad file must not stop the other meshes: report its message and go on (this is the
  // command's edge, where exceptions become reports).
  try {
    const remesh::SheetData sheet = remesh::read_sheet(path);
    const bool plastic = lower_extension(path) == ".ply";
    result.metrics =
        compute_metrics(sheet, options, plastic, keep_samples ? &result.samples : nullptr);
    result.ok = true;
  } catch (const std::exception& e) {
    result.error = e.what();
  }
  return result;
}

std::vector<MeshResult> measure_all(const std::vector<std::string>& files,
                                    const MetricsCommandOptions& opts, bool keep_samples) {
  MetricsOptions options;
  options.crease_angle_deg = opts.crease_angle_deg;
  options.self_intersections = opts.self_intersections;
  if (keep_samples)
    options.max_samples =
        std::max<std::size_t>(1, MAX_POOLED_SAMPLES / std::max<std::size_t>(1, files.size()));
  std::vector<MeshResult> results(files.size());
  tbb::task_arena arena(opts.threads > 0 ? opts.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, files.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i != range.end(); ++i)
                          results[i] = measure(files[i], options, keep_samples);
                      });
  });
  return results;
}

struct Column {
  const char* title;
  int width;
  double (*get)(const MeshMetrics&);
};

const std::vector<Column>& row_columns() {
  static const std::vector<Column> COLUMNS = {
      {"faces", 8, [](const MeshMetrics& m) { return double(m.faces); }},
      {"strain_max", 11, [](const MeshMetrics& m) { return m.isometry.edge_strain_max; }},
      {"s1_max", 9, [](const MeshMetrics& m) { return m.isometry.s1_max; }},
      {"s2_min", 9, [](const MeshMetrics& m) { return m.isometry.s2_min; }},
      {"int|K|", 10, [](const MeshMetrics& m) { return m.developability.angle_defect_integral; }},
      {"max|K|", 10, [](const MeshMetrics& m) { return m.developability.angle_defect_max; }},
      {"GB_resid", 10, [](const MeshMetrics& m) { return m.developability.gauss_bonnet_residual; }},
      {"creases", 8, [](const MeshMetrics& m) { return double(m.creases.lines); }},
      {"crease_len", 11, [](const MeshMetrics& m) { return m.creases.total_length; }},
      {"junct", 6, [](const MeshMetrics& m) { return double(m.creases.junctions); }},
      {"min_angle", 10, [](const MeshMetrics& m) { return m.quality.min_angle_deg; }},
      {"self_int", 9, [](const MeshMetrics& m) { return double(m.self_intersections); }},
  };
  return COLUMNS;
}

void write_rows(std::ostream& out, const std::vector<MeshResult>& results) {
  out << "mesh";
  for (const Column& c : row_columns()) out << ' ' << std::setw(c.width) << c.title;
  out << '\n';
  for (const MeshResult& r : results) {
    out << r.path;
    if (!r.ok) {
      out << "  FAILED: " << r.error << '\n';
      continue;
    }
    for (const Column& c : row_columns())
      out << ' ' << std::setw(c.width) << std::setprecision(4) << c.get(r.metrics);
    out << '\n';
  }
}

void write_summary_table(std::ostream& out, const std::vector<FieldSummary>& summary) {
  std::size_t width = 0;
  for (const FieldSummary& s : summary) width = std::max(width, s.name.size());
  out << std::left << std::setw(static_cast<int>(width) + 2) << "figure" << std::right
      << std::setw(14) << "min" << std::setw(14) << "mean" << std::setw(14) << "max" << '\n';
  for (const FieldSummary& s : summary)
    out << std::left << std::setw(static_cast<int>(width) + 2) << s.name << std::right
        << std::setprecision(6) << std::setw(14) << s.min << std::setw(14) << s.mean
        << std::setw(14) << s.max << '\n';
}

std::vector<MeshMetrics> measured(const std::vector<MeshResult>& results) {
  std::vector<MeshMetrics> metrics;
  for (const MeshResult& r : results)
    if (r.ok) metrics.push_back(r.metrics);
  return metrics;
}

void write_tables(std::ostream& out, const std::vector<MeshResult>& results) {
  const std::vector<MeshMetrics> metrics = measured(results);
  if (results.size() == 1 && metrics.size() == 1) {
    out << "mesh " << results.front().path << '\n';
    write_table(out, metrics.front());
    return;
  }
  write_rows(out, results);
  out << "\nsummary over " << metrics.size() << " of " << results.size() << " meshes\n";
  write_summary_table(out, summarize(metrics));
}

void write_json_report(std::ostream& out, const std::vector<MeshResult>& results,
                       const MetricsCommandOptions& opts) {
  nlohmann::json report;
  report["crease_angle_deg"] = opts.crease_angle_deg;
  report["meshes"] = nlohmann::json::array();
  for (const MeshResult& r : results) {
    nlohmann::json mesh{{"path", r.path}};
    if (r.ok)
      mesh["metrics"] = to_json(r.metrics);
    else
      mesh["error"] = r.error;
    report["meshes"].push_back(mesh);
  }
  const std::vector<MeshMetrics> metrics = measured(results);
  nlohmann::json fields = nlohmann::json::object();
  for (const FieldSummary& s : summarize(metrics))
    fields[s.name] = {{"min", s.min}, {"mean", s.mean}, {"max", s.max}};
  report["summary"] = {{"meshes", results.size()},
                       {"measured", metrics.size()},
                       {"failed", results.size() - metrics.size()},
                       {"fields", fields}};
  // File names are any bytes: those that are not UTF-8 become U+FFFD.
  out << report.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
}

/// @throw common::OutputError when the file cannot be written (nothing is left at `path`)
void write_csv(const std::string& path, const std::vector<MeshResult>& results) {
  common::write_file_atomically(path, [&](std::ostream& csv) {
    write_csv_header(csv);
    for (const MeshResult& r : results)
      if (r.ok) write_csv_row(csv, r.path, r.metrics);
  });
}

/// @throw PlotError, common::OutputError
void write_plots(const std::string& dir, const std::vector<MeshResult>& results,
                 std::ostream& err) {
  MetricsSamples pooled;
  for (const MeshResult& r : results) pooled.append(r.samples);
  PlotOptions options;
  const std::size_t n = measured(results).size();
  options.title_suffix = "(" + std::to_string(n) + (n == 1 ? " mesh)" : " meshes)");
  for (const std::string& file : write_histogram_plots(dir, pooled, options))
    err << "metrics: wrote " << file << '\n';
}

bool options_valid(const MetricsCommandOptions& opts, std::ostream& err) {
  if (!(opts.crease_angle_deg > 0.0 && opts.crease_angle_deg < 180.0)) {
    err << "metrics: --crease-angle must be in (0, 180) degrees, got " << opts.crease_angle_deg
        << '\n';
    return false;
  }
  if (opts.threads < 0) {
    err << "metrics: --threads must be >= 0\n";
    return false;
  }
  return true;
}

}  // namespace

std::vector<std::string> find_mesh_files(const std::vector<std::string>& paths,
                                         std::vector<std::string>& missing) {
  std::vector<std::string> files;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      const std::vector<std::string> inside = meshes_in_folder(path);
      files.insert(files.end(), inside.begin(), inside.end());
    } else if (fs::exists(path, ec)) {
      files.push_back(path);
    } else {
      missing.push_back(path);
    }
  }
  return files;
}

int run_metrics_command(const std::vector<std::string>& paths, const MetricsCommandOptions& opts,
                        std::ostream& out, std::ostream& err) {
  if (!options_valid(opts, err)) return 2;

  std::vector<std::string> missing;
  const std::vector<std::string> files = find_mesh_files(paths, missing);
  for (const std::string& path : missing)
    err << "metrics: no such file or folder: " << path << '\n';
  if (files.empty()) {
    err << "metrics: no OBJ or PLY mesh found\n";
    return 2;
  }
  const auto start = std::chrono::steady_clock::now();
  const std::vector<MeshResult> results = measure_all(files, opts, !opts.plots_dir.empty());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  bool ok = missing.empty();
  for (const MeshResult& r : results)
    if (!r.ok) {
      err << "metrics: " << r.path << ": " << r.error << '\n';
      ok = false;
    }
  if (opts.json)
    write_json_report(out, results, opts);
  else
    write_tables(out, results);
  err << "metrics: measured " << measured(results).size() << " of " << results.size()
      << " meshes in " << std::setprecision(3) << seconds << " s\n";
  try {
    if (!opts.csv_path.empty()) write_csv(opts.csv_path, results);
    if (!opts.plots_dir.empty()) write_plots(opts.plots_dir, results, err);
  } catch (const common::OutputError& e) {
    err << "metrics: cannot write output: " << e.what() << '\n';
    return 5;
  } catch (const PlotError& e) {
    err << "metrics: " << e.what() << '\n';
    return 6;
  }
  return ok ? 0 : 2;
}

void configure_metrics_command(CLI::App& command, int& exit_code, std::ostream& out,
                               std::ostream& err) {
  struct State {
    std::vector<std::string> paths;
    MetricsCommandOptions options;
    bool no_self_intersections = false;
  };
  auto state = std::make_shared<State>();
  command.add_option("meshes", state->paths, "OBJ or PLY meshes, or folders searched for them")
      ->required();
  command.add_flag("--json", state->options.json, "print JSON instead of tables");
  const CLI::Validator non_empty(
      [](std::string& value) {
        return value.empty() ? std::string("must not be empty") : std::string();
      },
      "NONEMPTY");
  command.add_option("--csv", state->options.csv_path, "write one CSV row per mesh to FILE")
      ->check(non_empty);
  command
      .add_option("--crease-angle", state->options.crease_angle_deg,
                  "crease threshold on the dihedral angle [deg]")
      ->capture_default_str();
  command.add_option("--plots", state->options.plots_dir, "write histogram SVGs to DIR")
      ->check(non_empty);
  command.add_option("--threads", state->options.threads, "worker threads (0 = all cores)")
      ->capture_default_str();
  command.add_flag("--no-self-intersections", state->no_self_intersections,
                   "skip the exact self-intersection count");
  command.callback([state, &exit_code, &out, &err] {
    state->options.self_intersections = !state->no_self_intersections;
    exit_code = run_metrics_command(state->paths, state->options, out, err);
  });
}

CLI::App* add_metrics_subcommand(CLI::App& app, int& exit_code, std::ostream& out,
                                 std::ostream& err) {
  CLI::App* command = app.add_subcommand(
      "metrics", "Measure meshes: isometry, developability, creases, quality, self-intersection");
  configure_metrics_command(*command, exit_code, out, err);
  return command;
}

}  // namespace papersim::validation
