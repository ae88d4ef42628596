// Known-answer validation (VALIDATION.md sections 1, 2, 3, 5 and 6; issue 5 item 2): the
// simulator library against answers computed independently of it.
//   1. heavy elastica: a clamped strip sagging under its own weight, along the mesh grid and at
//      30 degrees to it, with a mesh-convergence line for the rotated mesh; reported only, on a
//      wide strip of thin faces at angles to the bend (membrane locking, --only thin);
//   2. self-buckling (Greenhill): a vertical strip stays straight below G_c and falls over above;
//   3. cylinder wrap: bending energy of an isometrically wrapped sheet, D A / (2 R^2), and its
//      angle defect, over mesh patterns and axis angles;
//   4. numerical damping of backward Euler on the first bending mode of a clamped strip;
//   5. Coulomb friction on an incline with tan = 0.5: mu = 0.49 slides, mu = 0.51 sticks.
//   6. plasticity (issue 16): a strip bent by handles below the yield curvature and released
//      returns flat; bent above it, it keeps the return mapping's moment-free curvature.
// Prints one row per case (expected, measured, relative error, tolerance, verdict), optionally
// writes the same rows as CSV, and exits with status 1 when a case fails.
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "collision/collider.hpp"
#include "common/atomic_file.hpp"
#include "common/cli_checks.hpp"
#include "common/clock.hpp"
#include "remesh/sheet_generator.hpp"
#include "simulation/energies/vertex_energies.hpp"
#include "simulation/run.hpp"
#include "validation/metrics.hpp"

namespace ps = papersim::simulation;
namespace rm = papersim::remesh;
namespace pc = papersim::collision;

namespace {

using papersim::seconds_since;

constexpr double NOT_APPLICABLE = std::numeric_limits<double>::quiet_NaN();
constexpr double PI = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// The report: rows printed as they come, and written as CSV at the end.

struct Row {
  std::string group;    ///< case family ("elastica", "greenhill", ...)
  std::string name;     ///< what was measured, with the mesh and parameters
  double expected = 0;  ///< known answer (or the bound of a one-sided test)
  double measured = 0;
  double rel_error = NOT_APPLICABLE;  ///< measured / expected - 1, when meaningful
  std::string tolerance;              ///< "2%", "< 0.1", "info" (reported, not judged)
  std::string verdict;                ///< PASS, FAIL or info
};

class Report {
 public:
  void header() const {
    std::printf("%-58s %12s %12s %9s %9s %s\n", "case", "expected", "measured", "rel.err", "tol",
                "verdict");
  }
  void section(const std::string& title) const {
    std::printf("\n== %s\n", title.c_str());
    std::fflush(stdout);
  }
  void note(const std::string& text) const {
    std::printf("   %s\n", text.c_str());
    std::fflush(stdout);
  }
  void add(const Row& r) {
    m_rows.push_back(r);
    const std::string err = std::isnan(r.rel_error) ? "-" : format("%+.2f%%", 100 * r.rel_error);
    std::printf("%-58s %12.6g %12.6g %9s %9s %s\n", r.name.c_str(), r.expected, r.measured,
                err.c_str(), r.tolerance.c_str(), r.verdict.c_str());
    std::fflush(stdout);
  }
  /// Two-sided relative test: |measured / expected - 1| <= tol.
  void relative(const std::string& group, const std::string& name, double expected, double measured,
                double tol) {
    const double e = measured / expected - 1;
    add({group, name, expected, measured, e, format("%g%%", 100 * tol),
         std::abs(e) <= tol ? "PASS" : "FAIL"});
  }
  /// One-sided test: measured < bound (below = true) or measured > bound.
  void bound(const std::string& group, const std::string& name, double bound_value, double measured,
             bool below) {
    const bool ok = below ? measured < bound_value : measured > bound_value;
    add({group, name, bound_value, measured, NOT_APPLICABLE,
         format("%s %g", below ? "<" : ">", bound_value), ok ? "PASS" : "FAIL"});
  }
  void info(const std::string& group, const std::string& name, double expected, double measured) {
    const double e =
        expected != 0 && std::isfinite(expected) ? measured / expected - 1 : NOT_APPLICABLE;
    add({group, name, expected, measured, e, "info", "info"});
  }
  void failure(const std::string& group, const std::string& what) {
    add({group, group + ": " + what, NOT_APPLICABLE, NOT_APPLICABLE, NOT_APPLICABLE, "-", "FAIL"});
  }

  int failures() const {
    int n = 0;
    for (const Row& r : m_rows) n += r.verdict == "FAIL";
    return n;
  }
  int passes() const {
    int n = 0;
    for (const Row& r : m_rows) n += r.verdict == "PASS";
    return n;
  }
  void summary() const {
    std::printf("\n%d judged cases: %d PASS, %d FAIL (%zu rows with info)\n", passes() + failures(),
                passes(), failures(), m_rows.size() - passes() - failures());
    for (const Row& r : m_rows)
      if (r.verdict == "FAIL") std::printf("  FAIL  %s\n", r.name.c_str());
  }
  /// Written through a temporary name: the file appears complete or not at all.
  /// @throw common::OutputError naming the file when it cannot be written.
  void write_csv(const std::string& path) const {
    papersim::common::write_file_atomically(path, [&](std::ostream& out) {
      out << "group,case,expected,measured,rel_error,tolerance,verdict\n";
      out.precision(10);
      for (const Row& r : m_rows)
        out << r.group << ",\"" << r.name << "\"," << r.expected << ',' << r.measured << ','
            << (std::isnan(r.rel_error) ? std::string() : format("%.6g", r.rel_error)) << ",\""
            << r.tolerance << "\"," << r.verdict << '\n';
    });
  }

  template <typename... Args>
  static std::string format(const char* fmt, Args... args) {
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer), fmt, args...);
    return buffer;
  }

 private:
  std::vector<Row> m_rows;
};

template <typename... Args>
std::string fmt(const char* f, Args... args) {
  return Report::format(f, args...);
}

// ---------------------------------------------------------------------------------------------
// Building a simulation from the library's pieces (as tests/simulation/elastica_test.cpp does).

struct SimulationSetup {
  ps::Material material;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< [m/s^2]
  double damping = 0.0;                               ///< mass-proportional [1/s]; 0 = none
  /// Clamp of a strip: the band of material x <= clamp_x is held where it starts, slopes
  /// included; none when negative.
  double clamp_x = -1.0;  ///< [m]
  std::vector<std::shared_ptr<const pc::Collider>> obstacles;
  ps::ContactParams contact;
  ps::NewtonParams newton;
};

struct Simulation {
  std::unique_ptr<ps::Integrator> integrator;
  ps::SheetState state;
  const ps::BendingEnergy* bending = nullptr;
};

/// The run's composition of the incremental potential (ps::build_terms) for this setup.
Simulation make_simulation(const rm::SheetMesh& mesh, const Eigen::VectorXd& x0,
                           const SimulationSetup& s) {
  ps::PhysicsSetup p;
  p.material = s.material;
  p.material.damping = s.damping;
  p.gravity = s.gravity;
  if (s.clamp_x >= 0) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    ps::ClampSpec c;
    c.region = Eigen::Vector4d(-inf, -inf, s.clamp_x, inf);
    c.stiffness = 1e6;  // [N/m]
    p.clamps = {c};
    p.placement = ps::InitialPlacement(mesh, x0);
  }
  p.obstacles = s.obstacles;
  p.contact = s.contact;
  p.impact_rule = false;
  p.self_contact = false;
  ps::Terms terms = ps::build_terms(mesh, p);
  Simulation sim;
  sim.bending = terms.bending;
  sim.integrator =
      std::make_unique<ps::Integrator>(mesh.num_vertices(), std::move(terms.list), s.newton);
  sim.state.positions = x0;
  sim.state.velocities = Eigen::VectorXd::Zero(x0.size());
  return sim;
}

/// World positions of the flat sheet: (X, Y, 0).
Eigen::VectorXd flat_positions(const rm::SheetMesh& mesh) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  Eigen::VectorXd x(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v) x.segment<3>(3 * v) << X(v, 0), X(v, 1), 0.0;
  return x;
}

/// Vertices at the free end (largest material x) of a strip.
std::vector<int> tip_vertices(const rm::SheetMesh& mesh) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const double tip_x = X.col(0).maxCoeff();
  std::vector<int> tip;
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, 0) > tip_x - 1e-9) tip.push_back(v);
  return tip;
}

/// Mean of world component `axis` over vertices.
double mean_component(const Eigen::VectorXd& x, const std::vector<int>& vertices, int axis) {
  double s = 0;
  for (int v : vertices) s += x[3 * v + axis];
  return s / vertices.size();
}

// ---------------------------------------------------------------------------------------------
// Strips. The clamp is the band x <= 2h of a strip of free length L on [0, L + 2h] x [0, w].

struct Strip {
  rm::SheetMesh mesh;
  double length = 0.1;   ///< free length L [m]
  double clamp = 0.005;  ///< material x of the clamp line [m]
  double edge = 2.5e-3;  ///< target edge length h [m]
  double width = 0.01;   ///< [m]
  std::string label;     ///< "grid" or "30deg"
};

constexpr double STRIP_LENGTH = 0.1;       // [m] L
constexpr double STRIP_WIDTH = 0.01;       // [m]
constexpr double THIN_STRIP_WIDTH = 0.05;  // [m] room for faces 5 h long across the strip

Strip strip_along_grid(double h) {
  Strip s;
  s.edge = h;
  s.clamp = 2 * h;
  rm::RectangleOptions o;
  o.width = STRIP_LENGTH + s.clamp;
  o.height = STRIP_WIDTH;
  o.nx = static_cast<int>(std::lround(o.width / h)) + 1;
  o.ny = static_cast<int>(std::lround(STRIP_WIDTH / h)) + 1;
  o.triangulation = rm::Triangulation::alternating;
  s.mesh = rm::make_rectangle(o);
  s.width = STRIP_WIDTH;
  s.label = "grid";
  return s;
}

Strip strip_rotated(double h, double angle_deg) {
  Strip s;
  s.edge = h;
  s.clamp = 2 * h;
  rm::LatticeOptions o;
  o.width = STRIP_LENGTH + s.clamp;
  o.height = STRIP_WIDTH;
  o.edge_length = h;
  o.angle = angle_deg * PI / 180;
  // The clamp line is a line of vertices, as on the grid strip: a jagged clamp frontier would
  // clamp the strip further out (measured: tip drop 6.8% short at G = 1 instead of 4.8%).
  o.lines_x = {s.clamp};
  s.mesh = rm::make_rotated_lattice(o);
  s.width = STRIP_WIDTH;
  s.label = fmt("%gdeg", angle_deg);
  return s;
}

/// A strip 5 cm wide meshed by the Delaunay triangulation of a rectangular lattice whose spacing
/// is h along the direction at `angle_deg` to material x (the strip's length, the direction it
/// bends in) and h / aspect across it: faces `aspect` times as wide as long, like the anisotropic
/// faces remeshing makes (remesh.aspect_min). At 0 degrees the long edges lie along the bend's
/// generators (the faces are as the sizing of a cylinder asks), at 90 degrees across them. A line
/// of vertices at the clamp, as on the other strips.
Strip strip_thin_faces(double h, double aspect, double angle_deg) {
  Strip s;
  s.edge = h;
  s.clamp = 2 * h;
  s.width = THIN_STRIP_WIDTH;
  rm::LatticeOptions o;
  o.width = STRIP_LENGTH + s.clamp;
  o.height = s.width;
  o.edge_length = h;
  o.angle = angle_deg * PI / 180;
  o.aspect = aspect;
  o.lines_x = {s.clamp};
  s.mesh = rm::make_rotated_lattice(o);
  s.label = fmt("aspect %g at %gdeg", aspect, angle_deg);
  return s;
}

/// The table is for a beam (one-dimensional elastica). A plate strip with nu > 0 is stiffer
/// than D by up to 1 / (1 - nu^2) where its width keeps it from curving anticlastically, by an
/// amount that depends on w^2 / (R h); with nu = 0 the strip's bending stiffness is D exactly,
/// whatever its width, so G = rho_A g L^3 / D is unambiguous.
/// The bending discretisation under test (--bending).
ps::BendingModel g_bending_model = ps::Material{}.bending_model;
/// The strips' membrane stiffness [N/m] (--stretch-stiffness).
double g_stretch_stiffness = ps::Material{}.stretch_stiffness;
/// The membrane discretisation under test (--membrane).
ps::MembraneModel g_membrane_model = ps::Material{}.membrane_model;

ps::Material beam_material() {
  ps::Material m;
  m.poisson = 0.0;
  m.bending_model = g_bending_model;
  m.stretch_stiffness = g_stretch_stiffness;
  m.membrane_model = g_membrane_model;
  return m;
}

// ---------------------------------------------------------------------------------------------
// 1. Heavy elastica.

struct ElasticaCase {
  double G, tip_drop, reach, root_curvature;
};
// VALIDATION.md section 1 (shooting on theta'' = -G (1 - s) cos theta, RK4, 4000 steps).
const ElasticaCase ELASTICA[] = {
    {0.1, 0.01250, 0.99991, 0.050},   {0.5, 0.06231, 0.99778, 0.2496},
    {1, 0.12347, 0.99125, 0.4969},    {2, 0.23851, 0.96689, 0.9767},
    {4, 0.42516, 0.89011, 1.8443},    {6, 0.55392, 0.80373, 2.5782},
    {8, 0.64063, 0.72442, 3.2016},    {10, 0.70020, 0.65635, 3.7422},
    {15, 0.78604, 0.52957, 4.8561},   {20, 0.82988, 0.44523, 5.7615},
    {30, 0.87309, 0.34276, 7.2378},   {50, 0.90792, 0.24501, 9.5285},
    {100, 0.93752, 0.15922, 13.6932},
};

const ElasticaCase& elastica_case(double G) {
  for (const ElasticaCase& c : ELASTICA)
    if (c.G == G) return c;
  throw std::logic_error("no elastica case for this G");
}

struct ElasticaResult {
  double tip_drop = 0;        ///< / L
  double reach = 0;           ///< / L
  double root_curvature = 0;  ///< x L, from the face curvatures (root_curvature())
  double root_moment = 0;     ///< clamp moment / (D / L) [-] (root_moment())
  int steps = 0;
  bool at_rest = false;
  double seconds = 0;
};

/// Root curvature x L from the bending model's own face curvature tensors. The curvature of
/// the faces within about two edge lengths of the clamp is not resolved (their least-squares
/// stencils reach into the flat clamp), so K_xx (material x runs along the strip) is fitted by
/// a quadratic in s over the faces with s in [3h, 3h + L/4] and extrapolated to the root s = 0.
double root_curvature(const Strip& strip, const ps::BendingEnergy& bending,
                      const Eigen::VectorXd& x) {
  const Eigen::MatrixX3d K = bending.face_curvatures(x);
  const Eigen::MatrixX2d X = strip.mesh.material_coords();
  const Eigen::MatrixX3i F = strip.mesh.faces();
  std::vector<Eigen::Vector3d> rows;
  std::vector<double> values;
  for (int f = 0; f < F.rows(); ++f) {
    const double s = (X(F(f, 0), 0) + X(F(f, 1), 0) + X(F(f, 2), 0)) / 3 - strip.clamp;
    if (s < 3 * strip.edge || s > 3 * strip.edge + 0.25 * strip.length) continue;
    const double t = s / strip.length;
    rows.emplace_back(1.0, t, t * t);
    values.push_back(std::abs(K(f, 0)) * strip.length);
  }
  Eigen::MatrixXd A(rows.size(), 3);
  Eigen::VectorXd b(rows.size());
  for (size_t i = 0; i < rows.size(); ++i) A.row(i) = rows[i].transpose(), b[i] = values[i];
  return A.colPivHouseholderQr().solve(b)[0];
}

/// Root curvature x L from moment balance: in the beam the clamp moment is D kappa(0), and it
/// balances the moment of the weight of the free part about the clamp line, so
/// kappa(0) L = G integral_0^1 x(s) / L ds (integrate theta'' = -G (1 - s) cos theta once). The
/// integral is the lumped-mass sum over the free vertices. This reads the root curvature off
/// the deformed shape instead of the local face curvatures.
double root_moment(const Strip& strip, const Eigen::VectorXd& x, double G, double density) {
  const Eigen::MatrixX2d X = strip.mesh.material_coords();
  const Eigen::VectorXd mass = ps::lumped_masses(X, strip.mesh.faces(), density);
  double moment = 0;
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, 0) > strip.clamp + 1e-12) moment += mass[v] * (x[3 * v] - strip.clamp);
  const double L = strip.length;
  return G * moment / (density * strip.width * L * L);
}

/// Relax the clamped strip under gravity G D / (rho_A L^3) by damped backward Euler with large
/// steps (quasi-static, as in the elastica unit test).
ElasticaResult relax_elastica(const Strip& strip, double G) {
  const auto t0 = std::chrono::steady_clock::now();
  SimulationSetup s;
  s.material = beam_material();
  const double L = strip.length;
  s.gravity =
      Eigen::Vector3d(0, 0, -G * s.material.bending_stiffness / (s.material.density * L * L * L));
  s.damping = 20.0;  // [1/s], near critical for the first mode (24.9 rad/s)
  s.clamp_x = strip.clamp;
  // The rest test below (|v| < 1e-6 m/s) must not be met by a Newton solve that stops early:
  // with the default stopping speed (1e-4 m/s, 2 micrometres per 20 ms step) a slow creep
  // towards equilibrium stalls (measured: 30 degrees, 0.8 mm, G = 1 rested at -2.93% instead of
  // -1.61%). 1e-6 m/s is 20 nm per step.
  s.newton.tolerance = 1e-6;
  Simulation sim = make_simulation(strip.mesh, flat_positions(strip.mesh), s);
  ElasticaResult r;
  for (r.steps = 1; r.steps <= 400; ++r.steps) {
    sim.integrator->step(sim.state, 0.02);
    if (sim.state.velocities.cwiseAbs().maxCoeff() < 1e-6) {
      r.at_rest = true;
      break;
    }
  }
  const std::vector<int> tip = tip_vertices(strip.mesh);
  r.tip_drop = -mean_component(sim.state.positions, tip, 2) / L;
  r.reach = (mean_component(sim.state.positions, tip, 0) - strip.clamp) / L;
  r.root_curvature = root_curvature(strip, *sim.bending, sim.state.positions);
  r.root_moment = root_moment(strip, sim.state.positions, G, s.material.density);
  r.seconds = seconds_since(t0);
  return r;
}

constexpr double ELASTICA_TOLERANCE = 0.02;  // tip drop, issue 2 acceptance

void report_elastica(Report& report, const Strip& strip, const ElasticaCase& c,
                     const ElasticaResult& r) {
  const std::string where =
      fmt("elastica %s h=%.2fmm G=%g", strip.label.c_str(), 1e3 * strip.edge, c.G);
  if (!r.at_rest) report.note(where + ": not at rest after 400 steps of 20 ms");
  report.relative("elastica", where + " tip drop/L", c.tip_drop, r.tip_drop, ELASTICA_TOLERANCE);
  // Judged: the tip drop (issue 2 acceptance). Reported: reach (relative error grows as the
  // reach shrinks at large G) and the root curvature measured two ways (see root_moment() and
  // root_curvature()).
  report.info("elastica", where + " reach/L", c.reach, r.reach);
  report.info("elastica", where + " root curv*L (moment)", c.root_curvature, r.root_moment);
  report.info("elastica", where + " root curv*L (face K fit)", c.root_curvature, r.root_curvature);
}

void run_elastica(Report& report, bool quick) {
  const double h = 2.5e-3;
  const std::vector<double> Gs = quick ? std::vector<double>{1, 8}
                                       : std::vector<double>{0.1, 0.5, 1, 2, 4, 8, 10, 20, 50, 100};
  report.section(
      fmt("1. Heavy elastica (VALIDATION.md 1): strip L = %g cm x %g cm, clamp 2h, poisson 0, "
          "damped backward Euler (c = 20/s, h = 20 ms) to rest; tip drop and reach within 2%%",
          100 * STRIP_LENGTH, 100 * STRIP_WIDTH));
  for (const Strip& strip : {strip_along_grid(h), strip_rotated(h, 30)}) {
    report.note(fmt("mesh %s: target edge %.2f mm, %d vertices, %d faces", strip.label.c_str(),
                    1e3 * h, strip.mesh.num_vertices(), strip.mesh.num_faces()));
    double seconds = 0;
    for (double G : Gs) {
      const ElasticaResult r = relax_elastica(strip, G);
      seconds += r.seconds;
      report_elastica(report, strip, elastica_case(G), r);
    }
    report.note(fmt("(%.1f s)", seconds));
  }
}

/// Mesh convergence of the 30 degree strip: tip-drop error and observed order p between
/// successive meshes, p = ln(e1 / e2) / ln(h1 / h2).
void run_elastica_convergence(Report& report, bool quick) {
  const std::vector<double> hs =
      quick ? std::vector<double>{2.5e-3, 1.25e-3} : std::vector<double>{2.5e-3, 1.25e-3, 0.8e-3};
  const std::vector<double> Gs = quick ? std::vector<double>{1} : std::vector<double>{1, 8};
  report.section("1b. Heavy elastica, mesh convergence of the strip at 30 degrees to the grain");
  std::vector<Strip> strips;
  for (double h : hs) {
    strips.push_back(strip_rotated(h, 30));
    report.note(
        fmt("mesh 30deg h=%.2f mm: %d vertices", 1e3 * h, strips.back().mesh.num_vertices()));
  }
  for (double G : Gs) {
    const ElasticaCase& c = elastica_case(G);
    std::vector<double> errors;
    for (const Strip& strip : strips) {
      const ElasticaResult r = relax_elastica(strip, G);
      errors.push_back(std::abs(r.tip_drop / c.tip_drop - 1));
      report.relative(
          "elastica-convergence",
          fmt("elastica 30deg h=%.2fmm G=%g tip drop/L (%.1fs)", 1e3 * strip.edge, G, r.seconds),
          c.tip_drop, r.tip_drop, ELASTICA_TOLERANCE);
    }
    for (size_t i = 1; i < strips.size(); ++i) {
      const double p =
          std::log(errors[i - 1] / errors[i]) / std::log(strips[i - 1].edge / strips[i].edge);
      report.info("elastica-convergence",
                  fmt("elastica 30deg G=%g observed order h=%.2f->%.2fmm", G,
                      1e3 * strips[i - 1].edge, 1e3 * strips[i].edge),
                  1.0, p);
    }
  }
}

/// Thin faces (remeshing's aspect_min): does a face several times longer than wide bend as the
/// continuum does when its long edges do not lie along the bend's generators (membrane locking)?
/// The heavy elastica on strips of thin faces at angles to the bend, against strips of square
/// cells as fine as the thin faces are short (aspect 1, h) and as coarse as they are long (aspect
/// 1, h / aspect): a thin face that bends like the coarse square is under-resolved, one that is
/// stiffer than it locks. Reported, not judged: a measurement for docs/remeshing.md.
void run_thin_faces(Report& report, bool quick) {
  const double h = 2.5e-3;
  struct Mesh {
    double h, aspect;
  };
  const std::vector<Mesh> meshes =
      quick ? std::vector<Mesh>{{h, 1}, {h / 0.2, 1}, {h, 0.2}}
            : std::vector<Mesh>{{h, 1}, {h / 0.5, 1}, {h / 0.2, 1}, {h, 0.5}, {h, 0.2}};
  const std::vector<double> angles =
      quick ? std::vector<double>{0, 45} : std::vector<double>{0, 15, 30, 45, 60, 90};
  const std::vector<double> Gs = quick ? std::vector<double>{1} : std::vector<double>{1, 8};
  report.section(
      fmt("1c. Heavy elastica on thin faces: strip L = %g cm x %g cm, lattice spacing h "
          "along the angle to the strip, h / aspect across it",
          100 * STRIP_LENGTH, 100 * THIN_STRIP_WIDTH));
  for (const Mesh& mesh : meshes)
    for (double angle : angles) {
      // a square lattice at 60 / 90 degrees is at 30 / 0
      if (mesh.aspect == 1 && angle > 45) continue;
      const Strip strip = strip_thin_faces(mesh.h, mesh.aspect, angle);
      for (double G : Gs) {
        const ElasticaResult r = relax_elastica(strip, G);
        const ElasticaCase& c = elastica_case(G);
        const std::string where = fmt("thin h=%.1fmm %s (%d v) G=%g", 1e3 * mesh.h,
                                      strip.label.c_str(), strip.mesh.num_vertices(), G);
        if (!r.at_rest) report.note(where + ": not at rest after 400 steps of 20 ms");
        report.info("thin", where + " tip drop/L", c.tip_drop, r.tip_drop);
      }
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Self-buckling (Greenhill): a vertical strip clamped at its base.

constexpr double GREENHILL_G = 7.8373;

struct BucklingResult {
  double lateral = 0;  ///< tip displacement across the strip / L at the end
  bool at_rest = false;
  int steps = 0;
  double seconds = 0;
};

/// The strip stands on its clamp (material x up: world (0, Y, X)) under gravity G D /
/// (rho_A L^3), with an imperfection: a sideways component of 1e-3 g. Damped backward Euler
/// for at least 2 s and until at rest (or 12 s).
BucklingResult relax_vertical(const Strip& strip, double G) {
  const auto t0 = std::chrono::steady_clock::now();
  SimulationSetup s;
  s.material = beam_material();
  const double L = strip.length;
  const double g = G * s.material.bending_stiffness / (s.material.density * L * L * L);
  s.gravity = Eigen::Vector3d(-1e-3 * g, 0, -g);
  s.damping = 20.0;
  s.clamp_x = strip.clamp;
  const Eigen::MatrixX2d X = strip.mesh.material_coords();
  Eigen::VectorXd x0(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v) x0.segment<3>(3 * v) << 0.0, X(v, 1), X(v, 0);
  Simulation sim = make_simulation(strip.mesh, x0, s);
  BucklingResult r;
  for (r.steps = 1; r.steps <= 600; ++r.steps) {
    sim.integrator->step(sim.state, 0.02);
    if (r.steps >= 100 && sim.state.velocities.cwiseAbs().maxCoeff() < 1e-6) {
      r.at_rest = true;
      break;
    }
  }
  r.lateral = std::abs(mean_component(sim.state.positions, tip_vertices(strip.mesh), 0)) / L;
  r.seconds = seconds_since(t0);
  return r;
}

void run_greenhill(Report& report, bool quick) {
  report.section(
      "2. Self-buckling (VALIDATION.md 2): vertical strip L = 10 cm, G_c = 7.8373; imperfection "
      "1e-3 g sideways; below G_c the tip stays within 5% of L of the axis, above it moves "
      "more than 20% of L");
  const Strip strip = strip_along_grid(2.5e-3);
  for (double f :
       quick ? std::vector<double>{0.9, 1.1} : std::vector<double>{0.9, 0.97, 1.03, 1.1}) {
    const BucklingResult r = relax_vertical(strip, f * GREENHILL_G);
    const std::string where =
        fmt("greenhill grid h=2.50mm G=%.3g (%.2f G_c) tip sideways/L (%.1fs)", f * GREENHILL_G, f,
            r.seconds);
    if (!r.at_rest) report.note(where + ": not at rest after 12 s");
    report.bound("greenhill", where, f < 1 ? 0.05 : 0.2, r.lateral, f < 1);
  }
}

// ---------------------------------------------------------------------------------------------
// 3. Cylinder wrap.

/// World positions of the sheet wrapped isometrically onto a cylinder of radius R whose axis
/// makes the angle phi with material x (the sheet touches the cylinder along the material
/// line through the origin along the axis).
Eigen::VectorXd wrap_on_cylinder(const Eigen::MatrixX2d& X, double R, double phi) {
  const Eigen::Vector2d axis(std::cos(phi), std::sin(phi));
  const Eigen::Vector2d across(-axis.y(), axis.x());
  Eigen::VectorXd x(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v) {
    const Eigen::Vector2d p = X.row(v).transpose();
    const double s = p.dot(across), a = p.dot(axis);
    const Eigen::Vector2d in_plane = a * axis + R * std::sin(s / R) * across;
    x.segment<3>(3 * v) << in_plane.x(), in_plane.y(), R * (1 - std::cos(s / R));
  }
  return x;
}

void run_cylinder(Report& report, bool quick) {
  constexpr double R = 0.05, W = 0.1, H = 0.15, TOL = 0.03;
  report.section(
      "3. Cylinder wrap (VALIDATION.md 3): 10 x 15 cm sheet, 5 mm edges, on R = 5 cm; bending "
      "energy within 3% of D A / (2 R^2) for every mesh and axis angle; Gauss-Bonnet exact");
  struct MeshCase {
    std::string label;
    rm::SheetMesh mesh;
  };
  std::vector<MeshCase> meshes;
  const char* names[] = {"alternating", "random", "regular"};
  for (int t = 0; t < 3; ++t)
    for (double jitter : {0.0, 0.25}) {
      if (quick && jitter > 0 && t != 0) continue;
      rm::RectangleOptions o;
      o.width = W;
      o.height = H;
      o.nx = 21;
      o.ny = 31;
      o.triangulation = static_cast<rm::Triangulation>(t);
      o.jitter = jitter;
      o.seed = 11;
      meshes.push_back({fmt("%s%s", names[t], jitter > 0 ? "+jitter" : ""), rm::make_rectangle(o)});
    }
  rm::LatticeOptions lo;
  lo.width = W;
  lo.height = H;
  lo.edge_length = 5e-3;
  lo.angle = 30 * PI / 180;
  meshes.push_back({"lattice30", rm::make_rotated_lattice(lo)});
  ps::Material material;
  material.bending_model = g_bending_model;
  const double expected = material.bending_stiffness * W * H / (2 * R * R);
  const std::vector<double> angles =
      quick ? std::vector<double>{0, 30, 90} : std::vector<double>{0, 17, 30, 45, 90};
  for (const MeshCase& m : meshes) {
    const std::unique_ptr<ps::BendingEnergy> bending_model =
        ps::make_bending_energy(m.mesh, material);
    const ps::BendingEnergy& bending = *bending_model;
    const Eigen::MatrixX2d X = m.mesh.material_coords();
    const Eigen::MatrixX3i F = m.mesh.faces();
    const auto topology = papersim::validation::build_topology(F, static_cast<int>(X.rows()));
    double worst_gb = 0;
    for (double deg : angles) {
      const Eigen::VectorXd x = wrap_on_cylinder(X, R, deg * PI / 180);
      report.relative("cylinder", fmt("cylinder %s axis %g deg energy", m.label.c_str(), deg),
                      expected, bending.value(x), TOL);
      const Eigen::MatrixX3d P =
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(x.data(),
                                                                                      X.rows(), 3);
      const auto dev = papersim::validation::developability_metrics(P, F, topology);
      worst_gb = std::max(worst_gb, std::abs(dev.gauss_bonnet_residual));
    }
    report.bound("cylinder", fmt("cylinder %s |Gauss-Bonnet residual| [rad]", m.label.c_str()),
                 1e-9, worst_gb, true);
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Numerical damping of backward Euler on the first bending mode.

/// Fit x_{n+1} = a x_n + b x_{n-1} by least squares (Prony, two terms); returns the complex root
/// of lambda^2 - a lambda - b = 0 with positive imaginary part (NaN when the roots are real).
std::complex<double> prony_root(const std::vector<double>& z, size_t first) {
  Eigen::MatrixXd A(z.size() - first - 2, 2);
  Eigen::VectorXd y(A.rows());
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    const size_t n = first + 1 + static_cast<size_t>(i);
    A(i, 0) = z[n], A(i, 1) = z[n - 1], y[i] = z[n + 1];
  }
  const Eigen::Vector2d ab = A.colPivHouseholderQr().solve(y);
  const std::complex<double> disc = std::sqrt(std::complex<double>(ab[0] * ab[0] + 4 * ab[1], 0));
  const std::complex<double> root = 0.5 * (ab[0] + disc);
  return root.imag() >= 0 ? root : std::conj(root);
}

void run_damping(Report& report, bool quick) {
  report.section(
      "4. Backward-Euler damping (VALIDATION.md 5): clamped strip L = 10 cm, undamped, released "
      "from its sag at G = 0.2; mode from a Prony fit of the tip height; omega within 2%, "
      "decay per period within 2% of (1 + (w h)^2)^(-pi / (w h))");
  const Strip strip = strip_along_grid(2.5e-3);
  ps::Material material = beam_material();
  const double L = strip.length;
  const double omega1 =
      1.8751 * 1.8751 * std::sqrt(material.bending_stiffness / (material.density * L * L * L * L));
  // The released shape: the static sag at G = 0.2 (tip 2.5 mm, linear regime).
  SimulationSetup sag;
  sag.material = material;
  sag.gravity =
      Eigen::Vector3d(0, 0, -0.2 * material.bending_stiffness / (material.density * L * L * L));
  sag.damping = 20.0;
  sag.clamp_x = strip.clamp;
  sag.newton.tolerance = 1e-7;
  Simulation relax = make_simulation(strip.mesh, flat_positions(strip.mesh), sag);
  for (int k = 0; k < 400 && !(k > 10 && relax.state.velocities.cwiseAbs().maxCoeff() < 1e-8); ++k)
    relax.integrator->step(relax.state, 0.02);
  const std::vector<int> tip = tip_vertices(strip.mesh);
  const std::vector<double> whs =
      quick ? std::vector<double>{0.1, 1.0} : std::vector<double>{0.025, 0.1, 0.25, 1.0};
  for (double wh : whs) {
    const auto t0 = std::chrono::steady_clock::now();
    SimulationSetup s;
    s.material = material;
    s.clamp_x = strip.clamp;
    s.newton.tolerance = 1e-7;
    Simulation sim = make_simulation(strip.mesh, flat_positions(strip.mesh), s);
    sim.state.positions = relax.state.positions;
    const double h = wh / omega1;
    const double period_steps = 2 * PI / std::atan(wh);
    // Three discrete periods, or until the amplitude has fallen by 1e-4.
    const double per_step = 1 / std::sqrt(1 + wh * wh);
    const int steps =
        static_cast<int>(std::min(3 * period_steps, std::log(1e-4) / std::log(per_step)));
    std::vector<double> z{mean_component(sim.state.positions, tip, 2)};
    for (int k = 0; k < steps; ++k) {
      sim.integrator->step(sim.state, h);
      z.push_back(mean_component(sim.state.positions, tip, 2));
    }
    // Skip the first sixth of a period (the higher modes die out first under backward Euler).
    const std::complex<double> lambda = prony_root(z, static_cast<size_t>(period_steps / 6));
    const double omega_mesh = std::tan(std::arg(lambda)) / h;
    const double decay = std::pow(std::abs(lambda), 2 * PI / (omega_mesh * h));
    const double wh_mesh = omega_mesh * h;
    const double expected = std::pow(1 + wh_mesh * wh_mesh, -PI / wh_mesh);
    const double sec = seconds_since(t0);
    report.relative("damping",
                    fmt("damping w h = %g (h = %.3g ms, %d steps, %.1fs) omega [rad/s]", wh,
                        1e3 * h, steps, sec),
                    omega1, omega_mesh, 0.02);
    report.relative("damping", fmt("damping w h = %g amplitude factor per period", wh), expected,
                    decay, 0.02);
  }
}

// ---------------------------------------------------------------------------------------------
// 5. Friction on an incline.

struct InclineResult {
  double acceleration = 0;  ///< fitted down the slope [m/s^2]
  double travel = 0;        ///< mean displacement down the slope after 1 s [m]
  double seconds = 0;
};

/// A 4 x 4 cm sheet resting on the plane through the origin tilted to tan = 0.5 (an analytic
/// plane collider with a fixed rotation), mu as given, 1 s in steps of 5 ms. The slip speed
/// below which friction is static-like is 1e-5 m/s (the default 1e-3 m/s would let a sticking
/// sheet creep by up to a millimetre per second).
InclineResult slide_on_incline(double mu) {
  const auto t0 = std::chrono::steady_clock::now();
  const double alpha = std::atan(0.5);
  auto plane = std::make_shared<pc::PlaneCollider>();
  plane->friction = mu;
  pc::Keyframe k;
  k.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitY()));
  plane->motion = pc::RigidMotion({k});
  const Eigen::Vector3d normal(std::sin(alpha), 0, std::cos(alpha));
  const Eigen::Vector3d down(std::cos(alpha), 0, -std::sin(alpha));
  rm::RectangleOptions o;
  o.width = o.height = 0.04;
  o.nx = o.ny = 9;
  const rm::SheetMesh mesh = rm::make_rectangle(o);
  SimulationSetup s;
  s.gravity = Eigen::Vector3d(0, 0, -9.81);
  s.obstacles = {plane};
  s.contact.eps_velocity = 1e-5;
  s.newton.tolerance = 1e-7;
  const Eigen::MatrixX2d X = mesh.material_coords();
  Eigen::VectorXd x0(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v)
    x0.segment<3>(3 * v) =
        X(v, 0) * down + X(v, 1) * Eigen::Vector3d::UnitY() + 0.5 * s.contact.dhat * normal;
  Simulation sim = make_simulation(mesh, x0, s);
  const double h = 0.005;
  std::vector<double> t, d;
  for (int n = 1; n <= 200; ++n) {
    sim.integrator->step(sim.state, h);
    double mean = 0;
    for (int v = 0; v < X.rows(); ++v)
      mean += (sim.state.positions - x0).segment<3>(3 * v).dot(down);
    t.push_back(n * h), d.push_back(mean / X.rows());
  }
  // d(t) = c0 + c1 t + a t^2 / 2 over t in [0.2, 1] s (after the sheet has settled on the plane).
  std::vector<int> rows;
  for (size_t i = 0; i < t.size(); ++i)
    if (t[i] >= 0.2) rows.push_back(static_cast<int>(i));
  Eigen::MatrixXd A(rows.size(), 3);
  Eigen::VectorXd b(rows.size());
  for (size_t r = 0; r < rows.size(); ++r) {
    const double ti = t[rows[r]];
    A.row(r) << 1.0, ti, 0.5 * ti * ti;
    b[r] = d[rows[r]];
  }
  InclineResult r;
  r.acceleration = A.colPivHouseholderQr().solve(b)[2];
  r.travel = d.back();
  r.seconds = seconds_since(t0);
  return r;
}

void run_friction(Report& report, bool) {
  report.section(
      "5. Friction on an incline (VALIDATION.md 6): tan = 0.5, 4 x 4 cm sheet on a tilted plane "
      "collider, 1 s in 5 ms steps; mu = 0.49 slides at g (sin - mu cos) within 5%, mu = 0.51 "
      "moves less than 0.1 mm");
  const double alpha = std::atan(0.5);
  const InclineResult slide = slide_on_incline(0.49);
  report.relative("friction", fmt("incline mu=0.49 acceleration [m/s^2] (%.1fs)", slide.seconds),
                  9.81 * (std::sin(alpha) - 0.49 * std::cos(alpha)), slide.acceleration, 0.05);
  const InclineResult stick = slide_on_incline(0.51);
  report.bound("friction", fmt("incline mu=0.51 travel in 1 s [m] (%.1fs)", stick.seconds), 1e-4,
               std::abs(stick.travel), true);
}

// ---------------------------------------------------------------------------------------------
// 6. Plasticity: a strip bent by handles and released (return mapping of simulation/plasticity).

/// Curvature of the circular arc through the strip's ends and its middle [1/m]: the mean world
/// positions of the vertices at material x = 0, L / 2 and L give the chord c and the sagitta s,
/// and k = 2 s / (c^2 / 4 + s^2) (exact for an arc of any angle below 2 pi; 0 when flat).
double arc_curvature(const rm::SheetMesh& mesh, const Eigen::VectorXd& x, double length) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  auto mean_at = [&](double mx) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int n = 0;
    for (int v = 0; v < X.rows(); ++v)
      if (std::abs(X(v, 0) - mx) < 1e-9) sum += x.segment<3>(3 * v), ++n;
    if (n == 0)
      throw std::runtime_error("plasticity: no vertex column at material x = " +
                               std::to_string(mx));
    return Eigen::Vector3d(sum / n);
  };
  const Eigen::Vector3d a = mean_at(0), m = mean_at(0.5 * length), b = mean_at(length);
  const double c = (b - a).norm();
  const double sag = (m - a).cross(b - a).norm() / c;
  return 2 * sag / (0.25 * c * c + sag * sag);
}

/// Handles on every vertex of a flat strip (material x along its length, centred at the origin)
/// that wrap it onto a cylinder about y whose curvature grows linearly to k over [0, t_bend],
/// held until t_release, then released.
std::vector<ps::HandleSpec> bending_handles(const rm::SheetMesh& mesh, double length, double k,
                                            double t_bend, double t_release) {
  constexpr int KEYFRAMES = 20;
  std::vector<ps::HandleSpec> handles;
  const Eigen::MatrixX2d X = mesh.material_coords();
  for (int v = 0; v < X.rows(); ++v) {
    ps::HandleSpec h;
    h.material_point = X.row(v).transpose();
    h.release_time = t_release;
    h.stiffness = 1e4;  // [N/m] stiff against the strip's bending forces (~1e-3 N per vertex)
    const double s = X(v, 0) - 0.5 * length;
    for (int j = 0; j <= KEYFRAMES; ++j) {
      const double kj = k * j / KEYFRAMES;
      ps::HandleKeyframe f;
      f.time = t_bend * j / KEYFRAMES;
      f.displacement =
          kj > 0 ? Eigen::Vector3d(std::sin(kj * s) / kj - s, 0, (1 - std::cos(kj * s)) / kj)
                 : Eigen::Vector3d::Zero();
      h.keyframes.push_back(f);
    }
    handles.push_back(h);
  }
  return handles;
}

struct PlasticBendResult {
  double held = 0;            ///< fitted curvature just before the release [1/m]
  double residual = 0;        ///< fitted curvature at rest after the release [1/m]
  double model_residual = 0;  ///< mean k_xx of the bending model's faces at the end [1/m]
  double max_damage = 0;
  double max_speed = 0;  ///< at the end [m/s]
  double seconds = 0;
};

/// A 4 x 1 cm strip (2 mm edges) of paper with yield curvature ky bent by handles to k, held,
/// released and relaxed with mass damping and no gravity.
PlasticBendResult bend_and_release(double k, double ky, bool quick) {
  const auto t0 = std::chrono::steady_clock::now();
  const double length = 0.04, width = 0.01;
  const double t_bend = 0.2, t_release = 0.4;
  ps::Scene scene;
  scene.sheet.width = length;
  scene.sheet.height = width;
  scene.sheet.edge_length = quick ? 4e-3 : 2e-3;
  scene.sheet.position = Eigen::Vector3d::Zero();
  scene.sheet.material.yield_curvature = ky;
  scene.sheet.material.weakening = 1.0;
  scene.sheet.material.damping = 20.0;  // [1/s] to rest within the relaxation
  scene.sheet.material.bending_model = ps::BendingModel::morley;
  scene.sheet.material.membrane_model = g_membrane_model;
  scene.gravity = Eigen::Vector3d::Zero();
  scene.ground = false;
  scene.time_step = 5e-3;
  scene.duration = t_release + 1.0;
  // The last 1 1/m of the return flat moves the strip's ends by 0.2 mm: a Newton stop at the
  // default 1e-4 m/s (0.5 um per step) leaves it there; 1e-6 m/s follows it to rest.
  scene.newton.tolerance = 1e-6;
  rm::SheetMesh mesh;
  ps::SheetState start;
  ps::initial_sheet(scene, mesh, start);
  scene.handles = bending_handles(mesh, length, k, t_bend, t_release);
  ps::Run run(scene);
  PlasticBendResult r;
  while (!run.finished()) {
    run.step();
    if (std::abs(run.state().time - 0.5 * (t_bend + t_release)) < 0.5 * run.time_step()) {
      r.held = arc_curvature(run.mesh(), run.state().positions, length);
    }
  }
  r.residual = arc_curvature(run.mesh(), run.state().positions, length);
  r.model_residual = run.terms().bending->face_curvatures(run.state().positions).col(0).mean();
  r.max_damage = run.mesh().damage().maxCoeff();
  for (int v = 0; v < run.state().num_vertices(); ++v)
    r.max_speed = std::max(r.max_speed, run.state().velocities.segment<3>(3 * v).norm());
  r.seconds = seconds_since(t0);
  return r;
}

/// World position (x, z) of material abscissa s of a strip folded at s = 0 to angle phi [rad]
/// with bend radius r [m]: flat for s < 0, an arc of radius r over [0, r phi], straight beyond.
Eigen::Vector2d folded_point(double s, double phi, double r) {
  if (s <= 0) return {s, 0.0};
  const double a = std::min(s, r * phi);
  Eigen::Vector2d p(r * std::sin(a / r), r * (1 - std::cos(a / r)));
  if (s > r * phi) p += (s - r * phi) * Eigen::Vector2d(std::cos(phi), std::sin(phi));
  return p;
}

struct FoldResult {
  double rest_angle = 0;  ///< fold angle at rest after the release [rad]
  /// vertical force of the handles on the upper leg at the end of the press [N]
  double press_force = 0;
  double seconds = 0;
};

/// A 4 cm x 3 mm strip (0.5 mm edges) folded by handles on every vertex about material x = 1 cm,
/// to 180 degrees over 0.2 s with bend radius r, held to 0.3 s, released, relaxed 1 s (damping
/// 20/s, no gravity, no self-contact: the legs open on release).
FoldResult fold_and_release(double r, double ky, bool quick) {
  const auto t0 = std::chrono::steady_clock::now();
  const double length = 0.04, width = 0.003, x_fold = 0.01, t_fold = 0.2, t_release = 0.3;
  ps::Scene scene;
  scene.sheet.width = length;
  scene.sheet.height = width;
  scene.sheet.edge_length = quick ? 1e-3 : 5e-4;
  scene.sheet.position = Eigen::Vector3d(0.5 * length - x_fold, 0, 0);
  scene.sheet.material.yield_curvature = ky;
  scene.sheet.material.damping = 20.0;
  scene.sheet.material.bending_model = ps::BendingModel::morley;
  scene.sheet.material.membrane_model = g_membrane_model;
  scene.gravity = Eigen::Vector3d::Zero();
  scene.ground = false;
  scene.time_step = 5e-3;
  scene.duration = t_release + 1.0;
  scene.newton.tolerance = 1e-6;
  rm::SheetMesh mesh;
  ps::SheetState start;
  ps::initial_sheet(scene, mesh, start);
  const Eigen::MatrixX2d X = mesh.material_coords();
  constexpr int KEYFRAMES = 20;
  for (int v = 0; v < X.rows(); ++v) {
    ps::HandleSpec h;
    h.material_point = X.row(v).transpose();
    h.release_time = t_release;
    h.stiffness = 1e4;
    const double s = X(v, 0) - x_fold;
    for (int j = 0; j <= KEYFRAMES; ++j) {
      const Eigen::Vector2d p = folded_point(s, PI * j / KEYFRAMES, r);
      h.keyframes.push_back({t_fold * j / KEYFRAMES, Eigen::Vector3d(p.x() - s, 0, p.y())});
    }
    scene.handles.push_back(h);
  }
  ps::Run run(scene);
  FoldResult out;
  while (!run.finished()) {
    run.step();
    if (std::abs(run.state().time - 0.5 * (t_fold + t_release)) < 0.5 * run.time_step()) {
      // Force of the handles on the upper leg (beyond the arc), vertical component.
      for (int v = 0; v < X.rows(); ++v) {
        if (X(v, 0) - x_fold <= PI * r) continue;
        const Eigen::Vector3d target = start.positions.segment<3>(3 * v) +
                                       ps::handle_displacement(scene.handles[v], run.state().time);
        out.press_force +=
            scene.handles[v].stiffness * (target - run.state().positions.segment<3>(3 * v)).z();
      }
    }
  }
  // Leg directions away from the fold: lower leg from x = 5 mm to 0, upper from 3 cm to 4 cm.
  const Eigen::VectorXd& x = run.state().positions;
  auto mean_at = [&](double mx) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int n = 0;
    for (int v = 0; v < X.rows(); ++v)
      if (std::abs(X(v, 0) - mx) < 1e-9) sum += x.segment<3>(3 * v), ++n;
    return Eigen::Vector3d(sum / n);
  };
  const Eigen::Vector3d lower = (mean_at(0.0) - mean_at(0.005)).normalized();
  const Eigen::Vector3d upper = (mean_at(0.04) - mean_at(0.03)).normalized();
  out.rest_angle = PI - std::acos(std::clamp(lower.dot(upper), -1.0, 1.0));
  out.seconds = seconds_since(t0);
  return out;
}

void run_plasticity(Report& report, bool quick) {
  constexpr double KY = 50;  // [1/m] yield curvature of the cases
  report.section(
      "6. Plasticity (issue 16): 4 x 1 cm strip wrapped by handles onto a cylinder of curvature k, "
      "held, released, relaxed (k_y = 50 1/m); below yield flat (|k| < 2% of k), above k - k_y "
      "within "
      "5%. Then a 4 cm x 3 mm strip folded 180 deg at radius r (k_y = 200 1/m), released: rest "
      "angle against pi (1 - k_y r)");
  if (g_bending_model != ps::BendingModel::morley) {
    report.note("plasticity: skipped under --bending fit (the fit model carries no plasticity)");
    return;
  }
  const PlasticBendResult below = bend_and_release(0.8 * KY, KY, quick);
  report.info("plasticity", fmt("plastic k=%g held curvature [1/m]", 0.8 * KY), 0.8 * KY,
              below.held);
  report.bound(
      "plasticity",
      fmt("plastic k=%g (below yield) residual |k| [1/m] (%.1fs)", 0.8 * KY, below.seconds),
      0.02 * 0.8 * KY, std::abs(below.residual), true);
  report.bound("plasticity", fmt("plastic k=%g damage", 0.8 * KY), 1e-12, below.max_damage, true);
  for (double k : {2 * KY, 3 * KY}) {
    const PlasticBendResult r = bend_and_release(k, KY, quick);
    report.info("plasticity", fmt("plastic k=%g held curvature [1/m]", k), k, r.held);
    // Moment-free state of the return mapping: the plastic curvature k_held - k_y.
    report.relative("plasticity",
                    fmt("plastic k=%g residual curvature [1/m] (%.1fs)", k, r.seconds), r.held - KY,
                    r.residual, 0.05);
    report.info("plasticity", fmt("plastic k=%g residual mean face k_xx (model) [1/m]", k),
                r.held - KY, r.model_residual);
    report.info("plasticity", fmt("plastic k=%g largest damage (expected (k - k_y) / k_y)", k),
                (k - KY) / KY, r.max_damage);
    report.bound("plasticity", fmt("plastic k=%g largest speed at the end [m/s]", k), 1e-3,
                 r.max_speed, true);
  }
  // A strip folded 180 degrees about a bend of radius r and released keeps, moment-free, the
  // plastic curvature 1/r - k_y over the arc of length pi r: a fold of pi (1 - k_y r) (none
  // from r = 1 / k_y up). The press is the handles holding the upper leg at distance 2 r.
  constexpr double FOLD_KY = 200;  // [1/m] paper
  for (double r : {4e-3, 2e-3, 1e-3}) {
    const FoldResult f = fold_and_release(r, FOLD_KY, quick);
    const double expected = PI * (1 - FOLD_KY * r) * 180 / PI;
    // Reported, not judged: the arc spans only 3 to 12 edges (2 to 6 with --quick), and the
    // curvature jump at its ends is smeared over the yield measure's stencil (measured with
    // --quick: -5%, -11%, -12% at r = 4, 2, 1 mm).
    report.info("plasticity",
                fmt("fold 180deg r=%gmm rest angle [deg] (%.1fs)", 1e3 * r, f.seconds), expected,
                f.rest_angle * 180 / PI);
    report.info("plasticity",
                fmt("fold 180deg r=%gmm press: handle force on the upper leg [N/m]", 1e3 * r),
                NOT_APPLICABLE, f.press_force / 0.003);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_known_answers: the simulator against the known answers of VALIDATION.md "
      "(heavy elastica, self-buckling, cylinder wrap, backward-Euler damping, friction on "
      "an incline, bending plasticity; reported only, the elastica on thin faces). Exit status 1 "
      "when a "
      "case fails."};
  bool quick = false;
  std::string csv;
  std::vector<std::string> only;
  app.add_flag("--quick", quick, "coarser meshes and fewer cases (a smoke run, about a minute)");
  app.add_option("--csv", csv, "also write the rows as CSV to this file");
  app.add_option(
         "--only", only,
         "run only these families: elastica, convergence, greenhill, cylinder, damping, friction, "
         "plasticity, thin (the elastica on thin faces at angles to the bend)")
      ->check(CLI::IsMember({"elastica", "convergence", "greenhill", "cylinder", "damping",
                             "friction", "plasticity", "thin"}));
  std::string bending = "morley";
  app.add_option("--bending", bending,
                 "bending discretisation under test: morley (the simulator's default) or fit")
      ->check(CLI::IsMember({"fit", "morley"}));
  app.add_option(
         "--stretch-stiffness", g_stretch_stiffness,
         "membrane stiffness of the strips [N/m] (default: the material's, 5e5); the strain "
         "limit stays. With 'thin': how much of the stiffening is membrane locking")
      ->check(papersim::common::positive());
  std::string membrane = "chord";
  app.add_option(
         "--membrane", membrane,
         "membrane discretisation of the beams and strips: chord (the simulator's default) or "
         "arc (edges measured along the bent surface; sheet.material.membrane_model)")
      ->check(CLI::IsMember({"chord", "arc"}));
  CLI11_PARSE(app, argc, argv);
  g_membrane_model = membrane == "arc" ? ps::MembraneModel::arc : ps::MembraneModel::chord;
  g_bending_model = bending == "morley" ? ps::BendingModel::morley : ps::BendingModel::fit;

  const std::set<std::string> selected(only.begin(), only.end());
  const auto wanted = [&](const std::string& name) {
    return selected.empty() || selected.count(name);
  };
  const std::vector<std::pair<std::string, std::function<void(Report&, bool)>>> families = {
      {"elastica", run_elastica},     {"convergence", run_elastica_convergence},
      {"greenhill", run_greenhill},   {"cylinder", run_cylinder},
      {"damping", run_damping},       {"friction", run_friction},
      {"plasticity", run_plasticity}, {"thin", run_thin_faces},
  };
  const auto t0 = std::chrono::steady_clock::now();
  Report report;
  std::printf("papersim known answers%s, bending model %s\n", quick ? " (--quick)" : "",
              bending.c_str());
  report.header();
  for (const auto& [name, run] : families) {
    if (!wanted(name)) continue;
    try {
      run(report, quick);
    } catch (const std::exception& e) {
      report.failure(name, e.what());
    }
  }
  report.summary();
  std::printf("wall time %.1f s\n", seconds_since(t0));
  if (!csv.empty()) {
    try {
      report.write_csv(csv);
      std::printf("wrote %s\n", csv.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "papersim_known_answers: %s\n", e.what());
      return 2;
    }
  }
  return report.failures() == 0 ? 0 : 1;
}
