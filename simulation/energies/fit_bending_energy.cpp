#include "simulation/energies/fit_bending_energy.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

#include "simulation/energies/dihedral_angle.hpp"
#include "simulation/energies/psd.hpp"
#include "simulation/errors.hpp"

namespace papersim::simulation {

namespace {

/// Weight of the fit residual against the plate energy (see build_stencil).
constexpr double HOURGLASS_WEIGHT = 10.0;
}  // namespace

FitBendingEnergy::FitBendingEnergy(const remesh::SheetMesh& mesh, const Material& material,
                                   BendingHessian hessian_kind)
    : BendingEnergy(mesh, material, hessian_kind) {
  const Eigen::MatrixX3i faces = mesh.faces();
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i fh = remesh::face_hinges(mesh, m_hinges);
  m_faces.resize(faces.rows());
  const CurvatureStencils stencils(m_hinges, fh, faces, X);
  for (int f = 0; f < faces.rows(); ++f) build_stencil(f, stencils, faces, X);
  for (Face& face : m_faces)
    face.M = face.P.transpose() * m_Q * face.P + face.R.transpose() * face.R;
  set_plastic_state(mesh.plastic_curvature(), mesh.damage());
}

void FitBendingEnergy::build_stencil(int f, const CurvatureStencils& stencils,
                                     const Eigen::MatrixX3i& F, const Eigen::MatrixX2d& X) {
  Face& face = m_faces[f];
  // Stencil: the face's own hinges and those of its edge neighbours (up to nine), then of
  // faces sharing a vertex while the curvature is not determined (boundary faces).
  stencils.add_face_hinges(face.hinges, f);
  stencils.add_neighbour_hinges(face.hinges);
  if (!stencils.grow_until_determined(face.hinges, f))
    throw NumericError("bending: the curvature of face " + std::to_string(f) +
                       " is not determined by its neighbourhood (too few interior edges)");
  const Eigen::MatrixXd B = stencils.rows(face.hinges);
  const int ns = static_cast<int>(face.hinges.size());
  face.P = (B.transpose() * B).ldlt().solve(B.transpose());
  // Residual of the fit, scaled to curvature units by the centroid distance across each hinge
  // (theta ~ kappa l): zero for every constant curvature, positive for angle patterns that no
  // smooth surface has (hourglass modes), which the fit alone would not see.
  Eigen::VectorXd inv_l(ns);
  for (int i = 0; i < ns; ++i) {
    const Eigen::Vector4i v = m_hinges.vertices.row(face.hinges[i]);
    const Eigen::Vector2d p0 = X.row(v[0]), e = (Eigen::Vector2d(X.row(v[1])) - p0).normalized();
    auto height = [&](int k) {
      const Eigen::Vector2d r = Eigen::Vector2d(X.row(v[k])) - p0;
      return std::abs(e.x() * r.y() - e.y() * r.x());
    };
    inv_l[i] = 3.0 / (height(2) + height(3));
  }
  face.R = inv_l.asDiagonal() * (Eigen::MatrixXd::Identity(ns, ns) - B * face.P);
  face.R *= std::sqrt(HOURGLASS_WEIGHT / ns);
  for (int h : face.hinges) face.local.push_back(local_hinge(m_hinges, h, face.vertices));
  Eigen::Matrix2d T;
  T.col(0) = X.row(F(f, 1)) - X.row(F(f, 0));
  T.col(1) = X.row(F(f, 2)) - X.row(F(f, 0));
  face.area = 0.5 * std::abs(T.determinant());
}

void FitBendingEnergy::set_plastic_state(const Eigen::MatrixX3d& k, const Eigen::VectorXd& damage) {
  for (size_t f = 0; f < m_faces.size(); ++f) {
    m_faces[f].plastic = k.row(f).transpose();
    m_faces[f].stiffness = m_faces[f].area * m_D / (1 + m_weakening * damage[f]);
  }
}

void FitBendingEnergy::add_pattern(SparsityBuilder& pattern) const {
  for (const auto& face : m_faces)
    pattern.add_clique(face.vertices.data(), static_cast<int>(face.vertices.size()));
}

double FitBendingEnergy::face_energy(const Face& face, const Eigen::VectorXd& theta) const {
  Eigen::VectorXd t(face.hinges.size());
  for (size_t i = 0; i < face.hinges.size(); ++i) t[i] = theta[face.hinges[i]];
  const Eigen::Vector3d k = face.P * t - face.plastic;
  return 0.5 * face.stiffness * (k.dot(m_Q * k) + (face.R * t).squaredNorm());
}

double FitBendingEnergy::value(const Eigen::VectorXd& x) const {
  const Eigen::VectorXd theta = hinge_angles(x);
  double e = 0;
  for (const auto& face : m_faces) e += face_energy(face, theta);
  return e;
}

Eigen::MatrixX3d FitBendingEnergy::face_curvatures(const Eigen::VectorXd& x) const {
  const Eigen::VectorXd theta = hinge_angles(x);
  Eigen::MatrixX3d K(m_faces.size(), 3);
  for (size_t f = 0; f < m_faces.size(); ++f) {
    const Face& face = m_faces[f];
    Eigen::VectorXd t(face.hinges.size());
    for (size_t i = 0; i < face.hinges.size(); ++i) t[i] = theta[face.hinges[i]];
    K.row(f) = (face.P * t).transpose();
  }
  return K;
}

void FitBendingEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                                       BlockSymmetricMatrix* hessian,
                                       HessianProjection /*projection*/) const {
  const bool curvature_term = m_hessian_kind != BendingHessian::gauss_newton && hessian;
  const HingeDerivatives hd = hinge_derivatives(m_hinges, x, curvature_term);
  const Eigen::VectorXd& theta = hd.theta;
  const auto& grads = hd.gradients;
  const auto& hesses = hd.hessians;
  Eigen::MatrixXd H, JM;
  if (hessian && m_slots.stale(*hessian)) {
    m_slots.reset(*hessian);
    for (const Face& face : m_faces)
      m_slots.add(*hessian, face.vertices.data(), static_cast<int>(face.vertices.size()));
  }
  for (std::size_t fi = 0; fi < m_faces.size(); ++fi) {
    const Face& face = m_faces[fi];
    const int ns = static_cast<int>(face.hinges.size());
    Eigen::VectorXd t(ns);
    for (int i = 0; i < ns; ++i) t[i] = theta[face.hinges[i]];
    const Eigen::Vector3d k = face.P * t - face.plastic;
    const Eigen::VectorXd c =
        face.stiffness * (face.P.transpose() * (m_Q * k) + face.R.transpose() * (face.R * t));
    // Local gradient matrix Jt: column i = grad theta_i over the face's local vertices, nonzero
    // in the 4 vertices of hinge i only; the products below skip its zeros (measured: the
    // dense products were 13% of a fall-sphere run).
    const int nv = static_cast<int>(face.vertices.size());
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * nv);
    for (int i = 0; i < ns; ++i)
      for (int q = 0; q < 4; ++q)
        g.segment<3>(3 * face.local[i][q]) += c[i] * grads[face.hinges[i]].segment<3>(3 * q);
    for (int a = 0; a < nv; ++a) gradient.segment<3>(3 * face.vertices[a]) += g.segment<3>(3 * a);
    if (!hessian) continue;
    // H = Jt (stiffness M) Jt^T, as JM = Jt M column by column, then H = sum_j JM_j (Jt_j)^T.
    JM.setZero(3 * nv, ns);
    for (int i = 0; i < ns; ++i)
      for (int q = 0; q < 4; ++q) {
        const Eigen::Vector3d gi = face.stiffness * grads[face.hinges[i]].segment<3>(3 * q);
        const int a = 3 * face.local[i][q];
        for (int j = 0; j < ns; ++j) JM.block<3, 1>(a, j) += face.M(i, j) * gi;
      }
    H.setZero(3 * nv, 3 * nv);
    for (int j = 0; j < ns; ++j)
      for (int r = 0; r < 4; ++r)
        H.middleCols<3>(3 * face.local[j][r]).noalias() +=
            JM.col(j) * grads[face.hinges[j]].segment<3>(3 * r).transpose();
    if (curvature_term) {
      for (int i = 0; i < ns; ++i)
        for (int q = 0; q < 4; ++q)
          for (int r = 0; r < 4; ++r)
            H.block<3, 3>(3 * face.local[i][q], 3 * face.local[i][r]) +=
                c[i] * hesses[face.hinges[i]].block<3, 3>(3 * q, 3 * r);
    }
    if (m_hessian_kind == BendingHessian::projected) H = project_psd(H);
    hessian->add_element(face.vertices.data(), nv, m_slots.slots(static_cast<int>(fi)), H.data());
  }
}

}  // namespace papersim::simulation
