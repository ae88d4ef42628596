#include "simulation/energies/bending_energy.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
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
      row +=
          -0.5 * l[i] * l[j] * Eigen::RowVector3d(d.x() * d.x(), d.y() * d.y(), 2 * d.x() * d.y());
    }
  const Eigen::Vector2d e = (p1 - p0).normalized();
  const Eigen::Vector2d r = pb - p0;
  return row / std::abs(e.x() * r.y() - e.y() * r.x());
}

CurvatureStencils::CurvatureStencils(const remesh::Hinges& hinges,
                                     const Eigen::MatrixX3i& face_hinges,
                                     const Eigen::MatrixX3i& faces, const Eigen::MatrixX2d& X)
    : m_hinges(hinges),
      m_face_hinges(face_hinges),
      m_faces(faces),
      m_X(X),
      m_vertex_faces(X.rows()) {
  for (int f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) m_vertex_faces[faces(f, k)].push_back(f);
}

void CurvatureStencils::add_face_hinges(std::vector<int>& stencil, int g) const {
  for (int k = 0; k < 3; ++k) {
    const int h = m_face_hinges(g, k);
    if (h >= 0 && std::find(stencil.begin(), stencil.end(), h) == stencil.end())
      stencil.push_back(h);
  }
}

void CurvatureStencils::add_neighbour_hinges(std::vector<int>& stencil) const {
  const std::vector<int> mine = stencil;
  for (int h : mine)
    for (int s = 0; s < 2; ++s) add_face_hinges(stencil, m_hinges.faces(h, s));
}

Eigen::MatrixXd CurvatureStencils::rows(const std::vector<int>& stencil) const {
  Eigen::MatrixXd B(stencil.size(), 3);
  for (size_t i = 0; i < stencil.size(); ++i) {
    const Eigen::Vector4i v = m_hinges.vertices.row(stencil[i]);
    B.row(i) = hinge_curvature_row(m_X.row(v[0]), m_X.row(v[1]), m_X.row(v[2]), m_X.row(v[3]));
  }
  return B;
}

bool CurvatureStencils::determined(const std::vector<int>& stencil) const {
  if (stencil.size() < 3) return false;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(rows(stencil));
  return svd.singularValues()[2] > 1e-6 * svd.singularValues()[0];
}

bool CurvatureStencils::grow_until_determined(std::vector<int>& stencil, int f) const {
  for (int ring = 0; ring < 2; ++ring) {
    if (determined(stencil)) return true;
    std::vector<int> verts;
    for (int h : stencil)
      for (int k = 0; k < 4; ++k) verts.push_back(m_hinges.vertices(h, k));
    for (int k = 0; k < 3; ++k) verts.push_back(m_faces(f, k));
    // The faces with a corner in verts, in ascending order (the stencil's row order).
    std::vector<int> ring_faces;
    for (int v : verts)
      ring_faces.insert(ring_faces.end(), m_vertex_faces[v].begin(), m_vertex_faces[v].end());
    std::sort(ring_faces.begin(), ring_faces.end());
    ring_faces.erase(std::unique(ring_faces.begin(), ring_faces.end()), ring_faces.end());
    for (int g : ring_faces) add_face_hinges(stencil, g);
  }
  return determined(stencil);
}

std::array<int, 4> local_hinge(const remesh::Hinges& hinges, int h, std::vector<int>& vertices) {
  std::array<int, 4> loc;
  for (int k = 0; k < 4; ++k) {
    const int v = hinges.vertices(h, k);
    auto it = std::find(vertices.begin(), vertices.end(), v);
    if (it == vertices.end()) {
      vertices.push_back(v);
      it = vertices.end() - 1;
    }
    loc[k] = static_cast<int>(it - vertices.begin());
  }
  return loc;
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
                                                   const Material& material, BendingHessian hessian,
                                                   const std::vector<int>& clamped_faces) {
  if (material.bending_model == BendingModel::morley)
    return std::make_unique<MorleyBendingEnergy>(mesh, material, hessian, clamped_faces);
  return std::make_unique<FitBendingEnergy>(mesh, material, hessian);
}

}  // namespace papersim::simulation
