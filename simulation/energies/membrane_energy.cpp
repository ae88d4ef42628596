#include "simulation/energies/membrane_energy.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "collision/barrier.hpp"
#include "simulation/energies/bending_energy.hpp"
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
  bool active = false;  // limit_barrier: a limit is near (else all zero)
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
CFunction limit_barrier(const Vec3& c, double L, double dhat, double Lc, double dhat_c,
                        double kappa) {
  CFunction r;
  // Most faces are far from both limits: decide that from the eigenvalues in closed form,
  // mean -+ radius, before any eigenvector is computed.
  const double mean = 0.5 * (c[0] + c[1]), half = 0.5 * (c[0] - c[1]);
  const double radius = std::sqrt(half * half + c[2] * c[2]);
  if (!(L > 0 && mean + radius >= L - dhat) && !(Lc > 0 && mean - radius <= Lc + dhat_c)) return r;
  Eigen::Matrix2d C;
  C << c[0], c[2], c[2], c[1];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  const Eigen::Vector2d lam = es.eigenvalues();
  const bool upper = L > 0 && lam[1] >= L - dhat, lower = Lc > 0 && lam[0] <= Lc + dhat_c;
  if (!upper && !lower) return r;  // inactive: both eigenvalues far from the limits
  r.active = true;
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

/// StVK plus the limits at C (Voigt); value infinite past a limit.
CFunction energy_density(const Vec3& c, double lambda, double mu, double L, double dhat, double Lc,
                         double dhat_c, double kappa) {
  CFunction W = stvk(c, lambda, mu);
  if (L > 0 || Lc > 0) {
    const CFunction B = limit_barrier(c, L, dhat, Lc, dhat_c, kappa);
    if (!std::isfinite(B.value)) {
      W.value = INF;
      return W;
    }
    W.value += B.value;
    W.grad += B.grad;
    W.hess += B.hess;
  }
  return W;
}

/// dc/dx of a triangle (rows: c0, c1, c2 in Voigt; columns: its three corners).
Eigen::Matrix<double, 3, 9> c_jacobian(const Eigen::Matrix<double, 3, 2>& F,
                                       const Eigen::Matrix<double, 3, 2>& w) {
  Eigen::Matrix<double, 3, 9> J;
  for (int j = 0; j < 3; ++j) {
    const double w0 = w(j, 0), w1 = w(j, 1);
    J.block<1, 3>(0, 3 * j) = 2 * w0 * F.col(0).transpose();
    J.block<1, 3>(1, 3 * j) = 2 * w1 * F.col(1).transpose();
    J.block<1, 3>(2, 3 * j) = (w0 * F.col(1) + w1 * F.col(0)).transpose();
  }
  return J;
}

/// The arc model's fade-out: psi = 1 / (1 + (s / S_C)^4) [rad].
constexpr double S_C = 0.5;

}  // namespace

MembraneEnergy::MembraneEnergy(const remesh::SheetMesh& mesh, const Material& m)
    : MembraneEnergy(mesh.material_coords(), mesh.faces(), m) {
  if (m.membrane_model == MembraneModel::arc) build_arcs(mesh);
}

void MembraneEnergy::build_arcs(const remesh::SheetMesh& mesh) {
  const Eigen::MatrixX3i F = mesh.faces();
  const Eigen::MatrixX2d X = mesh.material_coords();
  m_hinges = remesh::interior_hinges(mesh);
  const Eigen::MatrixX3i fh = remesh::face_hinges(mesh, m_hinges);
  const CurvatureStencils stencils(m_hinges, fh, F, X);
  // Each face's curvature fit: its own hinges (three on an interior face: exact for every
  // constant curvature), then its edge neighbours' and rings of faces while not determined
  // (boundary faces).
  m_fits.resize(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    CurvatureFit& fit = m_fits[f];
    stencils.add_face_hinges(fit.hinges, f);
    if (!stencils.determined(fit.hinges)) stencils.add_neighbour_hinges(fit.hinges);
    if (!stencils.grow_until_determined(
            fit.hinges, f)) {  // too few interior edges (a mesh of one or two faces)
      fit.hinges.clear();
      fit.P.setZero(3, 0);
      continue;
    }
    const Eigen::MatrixXd B = stencils.rows(fit.hinges);
    fit.P = (B.transpose() * B).ldlt().solve(B.transpose());
  }
  // Each face's element: its edges' curvatures from the face and its edge neighbours.
  m_arcs.resize(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    Arc& a = m_arcs[f];
    a.faces.push_back(f);
    for (int j = 0; j < 3; ++j)
      if (fh(f, j) >= 0) {
        const int h = fh(f, j);
        a.faces.push_back(m_hinges.faces(h, 0) == f ? m_hinges.faces(h, 1) : m_hinges.faces(h, 0));
      }
    a.weight.setZero(3, a.faces.size());
    Eigen::Matrix3d Aedge;  // row j: (ex^2, ey^2, 2 ex ey), so e_j^T C e_j = row . c
    for (int j = 0, next = 1; j < 3; ++j) {
      const Eigen::Vector2d e = X.row(F(f, (j + 2) % 3)) - X.row(F(f, (j + 1) % 3));
      a.length[j] = e.norm();
      const Eigen::Vector2d t = e / a.length[j];
      Aedge.row(j) << e.x() * e.x(), e.y() * e.y(), 2 * e.x() * e.y();
      a.Q.row(j) << t.x() * t.x(), t.y() * t.y(), 2 * t.x() * t.y();
      if (fh(f, j) >= 0) {
        a.weight(j, 0) = 0.5;
        a.weight(j, next) = 0.5;
        a.size[j] = std::sqrt(m_tris[f].area + m_tris[a.faces[next]].area);
        ++next;
      } else {
        a.weight(j, 0) = 1;
        a.size[j] = std::sqrt(2 * m_tris[f].area);
      }
    }
    a.G = Aedge.inverse();
    for (int k = 0; k < 3; ++k) a.vertices.push_back(F(f, k));
    for (int g : a.faces)
      for (int h : m_fits[g].hinges)
        if (std::find(a.hinges.begin(), a.hinges.end(), h) == a.hinges.end()) a.hinges.push_back(h);
    for (int h : a.hinges) a.local.push_back(local_hinge(m_hinges, h, a.vertices));
    for (int g : a.faces)
      for (int h : m_fits[g].hinges)
        a.fit_local.push_back(
            static_cast<int>(std::find(a.hinges.begin(), a.hinges.end(), h) - a.hinges.begin()));
  }
}

Eigen::Matrix3Xd MembraneEnergy::face_curvatures(const Eigen::VectorXd& theta) const {
  Eigen::Matrix3Xd K = Eigen::Matrix3Xd::Zero(3, m_fits.size());
  for (size_t f = 0; f < m_fits.size(); ++f) {
    const CurvatureFit& fit = m_fits[f];
    for (size_t k = 0; k < fit.hinges.size(); ++k) K.col(f) += fit.P.col(k) * theta[fit.hinges[k]];
  }
  return K;
}

MembraneEnergy::Delta MembraneEnergy::arc_delta(double L, double size,
                                                const Eigen::RowVector3d& qrow,
                                                const Eigen::Vector3d& K, bool derivatives) {
  // delta = psi(q) u with u = L^4 k^2 / 12, k = qrow K, and psi = 1 / (1 + c q^2),
  // q = h^2 K^T M K = s^2 (M = diag(1, 1, 2): |K|^2 in Voigt), c = 1 / S_C^4: smooth in K.
  const Eigen::Vector3d M(1, 1, 2);
  const double c = 1 / std::pow(S_C, 4), L2 = size * size, L4 = L * L * L * L;
  const double q = L2 * K.dot(M.cwiseProduct(K));
  const double den = 1 + c * q * q;
  const double psi = 1 / den;
  const double k = qrow.dot(K);
  const double u = L4 * k * k / 12;
  Delta d;
  d.value = psi * u;
  if (!derivatives) return d;
  const double psi_q = -2 * c * q / (den * den);
  const double psi_qq = -2 * c / (den * den) + 8 * c * c * q * q / (den * den * den);
  const Eigen::Vector3d dq = 2 * L2 * M.cwiseProduct(K);
  const Eigen::Matrix3d ddq = 2 * L2 * M.asDiagonal();
  const Eigen::Vector3d du = L4 * k / 6 * qrow.transpose();
  const Eigen::Matrix3d ddu = L4 / 6 * qrow.transpose() * qrow;
  d.gradient = psi * du + u * psi_q * dq;
  d.hessian = psi * ddu + psi_q * (du * dq.transpose() + dq * du.transpose()) +
              u * (psi_qq * dq * dq.transpose() + psi_q * ddq);
  return d;
}

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
  if (arc()) {
    for (const auto& a : m_arcs)
      pattern.add_clique(a.vertices.data(), static_cast<int>(a.vertices.size()));
    return;
  }
  for (const auto& t : m_tris) pattern.add_clique(t.v.data(), 3);
}

double MembraneEnergy::element(int f, const Eigen::Matrix<double, 9, 1>& xs,
                               Eigen::Matrix<double, 9, 1>* g, Eigen::Matrix<double, 9, 9>* H,
                               bool project) const {
  const Triangle& t = m_tris[f];
  Eigen::Matrix<double, 3, 2> F = Eigen::Matrix<double, 3, 2>::Zero();
  for (int i = 0; i < 3; ++i) F += xs.segment<3>(3 * i) * t.w.row(i);
  const Vec3 c(F.col(0).squaredNorm(), F.col(1).squaredNorm(), F.col(0).dot(F.col(1)));
  const CFunction W =
      energy_density(c, m_lambda, m_mu, m_limit, m_dhat, m_limit_low, m_dhat_low, m_kappa);
  if (!std::isfinite(W.value)) return INF;
  if (!g && !H) return t.area * W.value;
  // dc/dx_j: c0 -> 2 w_j0 F0, c1 -> 2 w_j1 F1, c2 -> w_j0 F1 + w_j1 F0.
  const Eigen::Matrix<double, 3, 9> J = c_jacobian(F, t.w);
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
    if (project && (G.determinant() < 0 || G.trace() < 0)) *H = project_psd(*H);
  }
  return t.area * W.value;
}

void MembraneEnergy::arc_deltas(int f, const Eigen::Matrix3Xd& K, bool derivatives,
                                Delta d[3]) const {
  const Arc& a = m_arcs[f];
  for (int j = 0; j < 3; ++j) {
    Eigen::Vector3d Ke = Eigen::Vector3d::Zero();  // the edge's curvature, from its faces'
    for (size_t i = 0; i < a.faces.size(); ++i) Ke += a.weight(j, i) * K.col(a.faces[i]);
    d[j] = arc_delta(a.length[j], a.size[j], a.Q.row(j), Ke, derivatives);
  }
}

double MembraneEnergy::arc_element(int f, const Eigen::VectorXd& x, const Eigen::Matrix3Xd& Kf,
                                   const std::vector<Eigen::Matrix<double, 12, 1>>* grads,
                                   const std::vector<Eigen::Matrix<double, 12, 12>>* hesses,
                                   ArcWork* work, bool hessian, bool project) const {
  const Triangle& t = m_tris[f];
  const Arc& a = m_arcs[f];
  Eigen::Matrix<double, 3, 2> F = Eigen::Matrix<double, 3, 2>::Zero();
  for (int i = 0; i < 3; ++i) F += x.segment<3>(3 * t.v[i]) * t.w.row(i);
  const Vec3 c(F.col(0).squaredNorm(), F.col(1).squaredNorm(), F.col(0).dot(F.col(1)));
  const int nf = static_cast<int>(a.faces.size());
  const bool derivatives = work != nullptr;
  Delta d[3];
  arc_deltas(f, Kf, derivatives, d);
  const Eigen::Vector3d delta(d[0].value, d[1].value, d[2].value);
  // Stretching at the arcs' C', the limits at the chords' C.
  const CFunction W = stvk(c + a.G * delta, m_lambda, m_mu);
  CFunction B;
  if (m_limit > 0 || m_limit_low > 0) {
    B = limit_barrier(c, m_limit, m_dhat, m_limit_low, m_dhat_low, m_kappa);
    if (!std::isfinite(B.value)) return INF;
  }
  const double value = t.area * (W.value + B.value);
  if (!derivatives) return value;
  ArcWork& s = *work;
  const int n = 3 * static_cast<int>(a.vertices.size());
  // Rows 3 + 3j of M: dK_e/dx of edge j over the local vertices, the weighted sum of its faces'
  // dK/dx; d delta_e / dx from them.
  s.M.setZero(12, n);
  for (int i = 0, p = 0; i < nf; ++i) {
    const CurvatureFit& fit = m_fits[a.faces[i]];
    for (size_t k = 0; k < fit.hinges.size(); ++k) {
      const auto& loc = a.local[a.fit_local[p++]];
      const Eigen::Matrix<double, 12, 1>& gh = (*grads)[fit.hinges[k]];
      for (int j = 0; j < 3; ++j) {
        if (a.weight(j, i) == 0) continue;
        const Eigen::Vector3d wP = a.weight(j, i) * fit.P.col(k);
        for (int q = 0; q < 4; ++q)
          s.M.block<3, 3>(3 + 3 * j, 3 * loc[q]).noalias() += wP * gh.segment<3>(3 * q).transpose();
      }
    }
  }
  s.Dd.resize(3, n);
  for (int j = 0; j < 3; ++j)
    s.Dd.row(j).noalias() = d[j].gradient.transpose() * s.M.middleRows<3>(3 + 3 * j);
  const Eigen::Matrix<double, 3, 9> Jc = c_jacobian(F, t.w);
  // Rows 0-2: dc'/dx = dc/dx (the corners, local 0-2) + G d delta / dx.
  s.M.topRows<3>().noalias() = a.G * s.Dd;
  s.M.topLeftCorner<3, 9>() += Jc;
  s.g.noalias() = t.area * s.M.topRows<3>().transpose() * W.grad;
  s.g.head<9>() += t.area * Jc.transpose() * B.grad;
  if (!hessian) return value;
  // H = M^T D M with D = diag(A d2W/dc'2, the arcs' geometric terms through each K_e:
  // A dW/d delta_e d2 delta_e / dK_e2, projected when projecting). Projected, D is PSD (St.
  // Venant-Kirchhoff's d2W/dc'2 is): with D = L L^T block by block, H = (L^T M)^T (L^T M).
  // D is block diagonal, so D M (or L^T M) is four 3 x n products; H's lower 3 x 3 blocks are
  // products of 12 x 3 column blocks, then mirrored. Fixed sizes the compiler unrolls: Eigen's
  // general kernels spent their time packing these small operands (docs/performance.md, "The
  // arc membrane's assembly").
  const Vec3 beta = a.G.transpose() * W.grad;
  s.D.setZero();
  if (project) {
    s.D.topLeftCorner<3, 3>() = (t.area * W.hess).llt().matrixL();
    for (int j = 0; j < 3; ++j) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(t.area * beta[j] * d[j].hessian);
      s.D.block<3, 3>(3 + 3 * j, 3 + 3 * j) =
          es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
    }
  } else {
    s.D.topLeftCorner<3, 3>() = t.area * W.hess;
    for (int j = 0; j < 3; ++j)
      s.D.block<3, 3>(3 + 3 * j, 3 + 3 * j) = t.area * beta[j] * d[j].hessian;
  }
  s.DM.resize(12, n);
  for (int j = 0; j < 4; ++j) {
    const Eigen::Matrix3d Dj = project ? Eigen::Matrix3d(s.D.block<3, 3>(3 * j, 3 * j).transpose())
                                       : Eigen::Matrix3d(s.D.block<3, 3>(3 * j, 3 * j));
    s.DM.middleRows<3>(3 * j).noalias() = Dj.lazyProduct(s.M.middleRows<3>(3 * j));
  }
  // Projected: H = (L^T M)^T (L^T M); exact: H = M^T (D M). Lower blocks, then mirrored.
  const double* left = project ? s.DM.data() : s.M.data();
  s.H.resize(n, n);
  for (int b = 0; b < n / 3; ++b) {
    const Eigen::Map<const Eigen::Matrix<double, 12, 3>> right(s.DM.data() + 36 * b);
    for (int q = b; q < n / 3; ++q)
      s.H.block<3, 3>(3 * q, 3 * b).noalias() =
          Eigen::Map<const Eigen::Matrix<double, 12, 3>>(left + 36 * q)
              .transpose()
              .lazyProduct(right);
  }
  for (int b = 0; b < n / 3; ++b) {  // the upper triangle from the lower, block by block
    for (int q = b + 1; q < n / 3; ++q)
      s.H.block<3, 3>(3 * b, 3 * q) = s.H.block<3, 3>(3 * q, 3 * b).transpose();
    s.H(3 * b, 3 * b + 1) = s.H(3 * b + 1, 3 * b);
    s.H(3 * b, 3 * b + 2) = s.H(3 * b + 2, 3 * b);
    s.H(3 * b + 1, 3 * b + 2) = s.H(3 * b + 2, 3 * b + 1);
  }
  // The limits' Hessian (where a limit is near) and the chords' geometric term (dW/dC' + dB/dC
  // as a tensor), on the corners.
  if (B.active) s.H.topLeftCorner<9, 9>().noalias() += t.area * Jc.transpose() * B.hess * Jc;
  const Vec3 sc = W.grad + B.grad;
  Eigen::Matrix2d S;
  S << sc[0], 0.5 * sc[2], 0.5 * sc[2], sc[1];
  // The geometric term is Sg (x) I3 with Sg_ij = 2 A w_i^T S w_j, so its projection is that of
  // the 3 x 3 Sg, (x) I3.
  Eigen::Matrix3d Sg;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Sg(i, j) = 2 * t.area * t.w.row(i).dot(S * t.w.row(j).transpose());
  if (project && (S.determinant() < 0 || S.trace() < 0)) Sg = project_psd(Sg);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s.H.block<3, 3>(3 * i, 3 * j).diagonal().array() += Sg(i, j);
  if (!hesses) return value;
  // The exact Hessian: dW/d delta_e d delta_e / dK_e times the hinges' Hessians, each hinge's
  // coefficients summed over the edges and faces that use it, its Hessian added once.
  s.coefficient.setZero(static_cast<int>(a.hinges.size()));
  for (int j = 0; j < 3; ++j) {
    for (int i = 0, p = 0; i < nf; ++i) {
      const CurvatureFit& fit = m_fits[a.faces[i]];
      if (a.weight(j, i) == 0) {
        p += static_cast<int>(fit.hinges.size());
        continue;
      }
      const double scale = t.area * beta[j] * a.weight(j, i);
      for (size_t k = 0; k < fit.hinges.size(); ++k)
        s.coefficient[a.fit_local[p++]] += scale * fit.P.col(k).dot(d[j].gradient);
    }
  }
  for (size_t l = 0; l < a.hinges.size(); ++l) {
    const double w = s.coefficient[static_cast<int>(l)];
    if (w == 0) continue;
    const auto& loc = a.local[l];
    const Eigen::Matrix<double, 12, 12>& Hh = (*hesses)[a.hinges[l]];
    for (int q = 0; q < 4; ++q)
      for (int r = 0; r < 4; ++r)
        s.H.block<3, 3>(3 * loc[q], 3 * loc[r]) += w * Hh.block<3, 3>(3 * q, 3 * r);
  }
  return value;
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
  if (arc()) {
    const Eigen::Matrix3Xd K = face_curvatures(hinge_angles_at(m_hinges, x));
    for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
      e += arc_element(f, x, K, nullptr, nullptr, nullptr, false, false);
      if (!std::isfinite(e)) return INF;
    }
    return e;
  }
  for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
    e += element(f, gather(x, m_tris[f].v), nullptr, nullptr, false);
    if (!std::isfinite(e)) return INF;
  }
  return e;
}

void MembraneEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                                     BlockSymmetricMatrix* hessian,
                                     HessianProjection projection) const {
  const bool project = projection == HessianProjection::psd;
  if (arc()) {
    const bool exact = hessian && !project;
    const HingeDerivatives hd = hinge_derivatives(m_hinges, x, exact);
    const Eigen::Matrix3Xd K = face_curvatures(hd.theta);
    ArcWork work;
    if (hessian && m_slots.stale(*hessian)) {
      m_slots.reset(*hessian);
      for (const Arc& a : m_arcs)
        m_slots.add(*hessian, a.vertices.data(), static_cast<int>(a.vertices.size()));
    }
    for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
      const Arc& a = m_arcs[f];
      if (!std::isfinite(arc_element(f, x, K, &hd.gradients, exact ? &hd.hessians : nullptr, &work,
                                     hessian != nullptr, project)))
        throw NumericError("membrane: derivatives requested past the strain limit");
      for (size_t i = 0; i < a.vertices.size(); ++i)
        gradient.segment<3>(3 * a.vertices[i]) += work.g.segment<3>(3 * i);
      if (hessian)
        hessian->add_element(a.vertices.data(), static_cast<int>(a.vertices.size()),
                             m_slots.slots(f), work.H.data());
    }
    return;
  }
  Eigen::Matrix<double, 9, 1> g;
  Eigen::Matrix<double, 9, 9> H;
  if (hessian && m_slots.stale(*hessian)) {
    m_slots.reset(*hessian);
    for (const auto& t : m_tris) m_slots.add(*hessian, t.v.data(), 3);
  }
  for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
    const auto& t = m_tris[f];
    if (!std::isfinite(element(f, gather(x, t.v), &g, hessian ? &H : nullptr, project)))
      throw NumericError("membrane: derivatives requested past the strain limit");
    for (int i = 0; i < 3; ++i) gradient.segment<3>(3 * t.v[i]) += g.segment<3>(3 * i);
    if (hessian) hessian->add_element(t.v.data(), 3, m_slots.slots(f), H.data());
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

Eigen::MatrixX3d MembraneEnergy::green_strains(const Eigen::VectorXd& x) const {
  Eigen::Matrix3Xd K;
  if (arc()) K = face_curvatures(hinge_angles_at(m_hinges, x));
  Eigen::MatrixX3d e(m_tris.size(), 3);
  for (int f = 0; f < static_cast<int>(m_tris.size()); ++f) {
    const auto& t = m_tris[f];
    Eigen::Matrix<double, 3, 2> F = Eigen::Matrix<double, 3, 2>::Zero();
    for (int i = 0; i < 3; ++i) F += x.segment<3>(3 * t.v[i]) * t.w.row(i);
    Eigen::Vector3d c(F.col(0).squaredNorm(), F.col(1).squaredNorm(), F.col(0).dot(F.col(1)));
    if (arc()) {
      Delta d[3];
      arc_deltas(f, K, false, d);
      c += m_arcs[f].G * Eigen::Vector3d(d[0].value, d[1].value, d[2].value);
    }
    e.row(f) << 0.5 * (c[0] - 1), 0.5 * (c[1] - 1), 0.5 * c[2];
  }
  return e;
}

Eigen::MatrixX3d MembraneEnergy::vertex_curvatures(const Eigen::VectorXd& x) const {
  if (!arc()) return Eigen::MatrixX3d(0, 3);
  const Eigen::Matrix3Xd K = face_curvatures(hinge_angles_at(m_hinges, x));
  const Eigen::Index nv = x.size() / 3;
  Eigen::MatrixX3d sum = Eigen::MatrixX3d::Zero(nv, 3);
  Eigen::VectorXd area = Eigen::VectorXd::Zero(nv);
  for (int f = 0; f < static_cast<int>(m_tris.size()); ++f)
    for (int v : m_tris[f].v) {
      sum.row(v) += m_tris[f].area * K.col(f).transpose();
      area[v] += m_tris[f].area;
    }
  for (Eigen::Index v = 0; v < nv; ++v)
    if (area[v] > 0) sum.row(v) /= area[v];
  return sum;
}

}  // namespace papersim::simulation
