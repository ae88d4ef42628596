#include "simulation/energies/dihedral_angle.hpp"

#include <Eigen/Geometry>
#include <cmath>

// Notation used throughout (see the header for the hinge layout and sign convention):
//   e = x1 - x0 (hinge edge), and per wing W in {A, B} with apex q = xa or xb:
//   u = q - x0,  N = e x u  (|N| = 2 area = |e| h, h the height of q over the edge),
//   v = |e| N / |N|^2 = (N / |N|) / h,   alpha = (u . e) / |e|^2 (foot of the height on e).
// Face A's unit normal is n_a = N_A / |N_A|; face B is wound the other way round the edge, so
// n_b = -N_B / |N_B| (N_B built with the same e = x1 - x0).

namespace papersim::simulation {
namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

// Slots of the stacked 12-vector: x0, x1, xa, xb.
constexpr int X0 = 0;
constexpr int X1 = 3;
constexpr int XA = 6;
constexpr int XB = 9;

/// [a]x, the matrix with [a]x y = a x y.
Mat3 cross_matrix(const Vec3& a) {
  Mat3 m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

/// Per-wing quantities shared by value, gradient and Hessian.
struct Wing {
  Vec3 u;             // apex - x0 [m]
  Vec3 normal;        // N = e x u, unnormalised [m^2]
  double inv_nn = 0;  // 1 / |N|^2 [1/m^4]
  Vec3 v;             // |e| N / |N|^2 = n / h [1/m]
  double alpha = 0;   // (u . e) / |e|^2 [-]
};

Wing make_wing(const Vec3& e, double len_e, double inv_ee, const Vec3& x0, const Vec3& apex) {
  Wing w;
  w.u = apex - x0;
  w.normal = e.cross(w.u);
  w.inv_nn = 1.0 / w.normal.squaredNorm();
  w.v = (len_e * w.inv_nn) * w.normal;
  w.alpha = w.u.dot(e) * inv_ee;
  return w;
}

/// theta = atan2((n_b x n_a) . e_hat, n_a . n_b) written with the unnormalised normals
/// (N_A, -N_B) and e: both atan2 arguments are scaled by the same positive |e| |N_A| |N_B|.
/// The cross/dot pair keeps full precision near 0 and near +-pi, unlike acos(n_a . n_b).
double atan2_of_normals(const Vec3& e, double len_e, const Vec3& na, const Vec3& nb) {
  const double sin_part = na.cross(nb).dot(e);
  const double cos_part = -len_e * na.dot(nb);
  const double theta = std::atan2(sin_part, cos_part);
  // atan2 returns -pi for (-0, negative); the documented range is (-pi, pi].
  return theta == -M_PI ? M_PI : theta;
}

/// Gradient, Bridson et al. 2003 (bending-force directions u_1..u_4 with their N_i = our normals
/// and |E| N_i / |N_i|^2 = n_i / h_i) in our sign convention; Tamstorf & Grinspun 2013 give the
/// same vectors in cotangent form. The edge-vertex terms are the barycentric split of the apex
/// terms at the foot of each height, fixed by translation and rotation invariance:
///   d theta/dxa = v_A,  d theta/dxb = -v_B,
///   d theta/dx1 = -alpha_A v_A + alpha_B v_B,
///   d theta/dx0 = -(1 - alpha_A) v_A + (1 - alpha_B) v_B.
void write_gradient(const Wing& a, const Wing& b, Vec12& g) {
  g.segment<3>(XA) = a.v;
  g.segment<3>(XB) = -b.v;
  g.segment<3>(X1) = b.alpha * b.v - a.alpha * a.v;
  g.segment<3>(X0) = -(g.segment<3>(XA) + g.segment<3>(XB) + g.segment<3>(X1));
}

/// Adds sign * (Jacobian of one wing's part of the gradient) to the upper-triangle blocks of
/// hess (slot order X0 < X1 < apex); the caller mirrors them, so the result is exactly
/// symmetric.
///
/// Derivation (ours, checked against finite differences in the tests; Tamstorf & Grinspun
/// 2013 reach an equivalent Hessian written with face angles, heights and edge normals). The
/// gradient above is g = G(x0, x1, xa) - G(x0, x1, xb) with
///   G(x0, x1, q) = ( -(1 - alpha) v, -alpha v, v ),
/// a function of e = x1 - x0 and u = q - x0 alone, so that d/dq = d/du, d/dx1 = d/de and
/// d/dx0 = -d/de - d/du. With n = N / |N|, dN = [e]x du - [u]x de,
/// d(N / |N|^2) = (I - 2 n n^T) dN / |N|^2 and (I - 2 n n^T)[a]x = [a]x - 2 N (N x a)^T / |N|^2:
///   dv/du     = |e| / |N|^2 ([e]x - 2 N (N x e)^T / |N|^2)           (symmetric, as e . n = 0)
///   dv/de     = N e^T / (|e| |N|^2) - |e| / |N|^2 ([u]x - 2 N (N x u)^T / |N|^2)
///   dalpha/de = (u - 2 alpha e) / |e|^2.
/// Rows of the wing's 9 x 9 Jacobian F (row = gradient slot, column = variable):
///   F_qq = dv/du,  F_q1 = dv/de,  F_q0 = -(F_qq + F_q1),
///   F_11 = -alpha dv/de - v (dalpha/de)^T,  F_1q = F_q1^T,  F_10 = -(F_1q + F_11),
///   row 0 = -(row q + row 1)  (G sums to zero over its three slots).
/// F_1q = F_q1^T replaces the longer -alpha dv/du - v (dalpha/du)^T: only this wing touches the
/// (x1, q) pair and the full Hessian is symmetric. F itself is not symmetric on the edge slots:
/// G is the gradient of the wing's angle about the edge minus the rotation rate of the edge's
/// own frame, a term that depends on x0, x1 only, is the same for both wings and cancels in
/// G_A - G_B. Keeping each wing's symmetric part drops exactly that term, which gives
///   (1,1): S = sym(F_11),  (0,1): -(dv/de + S),  (0,0): dv/du + dv/de + dv/de^T + S,
///   (0,q): -(dv/du + dv/de^T),  (1,q): dv/de^T,  (q,q): dv/du.
void add_wing_hessian(const Vec3& e, double len_e, double inv_ee, const Wing& w, double sign,
                      int apex, Mat12& hess) {
  const Vec3& n = w.normal;
  const double s = sign * len_e * w.inv_nn;  // the wing's sign is folded in here
  const double two_inv_nn = 2.0 * w.inv_nn;
  Mat3 dv_du = s * (cross_matrix(e) - two_inv_nn * n * n.cross(e).transpose());
  dv_du = 0.5 * (dv_du + dv_du.transpose()).eval();  // symmetric up to rounding: make it exact
  const Mat3 dv_de = ((sign * w.inv_nn / len_e) * n) * e.transpose() -
                     s * (cross_matrix(w.u) - two_inv_nn * n * n.cross(w.u).transpose());
  const Vec3 dalpha_de = (w.u - 2.0 * w.alpha * e) * inv_ee;
  Mat3 f11 = -w.alpha * dv_de - (sign * w.v) * dalpha_de.transpose();
  f11 = 0.5 * (f11 + f11.transpose()).eval();
  const Mat3 dv_de_t = dv_de.transpose();

  hess.block<3, 3>(X0, X0) += dv_du + (dv_de + dv_de_t) + f11;
  hess.block<3, 3>(X0, X1) -= dv_de + f11;
  hess.block<3, 3>(X0, apex) = -(dv_du + dv_de_t);
  hess.block<3, 3>(X1, X1) += f11;
  hess.block<3, 3>(X1, apex) = dv_de_t;
  hess.block<3, 3>(apex, apex) = dv_du;
}

/// Copies the upper-triangle 3x3 blocks of hess onto the lower ones (the xa-xb blocks are 0).
void mirror_upper_blocks(Mat12& hess) {
  hess.block<3, 3>(X1, X0) = hess.block<3, 3>(X0, X1).transpose();
  hess.block<3, 3>(XA, X0) = hess.block<3, 3>(X0, XA).transpose();
  hess.block<3, 3>(XB, X0) = hess.block<3, 3>(X0, XB).transpose();
  hess.block<3, 3>(XA, X1) = hess.block<3, 3>(X1, XA).transpose();
  hess.block<3, 3>(XB, X1) = hess.block<3, 3>(X1, XB).transpose();
}

}  // namespace

void dihedral_angle_derivatives(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                const Eigen::Vector3d& xa, const Eigen::Vector3d& xb, double& theta,
                                Eigen::Matrix<double, 12, 1>* grad,
                                Eigen::Matrix<double, 12, 12>* hess) {
  const Vec3 e = x1 - x0;
  const double inv_ee = 1.0 / e.squaredNorm();
  const double len_e = std::sqrt(e.squaredNorm());
  const Wing a = make_wing(e, len_e, inv_ee, x0, xa);
  const Wing b = make_wing(e, len_e, inv_ee, x0, xb);
  theta = atan2_of_normals(e, len_e, a.normal, b.normal);
  if (grad != nullptr) write_gradient(a, b, *grad);
  if (hess != nullptr) {
    hess->setZero();
    add_wing_hessian(e, len_e, inv_ee, a, +1.0, XA, *hess);
    add_wing_hessian(e, len_e, inv_ee, b, -1.0, XB, *hess);
    mirror_upper_blocks(*hess);
  }
}

double dihedral_angle(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                      const Eigen::Vector3d& xa, const Eigen::Vector3d& xb) {
  const Vec3 e = x1 - x0;
  // Only the directions of N_A and N_B matter here, so they are not normalised.
  return atan2_of_normals(e, e.norm(), e.cross(xa - x0), e.cross(xb - x0));
}

Eigen::Matrix<double, 12, 1> dihedral_angle_gradient(const Eigen::Vector3d& x0,
                                                     const Eigen::Vector3d& x1,
                                                     const Eigen::Vector3d& xa,
                                                     const Eigen::Vector3d& xb) {
  double theta = 0.0;
  Vec12 grad;
  dihedral_angle_derivatives(x0, x1, xa, xb, theta, &grad, nullptr);
  return grad;
}

Eigen::Matrix<double, 12, 12> dihedral_angle_hessian(const Eigen::Vector3d& x0,
                                                     const Eigen::Vector3d& x1,
                                                     const Eigen::Vector3d& xa,
                                                     const Eigen::Vector3d& xb) {
  double theta = 0.0;
  Mat12 hess;
  dihedral_angle_derivatives(x0, x1, xa, xb, theta, nullptr, &hess);
  return hess;
}

}  // namespace papersim::simulation
