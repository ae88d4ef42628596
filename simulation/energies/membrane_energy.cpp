#include "simulation/energies/membrane_energy.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <Eigen/Cholesky>
#include <cmath>

#include "collision/barrier.hpp"
#include "simulation/energies/psd.hpp"
#include "simulation/errors.hpp"

namespace papersim::simulation {

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// Scalar function of C in Voigt form c = (C00, C11, C01): value, dW/dc, d2W/dc2.
struct CFunction {
  double value = 0;
  Vec3 grad = Vec3::Zero();
  Mat3 hess = Mat3::Zero();
};

/// St. Venant-Kirchhoff in plane stress: W = lambda/2 tr(E)^2 + mu tr(E^2), E = (C - I)/2.
CFunction stvk(const Vec3& c, double lambda, double mu) {
  const double e0 = 0.5 * (c[0] - 1), e1 = 0.5 * (c[1] - 1), e2 = 0.5 * c[2];
  const double tr = e0 + e1;
  CFunction r;
  r.value = 0.5 * lambda * tr * tr + mu * (e0 * e0 + e1 * e1 + 2 * e2 * e2);
  // dW/dE00 = lambda tr + 2 mu e0, dE00/dc0 = 1/2; W depends on c2 via 2 mu e2^2 with e2 = c2/2,
  // so dW/dc2 = 2 mu e2 = mu c2.
  r.grad << 0.5 * (lambda * tr + 2 * mu * e0), 0.5 * (lambda * tr + 2 * mu * e1), 2 * mu * e2;
  r.hess << 0.25 * (lambda + 2 * mu), 0.25 * lambda, 0, 0.25 * lambda, 0.25 * (lambda + 2 * mu), 0,
      0, 0, mu;
  return r;
}

/// The strain limits as barriers on the eigenvalues lambda_i of C (squared principal
/// stretches): sum_i kappa b(L - lambda_i, dhat) keeps every lambda_i below L (stretch), and
/// with Lc > 0 sum_i kappa b(lambda_i - Lc, dhat_c) keeps it above Lc (compression). Hessian by
/// the Daleckii-Krein formula for spectral functions.
CFunction limit_barrier(const Vec3& c, double L, double dhat, double Lc, double dhat_c, double kappa) {
  CFunction r;
  Eigen::Matrix2d C;
  C << c[0], c[2], c[2], c[1];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  const Eigen::Vector2d lam = es.eigenvalues();
  const bool upper = L > 0 && lam[1] >= L - dhat, lower = Lc > 0 && lam[0] <= Lc + dhat_c;
  if (!upper && !lower) return r;  // inactive: both eigenvalues far from the limits
  if ((L > 0 && lam[1] >= L) || (Lc > 0 && lam[0] <= Lc)) {
    r.value = INF;
    return r;
  }
  double f1[2] = {0, 0}, f2[2] = {0, 0};  // d/dlambda_i and d2/dlambda_i^2 of the barriers
  Vec3 a[2];
  for (int i = 0; i < 2; ++i) {
    if (upper) {
      const double d = L - lam[i];
      r.value += kappa * collision::barrier(d, dhat);
      f1[i] -= kappa * collision::barrier_first_derivative(d, dhat);
      f2[i] += kappa * collision::barrier_second_derivative(d, dhat);
    }
    if (lower) {
      const double d = lam[i] - Lc;
      r.value += kappa * collision::barrier(d, dhat_c);
      f1[i] += kappa * collision::barrier_first_derivative(d, dhat_c);
      f2[i] += kappa * collision::barrier_second_derivative(d, dhat_c);
    }
    const Eigen::Vector2d v = es.eigenvectors().col(i);
    a[i] << v[0] * v[0], v[1] * v[1], 2 * v[0] * v[1];
    r.grad += f1[i] * a[i];
    r.hess += f2[i] * a[i] * a[i].transpose();
  }
  const Eigen::Vector2d v0 = es.eigenvectors().col(0), v1 = es.eigenvectors().col(1);
  const Vec3 a01(v0[0] * v1[0], v0[1] * v1[1], v0[0] * v1[1] + v0[1] * v1[0]);
  const double gap = lam[1] - lam[0];
  const double divided = gap > 1e-12 ? (f1[1] - f1[0]) / gap : 0.5 * (f2[0] + f2[1]);
  r.hess += 2 * divided * a01 * a01.transpose();
  return r;
}

}  // namespace

MembraneEnergy::MembraneEnergy(const Eigen::MatrixX2d& X, const Eigen::MatrixX3i& F,
                               const Material& m) {
  const double nu = m.poisson;
  // Plane stress: lambda* = E nu / (1 - nu^2), mu = E / (2 (1 + nu)), times thickness.
  m_lambda = m.stretch_stiffness * nu / (1 - nu * nu);
  m_mu = m.stretch_stiffness / (2 * (1 + nu));
  m_limit = m.strain_limit > 0 ? (1 + m.strain_limit) * (1 + m.strain_limit) : 0.0;
  m_dhat = m_limit > 0 ? m_limit - (1 + 0.5 * m.strain_limit) * (1 + 0.5 * m.strain_limit) : 0.0;
  if (m.compression_limit > 0) {
    m_limit_low = (1 - m.compression_limit) * (1 - m.compression_limit);
    m_dhat_low = (1 - 0.5 * m.compression_limit) * (1 - 0.5 * m.compression_limit) - m_limit_low;
  }
  m_kappa = m.stretch_stiffness;
  m_tris.reserve(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    Triangle t;
    t.v = {F(f, 0), F(f, 1), F(f, 2)};
    Eigen::Matrix2d Dm;
    Dm.col(0) = X.row(F(f, 1)) - X.row(F(f, 0));
    Dm.col(1) = X.row(F(f, 2)) - X.row(F(f, 0));
    t.area = 0.5 * std::abs(Dm.determinant());
    const Eigen::Matrix2d B = Dm.inverse();
    t.w.row(1) = B.row(0);
    t.w.row(2) = B.row(1);
    t.w.row(0) = -(B.row(0) + B.row(1));
    m_tris.push_back(t);
  }
}

void MembraneEnergy::add_pattern(SparsityBuilder& pattern) const {
  for (const auto& t : m_tris) pattern.add_clique(t.v.data(), 3);
}

double MembraneEnergy::element(int f, const Eigen::Matrix<double, 9, 1>& xs,
                               Eigen::Matrix<double, 9, 1>* g,
                               Eigen::Matrix<double, 9, 9>* H) const {
  const Triangle& t = m_tris[f];
  Eigen::Matrix<double, 3, 2> F = Eigen::Matrix<double, 3, 2>::Zero();
  for (int i = 0; i < 3; ++i) F += xs.segment<3>(3 * i) * t.w.row(i);
  const Vec3 c(F.col(0).squaredNorm(), F.col(1).squaredNorm(), F.col(0).dot(F.col(1)));
  CFunction W = stvk(c, m_lambda, m_mu);
  if (m_limit > 0 || m_limit_low > 0) {
    const CFunction B = limit_barrier(c, m_limit, m_dhat, m_limit_low, m_dhat_low, m_kappa);
    if (!std::isfinite(B.value)) return INF;
    W.value += B.value;
    W.grad += B.grad;
    W.hess += B.hess;
  }
  if (!g && !H) return t.area * W.value;
  // dc/dx_j: c0 -> 2 w_j0 F0, c1 -> 2 w_j1 F1, c2 -> w_j0 F1 + w_j1 F0.
  Eigen::Matrix<double, 3, 9> J;
  for (int j = 0; j < 3; ++j) {
    const double w0 = t.w(j, 0), w1 = t.w(j, 1);
    J.block<1, 3>(0, 3 * j) = 2 * w0 * F.col(0).transpose();
    J.block<1, 3>(1, 3 * j) = 2 * w1 * F.col(1).transpose();
    J.block<1, 3>(2, 3 * j) = (w0 * F.col(1) + w1 * F.col(0)).transpose();
  }
  if (g) *g = t.area * J.transpose() * W.grad;
  if (H) {
    // Geometric term: d2c/dx_i dx_j = 2 (w_i^T G w_j) I3, G = [[g0, g2/2], [g2/2, g1]]. It is
    // indefinite under compression, so the element matrix is projected to PSD (Teran et al.
    // 2005 style, on the 9x9 element matrix as in IPC); when G is PSD the matrix already is.
    Eigen::Matrix2d G;
    G << W.grad[0], 0.5 * W.grad[2], 0.5 * W.grad[2], W.grad[1];
    *H = t.area * J.transpose() * W.hess * J;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double s = 2 * t.area * t.w.row(i).dot(G * t.w.row(j).transpose());
        H->block<3, 3>(3 * i, 3 * j).diagonal().array() += s;
      }
    if (m_project && (G.determinant() < 0 || G.trace() < 0)) *H = project_psd(*H);
  }
  return t.area * W.value;
}

namespace {
Eigen::Matrix<double, 9, 1> gather(const Eigen::VectorXd& x, const std::array<int, 3>& v) {
  Eigen::Matrix<double, 9, 1> xs;
  for (int i = 0; i < 3; ++i) xs.segment<3>(3 * i) = x.segment<3>(3 * v[i]);
  return xs;
}
}  // namespace

double MembraneEnergy::value(const Eigen::VectorXd& x) const {
  double e = 0;
  for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
    e += element(f, gather(x, m_tris[f].v), nullptr, nullptr);
    if (!std::isfinite(e)) return INF;
  }
  return e;
}

void MembraneEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                                     BlockSymmetricMatrix* hessian) const {
  Eigen::Matrix<double, 9, 1> g;
  Eigen::Matrix<double, 9, 9> H;
  for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
    const auto& t = m_tris[f];
    if (!std::isfinite(element(f, gather(x, t.v), &g, hessian ? &H : nullptr)))
      throw NumericError("membrane: derivatives requested past the strain limit");
    for (int i = 0; i < 3; ++i) gradient.segment<3>(3 * t.v[i]) += g.segment<3>(3 * i);
    if (hessian) hessian->add_element<3>(t.v, H);
  }
}

Eigen::MatrixX2d MembraneEnergy::principal_stretches(const Eigen::VectorXd& x) const {
  Eigen::MatrixX2d s(m_tris.size(), 2);
  for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
    const auto& t = m_tris[f];
    Eigen::Matrix<double, 3, 2> F = Eigen::Matrix<double, 3, 2>::Zero();
    for (int i = 0; i < 3; ++i) F += x.segment<3>(3 * t.v[i]) * t.w.row(i);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(F.transpose() * F);
    s.row(f) << std::sqrt(std::max(0.0, es.eigenvalues()[1])),
        std::sqrt(std::max(0.0, es.eigenvalues()[0]));
  }
  return s;
}

}  // namespace papersim::simulation
