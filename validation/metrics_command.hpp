#pragma once
/// `papersim metrics MESH... [--json] [--csv FILE] [--crease-angle DEG] [--plots DIR]`:
/// measure sheets stored as OBJ or PLY files, or every mesh in folders, in parallel.
#include <iosfwd>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace papersim::validation {

/// Options of the metrics command.
struct MetricsCommandOptions {
  bool json = false;               ///< print JSON on `out` instead of the tables
  std::string csv_path;            ///< write one CSV row per mesh to this file when not empty
  double crease_angle_deg = 30.0;  ///< [deg] crease threshold on the dihedral angle, (0, 180)
  std::string plots_dir;           ///< write histogram SVGs (gnuplot) here when not empty
  int threads = 0;                 ///< worker threads; 0 = all cores
  bool self_intersections = true;  ///< run the exact self-intersection count
};

/// The mesh files named by `paths`: a file is taken as given; a folder is searched recursively
/// for *.obj and *.ply (any case). When a folder holds NAME.obj and NAME.ply side by side,
/// only the PLY is taken (it carries the plastic data). Folder results are sorted.
/// @param missing receives the paths that do not exist
std::vector<std::string> find_mesh_files(const std::vector<std::string>& paths,
                                         std::vector<std::string>& missing);

/// Measure every mesh of `paths` (see find_mesh_files) with compute_metrics, in parallel over
/// meshes (TBB), and report: a table (one row per mesh and a summary of min / mean / max over
/// meshes; every figure when there is a single mesh) or JSON ({"meshes": [...], "summary":
/// {...}}) on `out`; the CSV file and plots when asked; errors and the timing on `err`.
/// Meshes that cannot be read or measured are reported on `err` (and in the JSON) and skipped.
/// @return the exit status (common/exit_status.hpp): 0 when every mesh was measured; 2 on bad
///         options, a missing path, a mesh that failed or no mesh found; 5 when the CSV or a
///         plot cannot be written (nothing partial is left); 6 when gnuplot fails.
///         Never throws for bad input files.
int run_metrics_command(const std::vector<std::string>& paths, const MetricsCommandOptions& opts,
                        std::ostream& out, std::ostream& err);

/// Give `command` (the main App of a program, or a subcommand) the metrics arguments and a
/// callback that runs run_metrics_command and stores its status in `exit_code`, which must
/// outlive the parse. `out` and `err` must outlive it too.
void configure_metrics_command(CLI::App& command, int& exit_code, std::ostream& out,
                               std::ostream& err);

/// Add the `metrics` subcommand to `app` (configure_metrics_command on a new subcommand).
/// Wiring in a main: `int code = 0; add_metrics_subcommand(app, code, std::cout, std::cerr);
/// CLI11_PARSE(app, argc, argv); return code;`
/// @return the subcommand
CLI::App* add_metrics_subcommand(CLI::App& app, int& exit_code, std::ostream& out,
                                 std::ostream& err);

}  // namespace papersim::validation
