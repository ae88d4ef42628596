// Run time against error (issue 5 item 2): one scenario draw simulated over a sweep of mesh edge
// length and time step, each result compared with a fine reference run of the same draw
// (validation/compare.hpp: RMS and max position error at the same material points, symmetric
// Hausdorff distance). Writes OUT/runtime_error.csv and OUT/runtime_error.png (gnuplot: wall
// time against RMS error, one line per time step), prints the table, the settings no other
// setting beats on both time and error (the Pareto front), and the cheapest setting whose RMS
// error is below --target.
//   papersim_runtime_error --out DIR [--scenario pull] [--seed 1] [--edges 20,14,10,7]
//       [--steps 20,10,5] [--reference-edge 5] [--reference-step 2.5] [--target 2]
//       [--check-edge 3.5] [--replot]
// Edges and the target are in mm, steps in ms. The reference is written to DIR/reference and
// reused by later runs with the same scenario, seed and reference settings. --check-edge runs
// the draw once more, finer (DIR/reference_check), and compares it with the reference: a draw
// whose end state changes under refinement (a draped sheet choosing another fold pattern) has
// no converged reference, and then no setting is recommended and the exit status is 1.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "remesh/sheet_io.hpp"
#include "simulation/scenario.hpp"
#include "simulation/simulate.hpp"
#include "validation/compare.hpp"

namespace fs = std::filesystem;
namespace ps = papersim::simulation;
namespace pv = papersim::validation;

namespace {

struct Sample {
  double edge_mm = 0, step_ms = 0;
  int vertices = 0, steps = 0;
  long newton = 0;
  double wall = 0;
  pv::SheetDifference error;
};

pv::SheetGeometry geometry_of(const papersim::remesh::SheetMesh& mesh, const Eigen::MatrixX3d& positions) {
  return {mesh.material_coords(), positions, mesh.faces()};
}

Eigen::MatrixX3d as_rows(const Eigen::VectorXd& x) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(x.data(), x.size() / 3, 3);
}

ps::Scene with_resolution(ps::Scene scene, double edge_mm, double step_ms) {
  scene.sheet.edge_length = 1e-3 * edge_mm;
  scene.time_step = 1e-3 * step_ms;
  return scene;
}

/// Progress on stderr: percent and ETA of one run.
ps::RunOptions progress_options(const std::string& label) {
  ps::RunOptions o;
  o.progress = [label](double f, double s) {
    const double eta = f > 0 ? s * (1 - f) / f : 0;
    std::fprintf(stderr, "\r  %-28s %5.1f%%  %6.1f s, ETA %6.1f s   ", label.c_str(), 100 * f, s, eta);
    if (f >= 1) std::fprintf(stderr, "\n");
  };
  return o;
}

/// A reference run, read back from DIR/NAME when it was made with the same settings.
pv::SheetGeometry reference_run(const ps::Scene& scene, const fs::path& dir, const std::string& name,
                                double& wall) {
  const fs::path ref = dir / name;
  const nlohmann::json key = {{"scenario", scene.scenario}, {"seed", scene.seed},
                              {"edge_length", scene.sheet.edge_length}, {"time_step", scene.time_step}};
  if (fs::exists(ref / "sheet.obj") && fs::exists(ref / "meta.json")) {
    std::ifstream in(ref / "meta.json");
    const nlohmann::json meta = nlohmann::json::parse(in, nullptr, false);
    if (!meta.is_discarded() && meta.contains("study_key") && meta["study_key"] == key) {
      const auto data = papersim::remesh::read_sheet((ref / "sheet.obj").string());
      wall = meta["run"]["wall_seconds"];
      std::printf("%s: reused %s (%.1f s when made)\n", name.c_str(), ref.c_str(), wall);
      return geometry_of(data.mesh, data.positions);
    }
  }
  fs::remove_all(ref);
  ps::RunOptions o = progress_options(name);
  o.out_dir = ref.string();
  o.extra_meta = {{"study_key", key}};
  const ps::RunResult r = ps::run_scene(scene, o);
  wall = r.meta["run"]["wall_seconds"];
  return geometry_of(r.mesh, as_rows(r.state.positions));
}

/// x with %g (shortest form: 2.5, not 2.500000).
std::string format_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

std::vector<double> parse_list(const std::string& text, const char* what) {
  std::vector<double> v;
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t end = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, end - pos);
    char* stop = nullptr;
    const double x = std::strtod(item.c_str(), &stop);
    if (item.empty() || *stop != '\0' || !(x > 0))
      throw std::runtime_error(std::string("--") + what + ": '" + item + "' is not a positive number");
    v.push_back(x);
    pos = end + 1;
  }
  return v;
}

void write_csv(const fs::path& path, const std::vector<Sample>& samples) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << "edge_mm,step_ms,vertices,steps,newton_iterations,wall_seconds,rms_error_m,max_error_m,hausdorff_m\n";
    for (const Sample& s : samples)
      out << s.edge_mm << ',' << s.step_ms << ',' << s.vertices << ',' << s.steps << ',' << s.newton << ','
          << s.wall << ',' << s.error.rms << ',' << s.error.max << ',' << s.error.hausdorff << '\n';
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, path);
}

/// gnuplot: wall time against RMS error, log-log, one series per time step, points labelled by
/// the edge length.
void write_plot(const fs::path& dir, const std::vector<double>& steps,
                const std::string& title) {
  std::ofstream gp(dir / "runtime_error.gp");
  gp << "set terminal pngcairo size 900,600 font 'DejaVu Sans,11'\n"
     << "set output 'runtime_error.png.tmp'\n"
     << "set title '" << title << "'\n"
     << "set logscale xy\nset grid\n"
     << "set xlabel 'RMS position error against the reference [mm]'\n"
     << "set ylabel 'wall time per run [s]'\n"
     << "set key top right\nset datafile separator ','\n";
  gp << "plot ";
  for (size_t i = 0; i < steps.size(); ++i) {
    if (i) gp << ", \\\n     ";
    gp << "'runtime_error.csv' every ::1 using ($2==" << steps[i] << " ? $7*1e3 : 1/0):6 with points pt 7 ps 1.3 "
       << "title 'step " << steps[i] << " ms', "
       << "'' every ::1 using ($2==" << steps[i] << " ? $7*1e3 : 1/0):6:(sprintf('%g mm', $1)) "
       << "with labels offset 1.2,0.6 font ',9' notitle";
  }
  gp << "\n";
  gp.close();
  const std::string cmd = "cd '" + dir.string() + "' && gnuplot runtime_error.gp 2> gnuplot.log";
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("gnuplot failed; see " + (dir / "gnuplot.log").string());
  fs::rename(dir / "runtime_error.png.tmp", dir / "runtime_error.png");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"papersim_runtime_error: wall time against error for a sweep of edge length and time step"};
  std::string out, scenario = "pull", edges_text = "20,14,10,7", steps_text = "20,10,5";
  long long seed = 1;
  double ref_edge = 5, ref_step = 2.5, target = 2;
  app.add_option("--out", out, "output folder (CSV, plot, reference run)")->required();
  app.add_option("--scenario", scenario, "scenario name")->capture_default_str();
  app.add_option("--seed", seed, "scenario seed")->capture_default_str();
  app.add_option("--edges", edges_text, "edge lengths of the sweep [mm], comma separated")->capture_default_str();
  app.add_option("--steps", steps_text, "time steps of the sweep [ms], comma separated")->capture_default_str();
  app.add_option("--reference-edge", ref_edge, "edge length of the reference [mm]")->capture_default_str();
  app.add_option("--reference-step", ref_step, "time step of the reference [ms]")->capture_default_str();
  app.add_option("--target", target, "RMS error to recommend a setting for [mm]")->capture_default_str();
  double check_edge = 0;
  app.add_option("--check-edge", check_edge,
                 "also run the draw at this finer edge length [mm] (reference step) and compare it with the "
                 "reference: when they differ by more than the target, the reference is not converged, no "
                 "setting is recommended and the exit status is 1");
  bool replot = false;
  app.add_flag("--replot", replot, "only redraw OUT/runtime_error.png from OUT/runtime_error.csv");
  CLI11_PARSE(app, argc, argv);
  try {
    const std::vector<double> edges = parse_list(edges_text, "edges"), steps = parse_list(steps_text, "steps");
    const std::string title = scenario + " seed " + std::to_string(seed) + ": reference edge " +
                              format_number(ref_edge) + " mm, step " + format_number(ref_step) + " ms";
    if (replot) {
      if (!fs::exists(fs::path(out) / "runtime_error.csv"))
        throw std::runtime_error("--replot: no " + (fs::path(out) / "runtime_error.csv").string());
      write_plot(out, steps, title);
      std::printf("wrote %s/runtime_error.png\n", out.c_str());
      return 0;
    }
    const ps::Scene base = ps::make_scenario(scenario, seed);
    fs::create_directories(out);
    const auto t0 = std::chrono::steady_clock::now();
    double ref_wall = 0;
    if (check_edge != 0 && !(check_edge > 0 && check_edge < ref_edge))
      throw std::runtime_error("--check-edge: " + format_number(check_edge) +
                               " mm is not a positive edge length finer than --reference-edge (" +
                               format_number(ref_edge) + " mm)");
    const pv::SheetGeometry reference =
        reference_run(with_resolution(base, ref_edge, ref_step), out, "reference", ref_wall);
    std::printf("reference: %s seed %lld, edge %g mm, step %g ms, %ld vertices, %.1f s\n", scenario.c_str(), seed,
                ref_edge, ref_step, static_cast<long>(reference.material.rows()), ref_wall);
    bool converged = true;
    if (check_edge > 0) {
      double check_wall = 0;
      const pv::SheetGeometry check =
          reference_run(with_resolution(base, check_edge, ref_step), out, "reference_check", check_wall);
      const pv::SheetDifference d = pv::compare_sheets(check, reference);
      converged = 1e3 * d.rms <= target;
      std::printf("reference check: edge %g mm (%ld vertices, %.1f s) against the reference: RMS %.3f mm, max %.3f mm, "
                  "Hausdorff %.3f mm: %s\n", check_edge, static_cast<long>(check.material.rows()), check_wall,
                  1e3 * d.rms, 1e3 * d.max, 1e3 * d.hausdorff,
                  converged ? "converged within the target" : "NOT converged within the target");
    }
    std::printf("%8s %8s %8s %7s %8s %9s %10s %10s %10s\n", "edge_mm", "step_ms", "vertices", "steps", "newton",
                "wall_s", "rms_mm", "max_mm", "hausd_mm");
    std::vector<Sample> samples;
    for (double e : edges)
      for (double h : steps) {
        const ps::Scene scene = with_resolution(base, e, h);
        const ps::RunResult r = ps::run_scene(scene, progress_options(
            "edge " + format_number(e) + " mm, step " + format_number(h) + " ms"));
        Sample s;
        s.edge_mm = e, s.step_ms = h;
        s.vertices = r.mesh.num_vertices();
        s.steps = r.meta["run"]["steps"];
        s.newton = r.meta["run"]["newton_iterations"];
        s.wall = r.meta["run"]["wall_seconds"];
        s.error = pv::compare_sheets(reference, geometry_of(r.mesh, as_rows(r.state.positions)));
        samples.push_back(s);
        std::printf("%8g %8g %8d %7d %8ld %9.2f %10.3f %10.3f %10.3f\n", e, h, s.vertices, s.steps, s.newton, s.wall,
                    1e3 * s.error.rms, 1e3 * s.error.max, 1e3 * s.error.hausdorff);
        std::fflush(stdout);
        write_csv(fs::path(out) / "runtime_error.csv", samples);  // partial results survive an interruption
      }
    write_plot(out, steps, title);
    std::printf("\nPareto front (no other setting is both faster and more accurate):\n");
    for (const Sample& s : samples) {
      const bool beaten = std::any_of(samples.begin(), samples.end(), [&](const Sample& o) {
        return o.wall < s.wall && o.error.rms < s.error.rms;
      });
      if (!beaten)
        std::printf("  edge %g mm, step %g ms: %.2f s, RMS %.3f mm, max %.3f mm\n", s.edge_mm, s.step_ms, s.wall,
                    1e3 * s.error.rms, 1e3 * s.error.max);
    }
    const Sample* best = nullptr;
    for (const Sample& s : samples)
      if (converged && 1e3 * s.error.rms <= target && (!best || s.wall < best->wall)) best = &s;
    if (best)
      std::printf("cheapest setting with RMS error <= %g mm: edge %g mm, step %g ms (%.2f s, RMS %.3f mm, max %.3f mm; "
                  "%.1fx faster than the reference)\n", target, best->edge_mm, best->step_ms, best->wall,
                  1e3 * best->error.rms, 1e3 * best->error.max, ref_wall / best->wall);
    else if (converged)
      std::printf("no setting of the sweep reaches RMS error <= %g mm\n", target);
    else
      std::printf("no setting recommended: the reference itself moves by more than %g mm RMS under refinement\n",
                  target);
    std::printf("wrote %s/runtime_error.csv and runtime_error.png (%.1f s in all)\n", out.c_str(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (!converged) return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_runtime_error: %s\n", e.what());
    return 1;
  }
  return 0;
}
