#include "simulation/energies/bending_energy.hpp"

#include <Eigen/LU>
#include <cmath>

#include "simulation/energies/dihedral_angle.hpp"
#include "simulation/energies/fit_bending_energy.hpp"
#include "simulation/energies/morley_bending_energy.hpp"

namespace papersim::simulation {

Eigen::RowVector3d hinge_curvature_row(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                       const Eigen::Vector2d& pa, const Eigen::Vector2d& pb) {
  Eigen::Matrix2d T;
  T.col(0) = p1 - p0;
  T.col(1) = pa - p0;
  const Eigen::Vector2d l12 = T.inverse() * (pb - p0);
  const double l[3] = {1 - l12[0] - l12[1], l12[0], l12[1]};
  const Eigen::Vector2d p[3] = {p0, p1, pa};
  Eigen::RowVector3d row = Eigen::RowVector3d::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      const Eigen::Vector2d d = p[i] - p[j];
      row += -0.5 * l[i] * l[j] * Eigen::RowVector3d(d.x() * d.x(), d.y() * d.y(), 2 * d.x() * d.y());
    }
  const Eigen::Vector2d e = (p1 - p0).normalized();
  const Eigen::Vector2d r = pb - p0;
  return row / std::abs(e.x() * r.y() - e.y() * r.x());
}

Eigen::Matrix3d plate_energy_matrix(double nu) {
  Eigen::Matrix3d Q = (1 - nu) * Eigen::Vector3d(1, 1, 2).asDiagonal().toDenseMatrix();
  Q += nu * Eigen::Vector3d(1, 1, 0) * Eigen::RowVector3d(1, 1, 0);
  return Q;
}

HingeDerivatives hinge_derivatives(const remesh::Hinges& hinges, const Eigen::VectorXd& x,
                                   bool with_hessians) {
  const int nh = static_cast<int>(hinges.vertices.rows());
  HingeDerivatives d;
  d.theta.resize(nh);
  d.gradients.resize(nh);
  d.hessians.resize(with_hessians ? nh : 0);
  Eigen::Vector3d p[4];
  for (int h = 0; h < nh; ++h) {
    gather_hinge(x, hinges.vertices.row(h), p);
    dihedral_angle_derivatives(p[0], p[1], p[2], p[3], d.theta[h], &d.gradients[h],
                               with_hessians ? &d.hessians[h] : nullptr);
  }
  return d;
}

Eigen::VectorXd hinge_angles_at(const remesh::Hinges& hinges, const Eigen::VectorXd& x) {
  Eigen::VectorXd theta(hinges.vertices.rows());
  Eigen::Vector3d p[4];
  for (int h = 0; h < theta.size(); ++h) {
    gather_hinge(x, hinges.vertices.row(h), p);
    theta[h] = dihedral_angle(p[0], p[1], p[2], p[3]);
  }
  return theta;
}

BendingEnergy::BendingEnergy(const remesh::SheetMesh& mesh, const Material& material,
                             BendingHessian hessian)
    : m_hinges(remesh::interior_hinges(mesh)),
      m_Q(plate_energy_matrix(material.poisson)),
      m_D(material.bending_stiffness),
      m_weakening(material.weakening),
      m_hessian_kind(hessian) {}

Eigen::VectorXd BendingEnergy::hinge_angles(const Eigen::VectorXd& x) const {
  return hinge_angles_at(m_hinges, x);
}

std::unique_ptr<BendingEnergy> make_bending_energy(const remesh::SheetMesh& mesh,
                                                   const Material& material,
                                                   BendingHessian hessian,
                                                   const std::vector<int>& clamped_faces) {
  if (material.bending_model == BendingModel::morley)
    return std::make_unique<MorleyBendingEnergy>(mesh, material, hessian, clamped_faces);
  return std::make_unique<FitBendingEnergy>(mesh, material, hessian);
}

}  // namespace papersim::simulation
