// Bending probe (diagnostic, see docs/elastica_30deg_diagnosis.md): for the elastica strips of
// known_answers (L = 10 cm, grid and 30 degree lattice, clamp line at x = 2h, Poisson 0)
//   - linear sag: the small-G tip drop of the clamped strip from the bending stiffness at the flat
//     state (central differences of the gradient in the out-of-plane displacements), divided by
//     the beam's G / 8, and the first mode frequencies over the cantilever's first one (a beam
//     gives 1, 6.27, 17.5); instant, and it reproduces the simulated G = 1 error;
//   - the discrete bending energy of prescribed isometric shapes (constant, linear, quadratic
//     curvature along x; constant curvature after the clamp line; the shooting elastica at
//     G = 1, 8, 20) over the continuum D/2 int K^2 dA, split into the curvature-fit part and the
//     fit-residual part;
//   - the same sag under a linear Morley plate (one normal slope unknown per edge), with free or
//     extrapolated boundary edges and with or without the slopes clamped in the clamp band, and
//     (--cylinder) its energy of a small-slope cylinder on a 15 cm wide sheet: the
//     consistent discretisation docs/elastica_30deg_diagnosis.md section 5 measures.
// Usage: papersim_bending_probe [--edge H] [--width W] [--angle DEG] [--bins] [--sag-only]
// [--mode-shape] [--cylinder]; papersim_bending_probe --modes; papersim_bending_probe --fold R
// (--help lists them).
#include <CLI/CLI.hpp>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/Sparse>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "remesh/sheet_generator.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/energies/fit_bending_energy.hpp"
#include "simulation/energies/vertex_energies.hpp"

namespace ps = papersim::simulation;
namespace rm = papersim::remesh;

namespace {

constexpr double L = 0.1, W = 0.01;

/// The command line's choices, read once in main.
struct ProbeOptions {
  double edge = 2.5e-3;     // [m]
  double width = W;         // [m]
  double angle = 30;        // lattice angle [deg]
  bool bins = false;        // energy and K_xx by x bins
  bool sag_only = false;    // the sags alone, no energies of prescribed shapes
  bool mode_shape = false;  // the first mode's displacements
  bool cylinder = false;    // the Morley plate's cylinder energies
  bool modes = false;       // zero modes and twist of the Morley plate
  double fold = 0;          // > 0: a 180-degree fold of this radius [m]
};
ProbeOptions options;

rm::SheetMesh strip(bool rotated, double h, double width) {
  const double c = 2 * h;
  if (!rotated) {
    rm::RectangleOptions o;
    o.width = L + c;
    o.height = width;
    o.nx = static_cast<int>(std::lround(o.width / h)) + 1;
    o.ny = static_cast<int>(std::lround(width / h)) + 1;
    o.triangulation = rm::Triangulation::alternating;
    return rm::make_rectangle(o);
  }
  rm::LatticeOptions o;
  o.width = L + c;
  o.height = width;
  o.edge_length = h;
  o.angle = options.angle * M_PI / 180;
  o.lines_x = {c};
  return rm::make_rotated_lattice(o);
}

/// Planar curve with curvature kappa(s) (s from material x = 0), integrated by RK4 on a fine grid.
struct Curve {
  double ds;
  std::vector<double> x, z, th;
  Curve(std::function<double(double)> kappa, double length, int n = 20000) : ds(length / n) {
    x = z = th = std::vector<double>(n + 1, 0.0);
    for (int i = 0; i < n; ++i) {
      const double s = i * ds;
      // theta' = kappa, x' = cos, z' = sin; RK4 on (th, x, z).
      auto f = [&](double ss, double t) {
        return std::array<double, 3>{kappa(ss), std::cos(t), std::sin(t)};
      };
      auto k1 = f(s, th[i]);
      auto k2 = f(s + ds / 2, th[i] + ds / 2 * k1[0]);
      auto k3 = f(s + ds / 2, th[i] + ds / 2 * k2[0]);
      auto k4 = f(s + ds, th[i] + ds * k3[0]);
      th[i + 1] = th[i] + ds / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
      x[i + 1] = x[i] + ds / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
      z[i + 1] = z[i] + ds / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2]);
    }
  }
  Eigen::Vector2d at(double s) const {
    const double u = s / ds;
    const int i = std::min(static_cast<int>(u), static_cast<int>(x.size()) - 2);
    const double t = u - i;
    // cubic Hermite with derivatives (cos th, sin th)
    const double h00 = 2 * t * t * t - 3 * t * t + 1, h10 = t * t * t - 2 * t * t + t,
                 h01 = -2 * t * t * t + 3 * t * t, h11 = t * t * t - t * t;
    return {
        h00 * x[i] + h10 * ds * std::cos(th[i]) + h01 * x[i + 1] + h11 * ds * std::cos(th[i + 1]),
        h00 * z[i] + h10 * ds * std::sin(th[i]) + h01 * z[i + 1] + h11 * ds * std::sin(th[i + 1])};
  }
};

/// Heavy elastica curvature kappa(s) L for theta'' = -G (1 - s) cos theta, theta(0)=0, theta'(1)=0.
std::vector<double> elastica_kappa(double G, int n, double* tip_drop) {
  auto shoot = [&](double k0, std::vector<double>* out) {
    double t = 0, k = k0, ds = 1.0 / n, z = 0;
    if (out) out->assign(n + 1, 0), (*out)[0] = k;
    for (int i = 0; i < n; ++i) {
      const double s = i * ds;
      auto f = [&](double ss, double tt, double kk) {
        return std::array<double, 3>{kk, -G * (1 - ss) * std::cos(tt), std::sin(tt)};
      };
      auto a = f(s, t, k);
      auto b = f(s + ds / 2, t + ds / 2 * a[0], k + ds / 2 * a[1]);
      auto c = f(s + ds / 2, t + ds / 2 * b[0], k + ds / 2 * b[1]);
      auto d = f(s + ds, t + ds * c[0], k + ds * c[1]);
      t += ds / 6 * (a[0] + 2 * b[0] + 2 * c[0] + d[0]);
      k += ds / 6 * (a[1] + 2 * b[1] + 2 * c[1] + d[1]);
      z += ds / 6 * (a[2] + 2 * b[2] + 2 * c[2] + d[2]);
      if (out) (*out)[i + 1] = k;
    }
    if (tip_drop) *tip_drop = z;
    return k;
  };
  double lo = 0, hi = 2 * G + 1;
  for (int it = 0; it < 200; ++it) {
    const double mid = (lo + hi) / 2;
    (shoot(mid, nullptr) > 0 ? hi : lo) = mid;
  }
  std::vector<double> out;
  shoot((lo + hi) / 2, &out);
  return out;
}

void probe(const char* label, const rm::SheetMesh& mesh, double clamp, double width,
           std::function<double(double)> kappa_of_x) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const double xmax = X.col(0).maxCoeff();
  Curve curve(kappa_of_x, xmax * 1.001);
  Eigen::VectorXd x(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v) {
    const Eigen::Vector2d q = curve.at(X(v, 0));
    x.segment<3>(3 * v) << q.x(), X(v, 1), q.y();
  }
  ps::Material m;
  m.poisson = 0;
  ps::FitBendingEnergy bend(mesh, m);
  const double D = m.bending_stiffness;
  const double E = bend.value(x);
  const Eigen::MatrixX3d K = bend.face_curvatures(x);
  // Continuum energy by quadrature
  double Ec = 0;
  const int nq = 200000;
  for (int i = 0; i < nq; ++i) {
    const double s = (i + 0.5) * xmax / nq;
    Ec += 0.5 * D * width * kappa_of_x(s) * kappa_of_x(s) * xmax / nq;
  }
  // Fit part, by bins of x.
  const int nb = 8;
  std::vector<double> fit(nb, 0), cont(nb, 0), kd(nb, 0), kc(nb, 0), area(nb, 0);
  double Efit = 0;
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Matrix2d T;
    T.col(0) = (X.row(F(f, 1)) - X.row(F(f, 0))).transpose();
    T.col(1) = (X.row(F(f, 2)) - X.row(F(f, 0))).transpose();
    const double A = 0.5 * std::abs(T.determinant());
    const double xc = (X(F(f, 0), 0) + X(F(f, 1), 0) + X(F(f, 2), 0)) / 3;
    const double e = 0.5 * D * A * (K(f, 0) * K(f, 0) + K(f, 1) * K(f, 1) + 2 * K(f, 2) * K(f, 2));
    Efit += e;
    const int b = std::min(nb - 1, static_cast<int>(xc / xmax * nb));
    fit[b] += e;
    cont[b] += 0.5 * D * A * kappa_of_x(xc) * kappa_of_x(xc);
    kd[b] += A * std::abs(K(f, 0));
    kc[b] += A * std::abs(kappa_of_x(xc));
    area[b] += A;
  }
  std::printf("%-34s E/Ec = %.4f  fit/Ec = %.4f  resid/Ec = %.4f\n", label, E / Ec, Efit / Ec,
              (E - Efit) / Ec);
  if (options.bins) {
    for (int b = 0; b < nb; ++b)
      std::printf("    bin %d x=[%.3f,%.3f]  fit/cont(centroid) %.4f   Kxx/kappa %.4f\n", b,
                  b * xmax / nb, (b + 1) * xmax / nb, fit[b] / cont[b], kd[b] / kc[b]);
  }
  (void)clamp;
}

/// Linear (small-G) sag of the clamped strip: stiffness of the out-of-plane displacement at the
/// flat state by differences of the gradient, solved for the uniform load; tip drop / (G L / 8).
void linear_sag(const char* label, const rm::SheetMesh& mesh, double clamp, double width) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const int nv = X.rows();
  ps::Material m;
  m.poisson = 0;
  ps::FitBendingEnergy bend(mesh, m);
  Eigen::VectorXd x0(3 * nv);
  for (int v = 0; v < nv; ++v) x0.segment<3>(3 * v) << X(v, 0), X(v, 1), 0.0;
  std::vector<int> free;
  for (int v = 0; v < nv; ++v)
    if (X(v, 0) > clamp + 1e-12) free.push_back(v);
  const int n = free.size();
  Eigen::MatrixXd H(n, n);
  const double eps = 1e-7;
  for (int j = 0; j < n; ++j) {
    Eigen::VectorXd x = x0;
    x[3 * free[j] + 2] += eps;
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * nv), g2 = g;
    bend.add_gradient(x, g);
    x[3 * free[j] + 2] -= 2 * eps;
    bend.add_gradient(x, g2);
    for (int i = 0; i < n; ++i) H(i, j) = (g[3 * free[i] + 2] - g2[3 * free[i] + 2]) / (2 * eps);
  }
  H = 0.5 * (H + H.transpose()).eval();
  const Eigen::VectorXd mass = ps::lumped_masses(X, mesh.faces(), m.density);
  const double G = 1.0, g = G * m.bending_stiffness / (m.density * L * L * L);
  Eigen::VectorXd f(n), M(n);
  for (int i = 0; i < n; ++i) f[i] = -mass[free[i]] * g, M[i] = mass[free[i]];
  const Eigen::VectorXd w = H.ldlt().solve(f);
  const double tip_x = X.col(0).maxCoeff();
  double drop = 0;
  int cnt = 0;
  for (int i = 0; i < n; ++i)
    if (X(free[i], 0) > tip_x - 1e-9) drop -= w[i], ++cnt;
  drop /= cnt * L;
  // Modes: H v = w^2 M v, relative to the clamped-free beam's first bending mode.
  Eigen::VectorXd Mi = M.cwiseSqrt().cwiseInverse();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Mi.asDiagonal() * H * Mi.asDiagonal());
  const double w1 = 1.8751 * 1.8751 * std::sqrt(m.bending_stiffness / (m.density * std::pow(L, 4)));
  std::printf("%-28s linear sag / (G/8) = %.4f   omega_k/omega_beam1:", label, drop / (G / 8));
  for (int k = 0; k < 6; ++k)
    std::printf(" %.3f", std::sqrt(std::max(0.0, es.eigenvalues()[k])) / w1);
  std::printf("\n");
  if (options.mode_shape) {
    const Eigen::VectorXd v = Mi.asDiagonal() * es.eigenvectors().col(0);
    for (int i = 0; i < n; ++i)
      std::printf("  x=%.5f y=%.5f w=%.5f\n", X(free[i], 0), X(free[i], 1),
                  v[i] / v.cwiseAbs().maxCoeff());
  }
  (void)width;
}

/// Linear Morley plate: the heights z of the vertices and one normal slope phi per edge (at its
/// midpoint) determine a constant curvature per face, exact for every quadratic height field:
/// for the edge (p_i, p_j) of face f with opposite vertex p_k, outward normal n and height h,
///   dz/dn(midpoint) - grad(I_f z) . n = a^T K_f b / (2 h),  a = p_k - p_i, b = p_k - p_j,
/// where I_f z is the linear interpolant. K is the stiffness of sum_f A_f D/2 K_f^T Q K_f over
/// (z, phi). Boundary edges: phi free (natural boundary condition), or, with `extrapolate`,
/// tied by a stiff penalty to the slope the mean curvature of the face's interior neighbours
/// gives there.
struct Morley {
  int nv = 0, ne = 0;
  std::map<std::pair<int, int>, int> edge_of;  // sorted vertex pair -> edge
  Eigen::SparseMatrix<double> K;               // (nv + ne)^2
  double area = 0;
};

Morley morley_system(const rm::SheetMesh& mesh, bool extrapolate) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const int nf = F.rows();
  Morley M;
  M.nv = X.rows();
  std::vector<Eigen::Vector2d> normal;  // fixed unit normal per edge
  Eigen::MatrixX3i fe(nf, 3);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const auto key = std::minmax(F(f, (k + 1) % 3), F(f, (k + 2) % 3));
      auto it = M.edge_of.find(key);
      if (it == M.edge_of.end()) {
        const Eigen::Vector2d d = X.row(key.second) - X.row(key.first);
        normal.push_back(Eigen::Vector2d(d.y(), -d.x()).normalized());
        it = M.edge_of.emplace(key, static_cast<int>(normal.size()) - 1).first;
      }
      fe(f, k) = it->second;
    }
  M.ne = normal.size();
  const int nv = M.nv;
  ps::Material m;
  m.poisson = 0;
  Eigen::Matrix3d Q = (1 - m.poisson) * Eigen::Vector3d(1, 1, 2).asDiagonal().toDenseMatrix();
  Q += m.poisson * Eigen::Vector3d(1, 1, 0) * Eigen::RowVector3d(1, 1, 0);
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<Eigen::Matrix<double, 3, 6>> C(nf), S(nf);  // K_f = C s_dofs, s = S dofs
  std::vector<Eigen::Matrix3d> R(nf);                     // R K = s
  std::vector<double> area(nf);
  auto dofs = [&](int f, int* d) {
    for (int k = 0; k < 3; ++k) d[k] = F(f, k), d[3 + k] = nv + fe(f, k);
  };
  auto add_quadratic = [&](const std::map<int, double>& row, double w) {
    for (const auto& [i, a] : row)
      for (const auto& [j, b] : row) trip.emplace_back(i, j, w * a * b);
  };
  for (int f = 0; f < nf; ++f) {
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = X.row(F(f, k));
    Eigen::Matrix2d T;
    T.col(0) = p[1] - p[0];
    T.col(1) = p[2] - p[0];
    area[f] = 0.5 * std::abs(T.determinant());
    M.area += area[f];
    Eigen::Matrix<double, 2, 3> grad;  // gradient of the linear interpolant = grad z
    const Eigen::Matrix2d Ti = T.inverse().transpose();
    grad.col(1) = Ti.col(0);
    grad.col(2) = Ti.col(1);
    grad.col(0) = -grad.col(1) - grad.col(2);
    S[f].setZero();
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d pi = p[(k + 1) % 3], pj = p[(k + 2) % 3], pk = p[k];
      const Eigen::Vector2d e = (pj - pi).normalized();
      Eigen::Vector2d n(e.y(), -e.x());
      if (n.dot(pk - pi) > 0) n = -n;
      const double h = std::abs(n.dot(pk - pi));
      const Eigen::Vector2d a = pk - pi, b = pk - pj;
      R[f].row(k) << a.x() * b.x(), a.y() * b.y(), a.x() * b.y() + a.y() * b.x();
      R[f].row(k) /= 2 * h;
      S[f](k, 3 + k) = n.dot(normal[fe(f, k)]) > 0 ? 1 : -1;
      S[f].block<1, 3>(k, 0) = -(n.transpose() * grad);
    }
    C[f] = R[f].inverse() * S[f];
    const Eigen::Matrix<double, 6, 6> Ke =
        area[f] * m.bending_stiffness * C[f].transpose() * Q * C[f];
    int d[6];
    dofs(f, d);
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) trip.emplace_back(d[r], d[c], Ke(r, c));
  }
  if (extrapolate) {
    std::vector<std::vector<int>> edge_faces(M.ne);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) edge_faces[fe(f, k)].push_back(f);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        if (edge_faces[fe(f, k)].size() != 1) continue;
        std::vector<int> neighbours;
        for (int j = 0; j < 3; ++j)
          for (int g : edge_faces[fe(f, j)])
            if (g != f) neighbours.push_back(g);
        std::map<int, double> row;  // s_fk - R_f,k . mean_g K_g
        int d[6];
        dofs(f, d);
        for (int c = 0; c < 6; ++c) row[d[c]] += S[f](k, c);
        for (int g : neighbours) {
          dofs(g, d);
          const Eigen::Matrix<double, 1, 6> a = R[f].row(k) * C[g] / neighbours.size();
          for (int c = 0; c < 6; ++c) row[d[c]] -= a[c];
        }
        add_quadratic(row, 1e6 * m.bending_stiffness);  // (s / h)^2 A D with A ~ h^2, x 1e6
      }
  }
  M.K.resize(nv + M.ne, nv + M.ne);
  M.K.setFromTriplets(trip.begin(), trip.end());
  return M;
}

/// Tip sag over G/8 of the clamped strip under the Morley plate (heights fixed to 0 up to the
/// clamp line; with `clamp_slopes` the slopes of the edges within the clamp too).
double morley_sag(const rm::SheetMesh& mesh, double clamp, bool extrapolate, bool clamp_slopes) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  Morley M = morley_system(mesh, extrapolate);
  const double big = 1e12;
  ps::Material m;
  const Eigen::VectorXd mass = ps::lumped_masses(X, mesh.faces(), m.density);
  const double G = 1.0, g = G * m.bending_stiffness / (m.density * L * L * L);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(M.nv + M.ne);
  for (int v = 0; v < M.nv; ++v) {
    if (X(v, 0) <= clamp + 1e-12)
      M.K.coeffRef(v, v) += big;
    else
      f[v] = -mass[v] * g;
  }
  if (clamp_slopes)
    for (const auto& [key, e] : M.edge_of)
      if (X(key.first, 0) <= clamp + 1e-12 && X(key.second, 0) <= clamp + 1e-12)
        M.K.coeffRef(M.nv + e, M.nv + e) += big;
  const Eigen::VectorXd w = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(M.K).solve(f);
  const double tip_x = X.col(0).maxCoeff();
  double drop = 0;
  int count = 0;
  for (int v = 0; v < M.nv; ++v)
    if (X(v, 0) > tip_x - 1e-9) drop -= w[v], ++count;
  return drop / (count * L) / (G / 8);
}

/// Energy of z = kappa/2 (d . p)^2 (a cylinder bent along d at `angle` to material x, small
/// slopes) minimised over the edge slopes, over the plate's D/2 kappa^2 A.
double morley_cylinder(const rm::SheetMesh& mesh, double angle, bool extrapolate) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Morley M = morley_system(mesh, extrapolate);
  const double kappa = 20;
  const Eigen::Vector2d d(std::cos(angle), std::sin(angle));
  Eigen::VectorXd z(M.nv);
  for (int v = 0; v < M.nv; ++v) z[v] = 0.5 * kappa * std::pow(d.dot(Eigen::Vector2d(X.row(v))), 2);
  const Eigen::SparseMatrix<double> Kpp = M.K.block(M.nv, M.nv, M.ne, M.ne);
  const Eigen::SparseMatrix<double> Kpz = M.K.block(M.nv, 0, M.ne, M.nv);
  const Eigen::SparseMatrix<double> Kzz = M.K.block(0, 0, M.nv, M.nv);
  const Eigen::VectorXd phi =
      -Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(Kpp).solve(Kpz * z);
  const double E = 0.5 * z.dot(Kzz * z) + z.dot(Kpz.transpose() * phi) + 0.5 * phi.dot(Kpp * phi);
  return E / (0.5 * ps::Material{}.bending_stiffness * kappa * kappa * M.area);
}

void morley_report(const char* label, const rm::SheetMesh& mesh, double clamp) {
  std::printf(
      "%-28s Morley sag / (G/8): free edges %.4f (slopes clamped %.4f), extrapolated edges "
      "%.4f (slopes clamped %.4f)\n",
      label, morley_sag(mesh, clamp, false, false), morley_sag(mesh, clamp, false, true),
      morley_sag(mesh, clamp, true, false), morley_sag(mesh, clamp, true, true));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "papersim_bending_probe: the discrete bending energies against the elastica strips of "
      "papersim_known_answers, and the linear Morley plate (docs/elastica_30deg_diagnosis.md)"};
  ProbeOptions& o = options;
  app.add_option("--edge", o.edge, "edge length of the strips [m]")->check(CLI::Range(5e-4, 0.02));
  app.add_option("--width", o.width, "width of the strips [m]")->check(CLI::Range(2e-3, 0.2));
  app.add_option("--angle", o.angle, "angle of the rotated lattice [deg]")
      ->check(CLI::Range(0.0, 90.0));
  app.add_flag("--bins", o.bins, "print the energy and K_xx in bins along the strip");
  app.add_flag("--sag-only", o.sag_only,
               "the sags alone, without the energies of prescribed shapes");
  app.add_flag("--mode-shape", o.mode_shape, "print the first mode's displacements");
  app.add_flag("--cylinder", o.cylinder,
               "the Morley plate's energy of a small-slope cylinder on a 15 cm wide sheet");
  auto* modes = app.add_flag("--modes", o.modes,
                             "only: zero modes and twist of the Morley plate on a 12 x 4 cm sheet");
  auto* fold =
      app.add_option("--fold", o.fold,
                     "only: a 180-degree fold of this radius [m] under both bending models")
          ->check(CLI::Range(1e-3, 0.05));
  modes->excludes(fold);
  CLI11_PARSE(app, argc, argv);
  if (o.edge > o.width / 2) {
    std::fprintf(
        stderr, "papersim_bending_probe: --edge %g leaves fewer than two faces across --width %g\n",
        o.edge, o.width);
    return 2;
  }
  // The linear sag solves a dense eigenproblem in the strip's free vertices: bound their count.
  const double strip_vertices = ((L + 2 * o.edge) / o.edge + 1) * (o.width / o.edge + 1);
  if (strip_vertices > 3000) {
    std::fprintf(stderr,
                 "papersim_bending_probe: --edge %g on --width %g makes about %.0f vertices, more "
                 "than the 3000 "
                 "the dense eigenproblem is made for\n",
                 o.edge, o.width, strip_vertices);
    return 2;
  }
  if (o.fold > 0) {
    // A 180-degree fold of radius r (isometric) on a 12 x 4 cm sheet at 8 mm, its start x0 swept
    // over two edge lengths: bending energy of both models over the continuum pi D w / r.
    rm::RectangleOptions o;
    o.width = 0.12;
    o.height = 0.04;
    o.nx = 16;
    o.ny = 6;
    const rm::SheetMesh mesh = rm::make_rectangle(o);
    const Eigen::MatrixX2d X = mesh.material_coords();
    const double r = options.fold;
    for (ps::BendingModel model : {ps::BendingModel::fit, ps::BendingModel::morley}) {
      ps::Material m;
      m.bending_model = model;
      const auto e = ps::make_bending_energy(mesh, m);
      const double ec = M_PI * m.bending_stiffness * o.height / r;
      std::printf("%s fold r = %g mm, E/Ec over x0:",
                  model == ps::BendingModel::fit ? "fit   " : "morley", 1e3 * r);
      for (double x0 = 0.04; x0 <= 0.056 + 1e-9; x0 += 0.002) {
        Eigen::VectorXd x(3 * X.rows());
        for (int v = 0; v < X.rows(); ++v) {
          const double s = X(v, 0), len = M_PI * r;
          double px, pz;
          if (s <= x0)
            px = s, pz = 0;
          else if (s <= x0 + len)
            px = x0 + r * std::sin((s - x0) / r), pz = r * (1 - std::cos((s - x0) / r));
          else
            px = x0 - (s - x0 - len), pz = 2 * r;
          x.segment<3>(3 * v) << px, X(v, 1), pz;
        }
        std::printf(" %.3f", e->value(x) / ec);
      }
      std::printf("\n");
    }
    return 0;
  }
  if (o.modes) {
    // smallest eigenvalues of the condensed Morley stiffness on a free sheet
    rm::RectangleOptions o;
    o.width = 0.12;
    o.height = 0.04;
    o.nx = 16;
    o.ny = 6;
    o.triangulation = rm::Triangulation::alternating;
    const rm::SheetMesh mesh = rm::make_rectangle(o);
    for (bool ex : {false, true}) {
      Morley M = morley_system(mesh, ex);
      {
        // twist z = tau x y: energy over the plate's D tau^2 A (nu = 0)
        const Eigen::MatrixX2d X = mesh.material_coords();
        Eigen::VectorXd z(M.nv);
        const double tau = 10;
        for (int v = 0; v < M.nv; ++v) z[v] = tau * X(v, 0) * X(v, 1);
        const Eigen::SparseMatrix<double> Kpp = M.K.block(M.nv, M.nv, M.ne, M.ne),
                                          Kpz = M.K.block(M.nv, 0, M.ne, M.nv),
                                          Kzz = M.K.block(0, 0, M.nv, M.nv);
        const Eigen::VectorXd phi =
            -Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(Kpp).solve(Kpz * z);
        const double E =
            0.5 * z.dot(Kzz * z) + z.dot(Kpz.transpose() * phi) + 0.5 * phi.dot(Kpp * phi);
        std::printf("extrapolate %d twist E/Ec %.4f\n", ex,
                    E / (ps::Material{}.bending_stiffness * tau * tau * M.area));
      }
      const Eigen::MatrixXd K(M.K);
      const int n = M.nv, m = M.ne;
      const Eigen::MatrixXd S =
          K.topLeftCorner(n, n) -
          K.topRightCorner(n, m) * K.bottomRightCorner(m, m).ldlt().solve(K.bottomLeftCorner(m, n));
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
      std::printf("extrapolate %d eigenvalues:", ex);
      for (int k = 0; k < 8; ++k) std::printf(" %.3g", es.eigenvalues()[k]);
      std::printf("\n");
    }
    return 0;
  }
  const double h = o.edge;
  const double width = o.width;
  const double c = 2 * h;
  for (bool rotated : {false, true}) {
    const rm::SheetMesh mesh = strip(rotated, h, width);
    linear_sag(rotated ? "rot  linear sag" : "grid linear sag", mesh, c, width);
    morley_report(rotated ? "rot  Morley" : "grid Morley", mesh, c);
    if (o.cylinder) {
      // A sheet of width x 15 cm, every mesh: cylinder energies at 0, 30, 45, 90 degrees.
      rm::SheetMesh sheet = rotated ? strip(true, h, 0.15) : strip(false, h, 0.15);
      for (bool ex : {false, true}) {
        std::printf("%s Morley cylinder E/Ec (%s edges):", rotated ? "rot " : "grid",
                    ex ? "extrapolated" : "free");
        for (double a : {0.0, 30.0, 45.0, 90.0})
          std::printf(" %g deg %.4f", a, morley_cylinder(sheet, a * M_PI / 180, ex));
        std::printf("\n");
      }
    }
    if (o.sag_only) continue;
    const std::string tag = rotated ? "rot " : "grid";
    const double k0 = 5.0;  // [1/m]
    probe((tag + " constant").c_str(), mesh, c, width, [&](double) { return k0; });
    probe((tag + " linear (no clamp)").c_str(), mesh, c, width,
          [&](double xx) { return k0 * (1 - xx / (L + c)); });
    probe((tag + " quadratic (no clamp)").c_str(), mesh, c, width, [&](double xx) {
      const double t = 1 - xx / (L + c);
      return k0 * t * t;
    });
    probe((tag + " constant after clamp").c_str(), mesh, c, width,
          [&](double xx) { return xx < c ? 0.0 : k0; });
    for (double G : {1.0, 8.0, 20.0}) {
      const int n = 4000;
      double drop = 0;
      const std::vector<double> kap = elastica_kappa(G, n, &drop);
      auto kx = [&, c](double xx) {
        if (xx < c) return 0.0;
        const double s = std::min(1.0, (xx - c) / L) * n;
        const int i = std::min(n - 1, static_cast<int>(s));
        return (kap[i] + (s - i) * (kap[i + 1] - kap[i])) / L;
      };
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s elastica G=%g", tag.c_str(), G);
      probe(buf, mesh, c, width, kx);
    }
  }
}
