#pragma once
/// Projection of a symmetric element Hessian onto the positive semi-definite cone (negative
/// eigenvalues set to zero), for Newton iterations whose exact Hessian is indefinite.
#include <Eigen/Eigenvalues>

namespace papersim::simulation {

template <class Derived>
typename Derived::PlainObject project_psd(const Eigen::MatrixBase<Derived>& H) {
  Eigen::SelfAdjointEigenSolver<typename Derived::PlainObject> es(H);
  return es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() *
         es.eigenvectors().transpose();
}

}  // namespace papersim::simulation
