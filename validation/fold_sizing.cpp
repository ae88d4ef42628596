// Which sizing criterion refines the 180-degree fold's mesh (issue 14, diagnostic). Runs the
// stress suite's fold (validation/fold_scene.hpp), uniform or remeshed, and at the steps asked
// for prints, per criterion of the sizing (remesh::sizing_terms: world curvature, plastic
// curvature, compression, velocity, obstacle), how many faces it alone would refine to
// size_min, the shortest and median edge it asks for, the faces where it is the largest
// criterion, and the vertex count the combined, clamped sizing implies (the metric area of the
// sheet over that of a unit equilateral triangle, halved; also with the metrics averaged at the
// vertices, as the remesher uses them) and the percentiles of the edges' lengths under those
// metrics (a pass splits above 1 and collapses below 0.9). Also the membrane's compression: the
// smallest principal Green strain (F^T F - I) / 2 and the faces compressed by more than 1e-3.
//   papersim_fold_sizing [--edge 8] [--remesh MIN:MAX] [--size 1:100] [--steps 1,2,50,100,160]
//   papersim_fold_sizing --checkpoint DIR [--steps S1,S2] [--size MIN:MAX]
// Sizes in mm; --size sets the sizing parameters of the report (and of the run with --remesh).
// With --checkpoint the run is the checkpoint's scene resumed from its state (papersim run
// --checkpoint): the report is made there and after the (absolute) steps listed, and the sizing
// parameters are the scene's unless --size is given.
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "remesh/remesh.hpp"
#include "remesh/sheet_io.hpp"
#include "remesh/sizing.hpp"
#include "simulation/run.hpp"
#include "simulation/scene.hpp"
#include "simulation/simulate.hpp"
#include "validation/fold_scene.hpp"

namespace ps = papersim::simulation;
namespace rm = papersim::remesh;

namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double largest_eigenvalue(const Eigen::Matrix2d& m) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(0.5 * (m + m.transpose())).eigenvalues()(1);
}

void report(const ps::Run& run, const rm::RemeshParams& p, const std::string& dump) {
  const rm::SheetMesh& mesh = run.mesh();
  const rm::RemeshState rs = run.remesh_state();
  const std::vector<rm::SizingTerms> terms = rm::sizing_terms(mesh, rs, p);
  const Eigen::MatrixX3i f = mesh.faces();
  const Eigen::MatrixX3d& x = rs.positions;
  double zmin = INFINITY, zmax = -INFINITY;
  for (int v = 0; v < x.rows(); ++v) zmin = std::min(zmin, x(v, 2)), zmax = std::max(zmax, x(v, 2));
  std::printf("step %d (t = %.3f s): %d vertices, %d faces, loop height %.1f mm\n",
              run.steps_done(), run.state().time, mesh.num_vertices(), mesh.num_faces(),
              1e3 * (zmax - zmin));
  const char* names[5] = {"curvature", "plastic", "compression", "velocity", "obstacle"};
  // --dump: the faces' table, written at the end of this step through a temporary name.
  const bool dumping = !dump.empty();
  std::string faces_csv =
      "mx,my,wx,wy,wz,l_curvature,l_plastic,l_compression,kp_xx,kp_yy,kp_xy,size\n";
  const Eigen::MatrixX3d kp = mesh.plastic_curvature();
  const double at_min = 1.0 / (p.size_min * p.size_min) * (1 - 1e-9);
  std::vector<int> finest(5, 0), dominant(5, 0);
  std::vector<std::vector<int>> finest_at(5, std::vector<int>(12, 0));  // by material x, 1 cm bins
  std::vector<std::vector<double>> wanted(5);
  double implied = 0, green_min = 0;
  int compressed = 0;
  for (int i = 0; i < f.rows(); ++i) {
    const rm::SizingTerms& t = terms[i];
    const Eigen::Matrix2d m[5] = {t.curvature, t.plastic, t.compression, t.velocity, t.obstacle};
    int best = -1;
    double best_l = 0;
    for (int k = 0; k < 5; ++k) {
      const double l = largest_eigenvalue(m[k]);
      if (l >= at_min) {
        ++finest[k];
        const double cx = (mesh.material_coord(f(i, 0)).x() + mesh.material_coord(f(i, 1)).x() +
                           mesh.material_coord(f(i, 2)).x()) /
                          3;
        ++finest_at[k][std::clamp(static_cast<int>(cx / 0.01), 0, 11)];
      }
      if (l > 0) wanted[k].push_back(1 / std::sqrt(l));
      if (l > best_l) best_l = l, best = k;
    }
    if (best >= 0) ++dominant[best];
    if (dumping) {
      Eigen::Vector2d mc = Eigen::Vector2d::Zero();
      Eigen::Vector3d wc = Eigen::Vector3d::Zero();
      double size = 0;
      for (int c = 0; c < 3; ++c) {
        mc += mesh.material_coord(f(i, c)) / 3;
        wc += x.row(f(i, c)).transpose() / 3;
        size = std::max(
            size, (mesh.material_coord(f(i, (c + 1) % 3)) - mesh.material_coord(f(i, c))).norm());
      }
      auto len = [&](int k) {
        const double l = largest_eigenvalue(m[k]);
        return l > 0 ? 1 / std::sqrt(l) : INFINITY;
      };
      char line[256];
      std::snprintf(line, sizeof line,
                    "%.6g,%.6g,%.6g,%.6g,%.6g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g\n", mc.x(), mc.y(),
                    wc.x(), wc.y(), wc.z(), len(0), len(1), len(2), kp(i, 0), kp(i, 1), kp(i, 2),
                    size);
      faces_csv += line;
    }
    const Eigen::Vector2d a = mesh.material_coord(f(i, 0)), b = mesh.material_coord(f(i, 1)),
                          c = mesh.material_coord(f(i, 2));
    Eigen::Matrix2d dm;
    dm << b - a, c - a;
    const double area = 0.5 * std::abs(dm.determinant());
    const Eigen::Matrix2d clamped =
        rm::clamp_metric(rm::tensor_max({m[0], m[1], m[2], m[3], m[4]}), p);
    implied += area * std::sqrt(std::max(clamped.determinant(), 0.0)) / (std::sqrt(3.0) / 4);
    Eigen::Matrix<double, 3, 2> def;
    def.col(0) = (x.row(f(i, 1)) - x.row(f(i, 0))).transpose();
    def.col(1) = (x.row(f(i, 2)) - x.row(f(i, 0))).transpose();
    def = def * dm.inverse();
    const Eigen::Matrix2d green = 0.5 * (def.transpose() * def - Eigen::Matrix2d::Identity());
    const double g = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(green).eigenvalues()(0);
    green_min = std::min(green_min, g);
    if (g < -1e-3) ++compressed;
  }
  if (dumping) {
    const std::string step = std::to_string(run.steps_done());
    papersim::common::write_text_atomically(dump + "/faces_" + step + ".csv", faces_csv);
    papersim::common::write_file_atomically(
        dump + "/sheet_" + step + ".obj", [&](std::ostream& obj) {
          rm::write_obj(obj, mesh, x, run.scene().sheet.width, run.scene().sheet.height);
        });
  }
  if (run.scene().remesh.enabled) {
    const ps::RunResult r = run.result(0);
    std::printf(
        "  remeshing so far: %d passes, %d rollbacks, %d splits, %d flips, %d collapses; refused:",
        r.remesh->passes, r.remesh->rollbacks, r.remesh->splits, r.remesh->flips,
        r.remesh->collapses);
    for (const auto& [reason, n] : r.remesh->refusals) std::printf(" %s %d,", reason.c_str(), n);
    std::printf("\n");
  }
  std::printf("  smallest principal Green strain %.3g; faces compressed beyond 1e-3: %d\n",
              green_min, compressed);
  std::printf("  implied by the clamped sizing: about %.0f vertices (%.0f faces)\n", 0.5 * implied,
              implied);
  {
    // What the remesher sees: face metrics averaged at the vertices (remesh::vertex_metrics), each
    // face measured by the mean of its corners' metrics.
    const std::vector<Eigen::Matrix2d> vm = rm::vertex_metrics(mesh, rm::sizing(mesh, rs, p));
    double by_vertex = 0;
    for (int i = 0; i < f.rows(); ++i) {
      const Eigen::Vector2d a = mesh.material_coord(f(i, 0)), b = mesh.material_coord(f(i, 1)),
                            c = mesh.material_coord(f(i, 2));
      Eigen::Matrix2d dm;
      dm << b - a, c - a;
      const Eigen::Matrix2d m = (vm[f(i, 0)] + vm[f(i, 1)] + vm[f(i, 2)]) / 3;
      by_vertex += 0.5 * std::abs(dm.determinant()) * std::sqrt(std::max(m.determinant(), 0.0)) /
                   (std::sqrt(3.0) / 4);
    }
    std::printf("  implied by the metrics averaged at the vertices: about %.0f vertices\n",
                0.5 * by_vertex);
    // Edge lengths under the metric the remesher uses (mean of the end vertices' metrics): a pass
    // splits above 1 and collapses only where no new edge exceeds 0.9.
    std::set<std::pair<int, int>> edges;
    for (int i = 0; i < f.rows(); ++i)
      for (int k = 0; k < 3; ++k) edges.insert(std::minmax(f(i, k), f(i, (k + 1) % 3)));
    std::vector<double> sizes;
    for (const auto& [a, b] : edges) {
      const Eigen::Vector2d u = mesh.material_coord(b) - mesh.material_coord(a);
      sizes.push_back(std::sqrt(u.dot(0.5 * (vm[a] + vm[b]) * u)));
    }
    std::sort(sizes.begin(), sizes.end());
    const auto pct = [&](double q) {
      return sizes[std::min(sizes.size() - 1, static_cast<size_t>(q * sizes.size()))];
    };
    std::printf(
        "  edge lengths under the metric: 10%% %.2f, 25%% %.2f, median %.2f, 75%% %.2f, "
        "90%% %.2f\n",
        pct(0.1), pct(0.25), pct(0.5), pct(0.75), pct(0.9));
  }
  std::printf("  %-12s %8s %8s %10s %10s\n", "criterion", "finest", "largest", "min_l_mm",
              "median_mm");
  for (int k = 0; k < 5; ++k) {
    std::vector<double>& w = wanted[k];
    std::sort(w.begin(), w.end());
    std::printf("  %-12s %8d %8d %10.3g %10.3g\n", names[k], finest[k], dominant[k],
                w.empty() ? NAN : 1e3 * w.front(), w.empty() ? NAN : 1e3 * w[w.size() / 2]);
  }
  std::printf("  faces at size_min by material x (1 cm bins from the clamped edge):\n");
  for (int k : {0, 1, 2}) {
    std::printf("  %-12s", names[k]);
    for (int b = 0; b < 12; ++b) std::printf(" %4d", finest_at[k][b]);
    std::printf("\n");
  }
  std::fflush(stdout);
}

bool parse_pair(const std::string& text, double& lo, double& hi) {
  int used = 0;
  return std::sscanf(text.c_str(), "%lf:%lf%n", &lo, &hi, &used) == 2 &&
         used == static_cast<int>(text.size()) && lo > 0 && hi >= lo;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"papersim_fold_sizing: which sizing criterion refines the 180-degree fold"};
  double edge = 8;
  std::string remesh_text, size_text = "1:100", steps_text = "1,2,50,100,160", dump, checkpoint;
  app.add_option("--edge", edge, "start edge length [mm]")->capture_default_str();
  app.add_option("--remesh", remesh_text, "remesh the run with MIN:MAX [mm] (default: uniform)");
  app.add_option("--size", size_text, "size_min:size_max [mm] of the report's sizing")
      ->capture_default_str();
  app.add_option("--steps", steps_text, "steps after which to report, comma separated")
      ->capture_default_str();
  app.add_option(
      "--dump", dump,
      "write faces_STEP.csv (per face: material and world centroid [m], the edge each "
      "criterion asks for [m], plastic curvature [1/m], longest edge [m]) into this directory");
  CLI::Option* checkpoint_option =
      app.add_option("--checkpoint", checkpoint,
                     "report on the checkpoint in DIR (its scene and state) and "
                     "after the steps listed")
          ->check(CLI::ExistingDirectory);
  checkpoint_option->excludes(app.get_option("--edge"))->excludes(app.get_option("--remesh"));
  CLI11_PARSE(app, argc, argv);
  try {
    ps::Checkpoint cp;
    if (!checkpoint.empty()) cp = ps::load_checkpoint(checkpoint);
    ps::Scene scene = checkpoint.empty()
                          ? papersim::validation::fold_180_scene(1e-3 * edge)
                          : ps::scene_from_json(cp.scene, checkpoint + "/checkpoint.json");
    double lo = 0, hi = 0;
    if (!parse_pair(size_text, lo, hi))
      throw std::runtime_error("--size: '" + size_text + "' is not MIN:MAX");
    rm::RemeshParams p = scene.remesh.params;
    if (checkpoint.empty() || app.count("--size")) {
      p.size_min = 1e-3 * lo;
      p.size_max = 1e-3 * hi;
    }
    if (!remesh_text.empty()) {
      if (!parse_pair(remesh_text, lo, hi))
        throw std::runtime_error("--remesh: '" + remesh_text + "' is not MIN:MAX");
      scene.remesh.enabled = true;
      scene.remesh.params.size_min = 1e-3 * lo;
      scene.remesh.params.size_max = 1e-3 * hi;
    }
    std::set<int> at;
    std::stringstream in(steps_text);
    std::string item;
    while (std::getline(in, item, ',')) at.insert(std::stoi(item));
    ps::Run run(scene);
    if (!checkpoint.empty()) {
      run.resume(cp.mesh, cp.state, cp.step);
      report(run, p, dump);
      at.insert(cp.step);
    }
    if (at.count(0)) report(run, p, dump);
    const double c0 = cpu_seconds();
    while (!run.finished() && run.steps_done() < *at.rbegin()) {
      const double c = cpu_seconds();
      const ps::StepStats& st = run.step();
      std::printf("step %d: %d vertices, %d Newton iterations, %.2f s CPU\n", run.steps_done(),
                  run.mesh().num_vertices(), st.newton_iterations, cpu_seconds() - c);
      std::fflush(stdout);
      if (at.count(run.steps_done())) report(run, p, dump);
    }
    std::printf("total %.1f s CPU\n", cpu_seconds() - c0);
    if (run.finished() && checkpoint.empty()) {  // the figures of papersim_fold_remesh
      const ps::RunResult r = run.result(0);
      const Eigen::VectorXd& x = r.state.positions;
      double zmin = INFINITY, zmax = -INFINITY;
      for (Eigen::Index i = 2; i < x.size(); i += 3)
        zmin = std::min(zmin, x(i)), zmax = std::max(zmax, x(i));
      const double radius = 0.5 * (zmax - zmin);
      const double continuum =
          M_PI * scene.sheet.material.bending_stiffness * scene.sheet.height / radius;
      std::printf(
          "end: %d vertices (%d at most), bending energy %.4g J, radius %.2f mm, pi D w / r %.4g "
          "J, "
          "ratio %.3f, self-intersections %d, max stretch %.6f, min ground %.3g m\n",
          r.sheet.vertices, r.sheet.vertices_max, r.energy.bend, 1e3 * radius, continuum,
          r.energy.bend / continuum, r.quality.self_intersections, r.quality.max_principal_stretch,
          r.quality.min_obstacle_distance.empty() ? NAN : r.quality.min_obstacle_distance.front());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "papersim_fold_sizing: %s\n", e.what());
    return 1;
  }
}
