// papersim_metrics_bench [--meshes N] [--nx NX --ny NY] [--threads T] [--keep DIR]
//
// Issue 5 acceptance: `papersim metrics` on 1,000 meshes of 10k triangles finishes in under a
// minute on 2 cores. Generates N sheets (default 1000 of 51 x 101 vertices = 10,000 triangles,
// A4, random diagonals and jitter, each folded along a random line and waved), writes them as
// OBJ into a temporary folder, then times run_metrics_command over the folder (reading,
// measuring, writing the table and a CSV) on T threads. Prints a table of case, target,
// measured, verdict; exits non-zero when over the target.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

#include "common/clock.hpp"
#include "remesh/sheet_generator.hpp"
#include "remesh/sheet_io.hpp"
#include "validation/metrics_command.hpp"

namespace {

namespace fs = std::filesystem;
using papersim::seconds_since;
using papersim::remesh::SheetMesh;

struct BenchOptions {
  int meshes = 1000;
  int nx = 51;
  int ny = 101;
  int threads = 2;
  double target_seconds = 60.0;  // [s]
  std::string keep_dir;          // write the meshes here and keep them
};

/// Fold the flat sheet along a random line through its middle by a random angle, then add a
/// gentle wave: a shape with one crease band, curvature and some strain.
Eigen::MatrixX3d deform(const SheetMesh& mesh, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double pi = 3.14159265358979323846;
  const Eigen::MatrixX2d x = mesh.material_coords();
  const Eigen::Vector2d centre = 0.5 * x.colwise().maxCoeff().transpose();
  const double direction = pi * uniform(rng), fold = pi * (0.2 + 0.6 * uniform(rng));
  const Eigen::Vector2d d(std::cos(direction), std::sin(direction)), m(-d.y(), d.x());
  const double amplitude = 0.002 * uniform(rng), wavelength = 0.05 + 0.1 * uniform(rng);
  Eigen::MatrixX3d p(x.rows(), 3);
  for (Eigen::Index v = 0; v < x.rows(); ++v) {
    const Eigen::Vector2d r = x.row(v).transpose() - centre;
    const double t = d.dot(r), s = m.dot(r);
    const double across = s > 0.0 ? s * std::cos(fold) : s, up = s > 0.0 ? s * std::sin(fold) : 0.0;
    const Eigen::Vector2d plane = centre + t * d + across * m;
    p.row(v) << plane.x(), plane.y(), up + amplitude * std::sin(2.0 * pi * t / wavelength);
  }
  return p;
}

void write_meshes(const fs::path& dir, const BenchOptions& o) {
  tbb::task_arena arena(o.threads);
  arena.execute([&] {
    tbb::parallel_for(0, o.meshes, [&](int i) {
      papersim::remesh::RectangleOptions r;
      r.nx = o.nx;
      r.ny = o.ny;
      r.triangulation = papersim::remesh::Triangulation::random;
      r.jitter = 0.2;
      r.seed = static_cast<std::uint64_t>(i);
      const SheetMesh mesh = papersim::remesh::make_rectangle(r);
      std::ostringstream name;
      name << "sheet_" << std::setw(5) << std::setfill('0') << i << ".obj";
      std::ofstream out(dir / name.str());
      papersim::remesh::write_obj(out, mesh, deform(mesh, 1000 + i), r.width, r.height);
    });
  });
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions o;
  CLI::App app{"Time the metrics command on many generated meshes"};
  app.add_option("--meshes", o.meshes, "number of meshes")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  app.add_option("--nx", o.nx, "vertices along the sheet width")
      ->capture_default_str()
      ->check(CLI::Range(2, 10000));
  app.add_option("--ny", o.ny, "vertices along the sheet height")
      ->capture_default_str()
      ->check(CLI::Range(2, 10000));
  app.add_option("--threads", o.threads, "worker threads")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  app.add_option("--target", o.target_seconds, "target time [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--keep", o.keep_dir, "write the meshes to this folder and keep them");
  CLI11_PARSE(app, argc, argv);
  try {
    const fs::path dir =
        o.keep_dir.empty()
            ? fs::temp_directory_path() / ("papersim_metrics_bench_" + std::to_string(::getpid()))
            : fs::path(o.keep_dir);
    fs::create_directories(dir / "meshes");
    auto start = std::chrono::steady_clock::now();
    write_meshes(dir / "meshes", o);
    std::cout << "generated " << o.meshes << " meshes of " << 2 * (o.nx - 1) * (o.ny - 1)
              << " triangles in " << std::setprecision(3) << seconds_since(start) << " s\n";

    papersim::validation::MetricsCommandOptions options;
    options.threads = o.threads;
    options.csv_path = (dir / "metrics.csv").string();
    std::ofstream table(dir / "metrics.txt");
    start = std::chrono::steady_clock::now();
    const int status = papersim::validation::run_metrics_command({(dir / "meshes").string()},
                                                                 options, table, std::cerr);
    const double seconds = seconds_since(start);
    const bool pass = status == 0 && seconds < o.target_seconds;
    std::cout << std::left << std::setw(44) << "case" << std::setw(12) << "target [s]"
              << std::setw(14) << "measured [s]"
              << "verdict\n"
              << std::setw(44)
              << ("metrics, " + std::to_string(o.meshes) + " meshes, " + std::to_string(o.threads) +
                  " threads")
              << std::setw(12) << o.target_seconds << std::setw(14) << std::setprecision(4)
              << seconds << (pass ? "PASS" : "FAIL") << '\n'
              << "per mesh: " << std::setprecision(3) << 1000.0 * seconds * o.threads / o.meshes
              << " ms per mesh per thread\n";
    if (o.keep_dir.empty()) fs::remove_all(dir);
    return pass ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "papersim_metrics_bench: " << e.what() << '\n';
    return 1;
  }
}
