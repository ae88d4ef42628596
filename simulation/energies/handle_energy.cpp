#include "simulation/energies/handle_energy.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "simulation/errors.hpp"

namespace papersim::simulation {

Eigen::Vector3d handle_displacement(const HandleSpec& spec, double t) {
  const auto& k = spec.keyframes;
  if (k.empty()) return Eigen::Vector3d::Zero();
  if (t <= k.front().time) return k.front().displacement;
  if (t >= k.back().time) return k.back().displacement;
  const auto hi = std::upper_bound(k.begin(), k.end(), t,
                                   [](double s, const HandleKeyframe& f) { return s < f.time; });
  const auto lo = hi - 1;
  const double a = (t - lo->time) / (hi->time - lo->time);
  return (1 - a) * lo->displacement + a * hi->displacement;
}

MaterialLocation locate_material_point(const remesh::SheetMesh& mesh, const Eigen::Vector2d& p) {
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  MaterialLocation best;
  double best_outside = INF;
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Matrix2d T;
    T.col(0) = X.row(F(f, 1)) - X.row(F(f, 0));
    T.col(1) = X.row(F(f, 2)) - X.row(F(f, 0));
    const Eigen::Vector2d l = T.inverse() * (p - Eigen::Vector2d(X.row(F(f, 0))));
    const Eigen::Vector3d w(1 - l.sum(), l[0], l[1]);
    const double outside = -std::min(0.0, w.minCoeff());
    if (outside < best_outside) {
      best_outside = outside;
      best.face = f;
      best.weights = w;
    }
  }
  if (best_outside > 1e-9) best.face = -1;
  return best;
}

namespace {

MaterialLocation locate_or_throw(const remesh::SheetMesh& mesh, const Eigen::Vector2d& p) {
  MaterialLocation loc = locate_material_point(mesh, p);
  if (loc.face < 0) {
    std::ostringstream s;
    s << "handle: material point (" << p.x() << ", " << p.y() << ") lies outside the sheet";
    throw SceneError(s.str());
  }
  return loc;
}

}  // namespace

std::vector<AnchoredHandle> anchor_handles(const remesh::SheetMesh& mesh, const Eigen::VectorXd& x,
                                           const std::vector<HandleSpec>& handles) {
  const Eigen::MatrixX3i F = mesh.faces();
  std::vector<AnchoredHandle> anchored;
  anchored.reserve(handles.size());
  for (const HandleSpec& spec : handles) {
    const MaterialLocation loc = locate_or_throw(mesh, spec.material_point);
    AnchoredHandle a;
    a.spec = spec;
    for (int k = 0; k < 3; ++k) a.anchor += loc.weights[k] * x.segment<3>(3 * F(loc.face, k));
    anchored.push_back(a);
  }
  return anchored;
}

HandleEnergy::HandleEnergy(const remesh::SheetMesh& mesh, const Eigen::VectorXd& x0,
                           const std::vector<HandleSpec>& handles)
    : HandleEnergy(mesh, anchor_handles(mesh, x0, handles)) {}

HandleEnergy::HandleEnergy(const remesh::SheetMesh& mesh,
                           const std::vector<AnchoredHandle>& handles) {
  const Eigen::MatrixX3i F = mesh.faces();
  m_handles.reserve(handles.size());
  for (const AnchoredHandle& a : handles) {
    const MaterialLocation loc = locate_or_throw(mesh, a.spec.material_point);
    Bound b;
    b.spec = a.spec;
    b.v = {F(loc.face, 0), F(loc.face, 1), F(loc.face, 2)};
    b.w = loc.weights;
    b.start = a.anchor;
    m_handles.push_back(b);
  }
}

void HandleEnergy::add_pattern(SparsityBuilder& pattern) const {
  for (const auto& h : m_handles) pattern.add_clique(h.v.data(), 3);
}

void HandleEnergy::begin_step(const StepContext& ctx, const Eigen::VectorXd&) {
  m_t1 = ctx.time_t1();
}

Eigen::Vector3d HandleEnergy::point(int i, const Eigen::VectorXd& x) const {
  const Bound& b = m_handles[i];
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) p += b.w[k] * x.segment<3>(3 * b.v[k]);
  return p;
}

Eigen::Vector3d HandleEnergy::target(int i, double t) const {
  return m_handles[i].start + handle_displacement(m_handles[i].spec, t);
}

double HandleEnergy::error(int i, const Eigen::VectorXd& x, double t) const {
  return (point(i, x) - target(i, t)).cwiseProduct(m_handles[i].spec.axes).norm();
}

double HandleEnergy::value(const Eigen::VectorXd& x) const {
  double e = 0;
  for (int i = 0; i < size(); ++i)
    if (active(i, m_t1)) e += 0.5 * m_handles[i].spec.stiffness * std::pow(error(i, x, m_t1), 2);
  return e;
}

void HandleEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& g,
                                   BlockSymmetricMatrix* H,
                                   HessianProjection /*projection*/) const {
  for (int i = 0; i < size(); ++i) {
    if (!active(i, m_t1)) continue;
    const Bound& b = m_handles[i];
    const Eigen::Vector3d r =
        b.spec.stiffness * (point(i, x) - target(i, m_t1)).cwiseProduct(b.spec.axes);
    for (int k = 0; k < 3; ++k) g.segment<3>(3 * b.v[k]) += b.w[k] * r;
    if (!H) continue;
    Eigen::Matrix<double, 9, 9> local;
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c)
        local.block<3, 3>(3 * a, 3 * c) =
            b.spec.stiffness * b.w[a] * b.w[c] * Eigen::Matrix3d(b.spec.axes.asDiagonal());
    H->add_element<3>(b.v, local);
  }
}

}  // namespace papersim::simulation
