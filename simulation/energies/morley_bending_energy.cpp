#include "simulation/energies/morley_bending_energy.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "common/assert.hpp"
#include "simulation/energies/dihedral_angle.hpp"
#include "simulation/energies/fit_bending_energy.hpp"
#include "simulation/energies/psd.hpp"
#include "simulation/errors.hpp"

namespace papersim::simulation {

struct MorleyBendingEnergy::Factor {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  bool analyzed = false;  // the symbolic analysis is made once: the pattern never changes
};

namespace {

/// Weight of the boundary-slope penalty over D_f (its residual is a slope, dimensionless):
/// stiff enough to act as a constraint (the probe's figures are at this weight) while the
/// slope matrix stays well conditioned for a direct solve.
constexpr double BOUNDARY_PENALTY = 1e6;
}  // namespace

MorleyBendingEnergy::MorleyBendingEnergy(const remesh::SheetMesh& mesh, const Material& material,
                                         BendingHessian hessian_kind,
                                         const std::vector<int>& clamped_faces)
    : BendingEnergy(mesh, material, hessian_kind), m_C(std::make_unique<Factor>()) {
  const Eigen::MatrixX3i F = mesh.faces();
  const Eigen::MatrixX2d X = mesh.material_coords();
  m_faces.resize(F.rows());
  for (int f : clamped_faces) {
    if (f < 0 || f >= F.rows())
      throw NumericError("bending: clamped face " + std::to_string(f) +
                         " is not a face of the mesh");
    m_faces[f].clamped = true;
  }
  // Face geometry: R_f (s = R_f K for quadratics) per local edge k (opposite corner k).
  for (int f = 0; f < F.rows(); ++f) {
    Face& face = m_faces[f];
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = X.row(F(f, k));
    face.area = 0.5 * std::abs((p[1] - p[0]).x() * (p[2] - p[0]).y() -
                               (p[1] - p[0]).y() * (p[2] - p[0]).x());
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d pi = p[(k + 1) % 3], pj = p[(k + 2) % 3], pk = p[k];
      const Eigen::Vector2d e = (pj - pi).normalized();
      const double h = std::abs(e.x() * (pk - pi).y() - e.y() * (pk - pi).x());
      const Eigen::Vector2d a = pk - pi, b = pk - pj;
      face.R.row(k) << a.x() * b.x(), a.y() * b.y(), a.x() * b.y() + a.y() * b.x();
      face.R.row(k) /= 2 * h;
    }
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(face.R);
    if (!lu.isInvertible() || !(face.area > 0))
      throw NumericError("bending: face " + std::to_string(f) + " is degenerate in material space");
    face.Rinv = lu.inverse();
  }
  // Edges: interior hinges split their angle, s = alpha theta + sigma psi.
  auto local_edge = [&](int f, int opposite) {
    for (int k = 0; k < 3; ++k)
      if (F(f, k) == opposite) return k;
    throw NumericError("bending: inconsistent hinge of face " + std::to_string(f));
  };
  for (int h = 0; h < m_hinges.vertices.rows(); ++h) {
    const Eigen::Vector4i v = m_hinges.vertices.row(h);
    const int f0 = m_hinges.faces(h, 0), f1 = m_hinges.faces(h, 1);
    const int k0 = local_edge(f0, v[2]), k1 = local_edge(f1, v[3]);
    // The two faces' slope rows add up to the hinge's angle row (sign t of the convention).
    const Eigen::RowVector3d row =
        hinge_curvature_row(X.row(v[0]), X.row(v[1]), X.row(v[2]), X.row(v[3]));
    const Eigen::RowVector3d sum = m_faces[f0].R.row(k0) + m_faces[f1].R.row(k1);
    const double t = sum.dot(row) > 0 ? 1.0 : -1.0;
    if ((sum - t * row).norm() > 1e-8 * row.norm())
      throw NumericError("bending: the slopes of hinge " + std::to_string(h) +
                         " do not add up to its angle (inconsistent orientation)");
    Face &a = m_faces[f0], &b = m_faces[f1];
    a.hinge[k0] = b.hinge[k1] = h;
    if (!a.clamped && !b.clamped) {
      a.alpha[k0] = b.alpha[k1] = 0.5 * t;
      a.psi[k0] = b.psi[k1] = m_num_psi++;
      a.sigma[k0] = 1;
      b.sigma[k1] = -1;
    } else if (!a.clamped) {
      a.alpha[k0] = t;  // the clamped face keeps its slope: this one takes the whole angle
    } else if (!b.clamped) {
      b.alpha[k1] = t;
    }
  }
  for (Face& face : m_faces)
    for (int k = 0; k < 3; ++k)
      if (face.hinge[k] < 0 && !face.clamped) {
        face.psi[k] = m_num_psi++;
        face.sigma[k] = 1;
      }
  pack_slopes();
  build_elements();
  set_plastic_state(mesh.plastic_curvature(), mesh.damage());
  try {
    m_measure = std::make_unique<FitBendingEnergy>(mesh, material, hessian_kind);
  } catch (const NumericError&) {
    // A mesh too small for the fit's stencils (fewer than three interior edges): the plastic
    // update measures the condensed curvature instead.
  }
}

MorleyBendingEnergy::~MorleyBendingEnergy() = default;

void MorleyBendingEnergy::pack_slopes() {
  // The Newton system stores 3x3 blocks, so the three slopes sharing a block couple to each
  // other's vertices. Packing the three edges of one face together adds no coupling (they share
  // that face's element); the edges left over are packed in face order, near each other.
  std::vector<int> order(m_num_psi, -1);
  int next = 0;
  for (const Face& face : m_faces)
    if (face.psi[0] >= 0 && face.psi[1] >= 0 && face.psi[2] >= 0 && order[face.psi[0]] < 0 &&
        order[face.psi[1]] < 0 && order[face.psi[2]] < 0)
      for (int k = 0; k < 3; ++k) order[face.psi[k]] = next++;
  for (const Face& face : m_faces)
    for (int k = 0; k < 3; ++k)
      if (face.psi[k] >= 0 && order[face.psi[k]] < 0) order[face.psi[k]] = next++;
  for (Face& face : m_faces)
    for (int k = 0; k < 3; ++k)
      if (face.psi[k] >= 0) face.psi[k] = order[face.psi[k]];
}

void MorleyBendingEnergy::build_elements() {
  const int nf = static_cast<int>(m_faces.size());
  m_face_element.assign(nf, -1);
  // Face g's curvature K_g - Kp_g as columns over an element's unknown lists (appended as
  // needed; theta columns are >= 0, psi column j is -1 - j).
  auto curvature_rows = [&](int g, std::vector<int>& theta, std::vector<int>& psi,
                            std::vector<std::pair<int, Eigen::Vector3d>>& columns) {
    const Face& face = m_faces[g];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d col = face.Rinv.col(k);
      if (face.alpha[k] != 0) {
        auto it = std::find(theta.begin(), theta.end(), face.hinge[k]);
        if (it == theta.end()) theta.push_back(face.hinge[k]), it = theta.end() - 1;
        columns.emplace_back(static_cast<int>(it - theta.begin()), face.alpha[k] * col);
      }
      if (face.psi[k] >= 0) {
        auto it = std::find(psi.begin(), psi.end(), face.psi[k]);
        if (it == psi.end()) psi.push_back(face.psi[k]), it = psi.end() - 1;
        columns.emplace_back(-1 - static_cast<int>(it - psi.begin()), face.sigma[k] * col);
      }
    }
  };
  auto to_matrix = [](const std::vector<int>& theta, const std::vector<int>& psi,
                      const std::vector<std::pair<int, Eigen::Vector3d>>& columns) {
    Eigen::MatrixXd L = Eigen::MatrixXd::Zero(3, theta.size() + psi.size());
    for (const auto& [c, v] : columns)
      L.col(c >= 0 ? c : static_cast<int>(theta.size()) - 1 - c) += v;
    return L;
  };
  // Face element: K_f - Kp_f = L u - Kp_f over the face's own unknowns u.
  for (int f = 0; f < nf; ++f) {
    if (m_faces[f].clamped) continue;
    Element e;
    std::vector<std::pair<int, Eigen::Vector3d>> columns;
    curvature_rows(f, e.theta, e.psi, columns);
    e.L = to_matrix(e.theta, e.psi, columns);
    m_face_element[f] = static_cast<int>(m_elements.size());
    m_elements.push_back(std::move(e));
  }
  m_num_face_elements = static_cast<int>(m_elements.size());
  // Boundary penalties: s_fk - R_f,k (Kp_f + mean_g (K_g - Kp_g)) over the unclamped faces g
  // across f's interior edges.
  for (int f = 0; f < nf; ++f) {
    const Face& face = m_faces[f];
    if (face.clamped) continue;
    std::vector<int> neighbours;
    for (int k = 0; k < 3; ++k) {
      const int h = face.hinge[k];
      if (h < 0) continue;
      const int g = m_hinges.faces(h, 0) == f ? m_hinges.faces(h, 1) : m_hinges.faces(h, 0);
      if (!m_faces[g].clamped) neighbours.push_back(g);
    }
    if (neighbours.empty()) continue;
    for (int k = 0; k < 3; ++k) {
      if (face.hinge[k] >= 0) continue;
      Element e;
      e.psi.push_back(face.psi[k]);
      std::vector<std::pair<int, Eigen::Vector3d>> columns;
      for (int g : neighbours) curvature_rows(g, e.theta, e.psi, columns);
      const Eigen::MatrixXd L3 = to_matrix(e.theta, e.psi, columns);
      e.L = -face.R.row(k) * L3 / static_cast<double>(neighbours.size());
      e.L(0, e.theta.size()) += face.sigma[k];  // psi of the edge itself: first psi
      m_penalties.push_back({f, k, neighbours});
      m_elements.push_back(std::move(e));
    }
  }
  // Vertices of each element's hinges (for the Hessian), local order.
  for (Element& e : m_elements) {
    if (e.L.rows() > 3 || e.L.cols() > MAX_ELEMENT_UNKNOWNS)
      throw NumericError("bending: an element with " + std::to_string(e.L.cols()) +
                         " unknowns (at most " + std::to_string(MAX_ELEMENT_UNKNOWNS) + ")");
    for (int h : e.theta) {
      std::array<int, 4> loc;
      for (int k = 0; k < 4; ++k) {
        const int v = m_hinges.vertices(h, k);
        auto it = std::find(e.vertices.begin(), e.vertices.end(), v);
        if (it == e.vertices.end()) e.vertices.push_back(v), it = e.vertices.end() - 1;
        loc[k] = static_cast<int>(it - e.vertices.begin());
      }
      e.local.push_back(loc);
    }
    // Local order ascending in the global numbering: the blocks of column block b that the
    // matrix stores (its upper triangle) are then the rows of local blocks 0..b, a prefix, and
    // the Hessian loop computes only those.
    const std::vector<int> unsorted = e.vertices;
    std::sort(e.vertices.begin(), e.vertices.end());
    for (auto& loc : e.local)
      for (int& k : loc) {
        const auto at = std::lower_bound(e.vertices.begin(), e.vertices.end(), unsorted[k]);
        k = static_cast<int>(at - e.vertices.begin());
      }
    for (int p : e.psi) {
      const int block = p / 3;
      auto it = std::find(e.blocks.begin(), e.blocks.end(), block);
      if (it == e.blocks.end()) e.blocks.push_back(block), it = e.blocks.end() - 1;
      e.psi_at.emplace_back(static_cast<int>(it - e.blocks.begin()), p % 3);
    }
  }
}

void MorleyBendingEnergy::set_plastic_state(const Eigen::MatrixX3d& k,
                                            const Eigen::VectorXd& damage) {
  const int nf = static_cast<int>(m_faces.size());
  PAPERSIM_ASSERT(k.rows() == nf && damage.size() == nf,
                  "MorleyBendingEnergy::set_plastic_state: sizes");
  const bool first = m_stiffness.empty();
  m_plastic.resize(nf);
  m_stiffness.resize(nf, 0.0);
  bool stiffness_changed = first;
  for (int f = 0; f < nf; ++f) {
    m_plastic[f] = k.row(f).transpose();
    const double stiffness = m_faces[f].area * m_D / (1 + m_weakening * damage[f]);
    stiffness_changed = stiffness_changed || stiffness != m_stiffness[f];
    m_stiffness[f] = stiffness;
  }
  // Plastic curvature enters only the offsets c (the right-hand side of the slope system);
  // damage changes the weights and so the matrix, which is then re-factored numerically on the
  // symbolic analysis made once.
  if (stiffness_changed) update_weights();
  update_offsets();
}

void MorleyBendingEnergy::update_weights() {
  const int nf = static_cast<int>(m_faces.size());
  for (int f = 0; f < nf; ++f)
    if (m_face_element[f] >= 0) m_elements[m_face_element[f]].W = m_stiffness[f] * m_Q;
  for (size_t i = 0; i < m_penalties.size(); ++i) {
    const Penalty& pen = m_penalties[i];
    m_elements[m_num_face_elements + i].W = Eigen::MatrixXd::Constant(
        1, 1, BOUNDARY_PENALTY * m_stiffness[pen.face] / m_faces[pen.face].area);
  }
  // C = d2E/dpsi2 and A_psi_theta = d2E/dpsi dtheta.
  std::vector<Eigen::Triplet<double>> c_entries, a_entries;
  for (Element& e : m_elements) {
    e.M = e.L.transpose() * e.W * e.L;
    const int nt = static_cast<int>(e.theta.size());
    for (size_t i = 0; i < e.psi.size(); ++i) {
      for (size_t j = 0; j < e.psi.size(); ++j)
        c_entries.emplace_back(e.psi[i], e.psi[j], e.M(nt + i, nt + j));
      for (int j = 0; j < nt; ++j) a_entries.emplace_back(e.psi[i], e.theta[j], e.M(nt + i, j));
    }
  }
  m_A_psi_theta.resize(m_num_psi, m_hinges.vertices.rows());
  m_A_psi_theta.setFromTriplets(a_entries.begin(), a_entries.end());
  if (m_num_psi == 0) return;
  Eigen::SparseMatrix<double> C(m_num_psi, m_num_psi);
  C.setFromTriplets(c_entries.begin(), c_entries.end());
  if (!m_C->analyzed) {
    m_C->ldlt.analyzePattern(C);
    m_C->analyzed = true;
  }
  m_C->ldlt.factorize(C);
  ++m_factorizations;
  if (m_C->ldlt.info() != Eigen::Success)
    throw NumericError("bending: the edge slope system cannot be factored");
}

void MorleyBendingEnergy::update_offsets() {
  const int nf = static_cast<int>(m_faces.size());
  for (int f = 0; f < nf; ++f)
    if (m_face_element[f] >= 0) m_elements[m_face_element[f]].c = m_plastic[f];
  for (size_t i = 0; i < m_penalties.size(); ++i) {
    const Penalty& pen = m_penalties[i];
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int g : pen.neighbours) mean += m_plastic[g];
    mean /= static_cast<double>(pen.neighbours.size());
    m_elements[m_num_face_elements + i].c = Eigen::VectorXd::Constant(
        1, m_faces[pen.face].R.row(pen.edge).dot(m_plastic[pen.face] - mean));
  }
  // b_psi = sum L_psi^T W c: C psi* = b_psi - A_psi_theta theta.
  m_b_psi = Eigen::VectorXd::Zero(m_num_psi);
  for (const Element& e : m_elements) {
    const int nt = static_cast<int>(e.theta.size());
    const Eigen::VectorXd Wc = e.L.transpose() * (e.W * e.c);
    for (size_t i = 0; i < e.psi.size(); ++i) m_b_psi[e.psi[i]] += Wc[nt + i];
  }
}

void MorleyBendingEnergy::add_pattern(SparsityBuilder& pattern) const {
  // Each psi is one component of its block: the vertices couple to it, and it to the element's
  // other psi, and not to the block's other two unknowns (which belong to other edges).
  std::vector<int> clique;
  std::vector<unsigned char> components;
  for (const Element& e : m_elements) {
    clique = e.vertices;
    components.assign(e.vertices.size(), 7);
    for (const auto& [block, component] : e.psi_at) {
      clique.push_back(m_first_block + e.blocks[block]);
      components.push_back(static_cast<unsigned char>(1u << component));
    }
    pattern.add_clique(clique.data(), components.data(), static_cast<int>(clique.size()));
  }
}

void MorleyBendingEnergy::unknowns(const Eigen::VectorXd& x, Eigen::VectorXd& theta,
                                   Eigen::VectorXd& psi) const {
  if (theta.size() != m_hinges.vertices.rows()) theta = hinge_angles(x);
  psi = m_num_psi > 0 ? Eigen::VectorXd(m_C->ldlt.solve(m_b_psi - m_A_psi_theta * theta))
                      : Eigen::VectorXd();
}

namespace {

/// y = A x for an element's small dense matrices (L or W, at most 3 rows, or L's transpose, at
/// most 3 columns), each entry summed over the columns in order from zero. That is the order and
/// the rounding of Eigen's matrix-vector kernels at these sizes, without their dispatch or, inside
/// a larger expression, a heap temporary: the same results to the bit (checked on whole runs).
template <class Matrix>
void element_product(const Matrix& A, const double* x, double* y) {
  const Eigen::Index rows = A.rows(), cols = A.cols();
  for (Eigen::Index r = 0; r < rows; ++r) {
    double s = 0;
    for (Eigen::Index c = 0; c < cols; ++c) s += A(r, c) * x[c];
    y[r] = s;
  }
}

}  // namespace

MorleyBendingEnergy::ElementVector MorleyBendingEnergy::element_residual(
    const Element& e, const Eigen::VectorXd& theta, const Eigen::VectorXd& psi) const {
  const int nt = static_cast<int>(e.theta.size());
  ElementVector u(nt + e.psi.size());
  for (int i = 0; i < nt; ++i) u[i] = theta[e.theta[i]];
  for (size_t i = 0; i < e.psi.size(); ++i) u[nt + i] = psi[e.psi[i]];
  ElementVector r(e.L.rows());
  element_product(e.L, u.data(), r.data());
  return r - e.c;
}

double MorleyBendingEnergy::value(const Eigen::VectorXd& x) const {
  Eigen::VectorXd theta, psi;
  unknowns(x, theta, psi);
  double energy = 0;
  for (const Element& e : m_elements) {
    const ElementVector r = element_residual(e, theta, psi);
    ElementVector Wr(r.size());
    element_product(e.W, r.data(), Wr.data());
    energy += 0.5 * r.dot(Wr);
  }
  return energy;
}

Eigen::MatrixX3d MorleyBendingEnergy::yield_curvatures(const Eigen::VectorXd& x) const {
  if (!m_measure) return face_curvatures(x);
  Eigen::MatrixX3d K = m_measure->face_curvatures(x);
  for (size_t f = 0; f < m_faces.size(); ++f)
    if (m_face_element[f] < 0) K.row(f) = m_plastic[f].transpose();
  return K;
}

Eigen::MatrixX3d MorleyBendingEnergy::face_curvatures(const Eigen::VectorXd& x) const {
  Eigen::VectorXd theta, psi;
  unknowns(x, theta, psi);
  Eigen::MatrixX3d K(m_faces.size(), 3);
  for (size_t f = 0; f < m_faces.size(); ++f) {
    const int e = m_face_element[f];
    K.row(f) = (e < 0 ? m_plastic[f]
                      : Eigen::Vector3d(element_residual(m_elements[e], theta, psi) + m_plastic[f]))
                   .transpose();
  }
  return K;
}

void MorleyBendingEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                                          BlockSymmetricMatrix* hessian,
                                          HessianProjection /*projection*/) const {
  const int nh = static_cast<int>(m_hinges.vertices.rows());
  const bool curvature_term = m_hessian_kind != BendingHessian::gauss_newton && hessian;
  HingeDerivatives hd = hinge_derivatives(m_hinges, x, curvature_term);
  Eigen::VectorXd& theta = hd.theta;
  const auto& grads = hd.gradients;
  const auto& hesses = hd.hessians;
  Eigen::VectorXd psi;
  unknowns(x, theta, psi);
  // dE/dtheta at psi* (envelope theorem: dE/dpsi = 0 there).
  Eigen::VectorXd dE = Eigen::VectorXd::Zero(nh);
  std::vector<char> used(nh, 0);
  for (const Element& e : m_elements) {
    const ElementVector r = element_residual(e, theta, psi);
    ElementVector Wr(r.size()), g(e.L.cols());
    element_product(e.W, r.data(), Wr.data());
    element_product(e.L.transpose(), Wr.data(), g.data());
    for (size_t i = 0; i < e.theta.size(); ++i) dE[e.theta[i]] += g[i], used[e.theta[i]] = 1;
  }
  for (int h = 0; h < nh; ++h)
    for (int q = 0; q < 4; ++q)
      gradient.segment<3>(3 * m_hinges.vertices(h, q)) += dE[h] * grads[h].segment<3>(3 * q);
  if (!hessian) return;
  if (m_first_block < 0 && m_num_psi > 0)
    throw NumericError("bending: the Hessian needs the integrator's auxiliary blocks");
  // Gauss-Newton: per element, [G, I]^T M [G, I] over (hinge vertices, psi), with G the hinge
  // gradients (column i = grad theta_i on its 4 vertices): the vertex part G M G^T as one
  // element matrix, and each psi's column (G M[:, psi] over the vertices, M over the psi) alone,
  // since a psi is one component of its block and the block's other entries are zero.
  // Scratch sized for the largest element and reused: no allocation per element.
  std::size_t gm_size = 0, h_size = 0;
  for (const Element& e : m_elements) {
    const std::size_t rows = 3 * e.vertices.size();
    gm_size = std::max(gm_size, rows * (e.theta.size() + e.psi.size()));
    h_size = std::max(h_size, rows * rows);
  }
  std::vector<double> gm_buffer(gm_size), h_buffer(h_size);
  // Each element's vertex blocks, then its slopes' columns (add_column) and slope-slope entries
  // in the order the loop below adds them.
  auto slope_column = [&](const Element& e, int j) {
    return 3 * (m_first_block + e.blocks[e.psi_at[j].first]) + e.psi_at[j].second;
  };
  if (m_slots.stale(*hessian)) {
    m_slots.reset(*hessian);
    std::vector<int> positions;
    for (const Element& e : m_elements) {
      positions.clear();
      const int np = static_cast<int>(e.psi.size());
      for (int j = 0; j < np; ++j) {
        const int col = slope_column(e, j);
        for (int v : e.vertices) positions.push_back(hessian->position(3 * v, col));
        for (int i = 0; i < np; ++i)
          if (const int row = slope_column(e, i); row <= col)
            positions.push_back(hessian->position(row, col));
      }
      m_slots.add(*hessian, e.vertices.data(), static_cast<int>(e.vertices.size()), positions);
    }
  }
  for (std::size_t ei = 0; ei < m_elements.size(); ++ei) {
    const Element& e = m_elements[ei];
    const int nt = static_cast<int>(e.theta.size()), np = static_cast<int>(e.psi.size());
    const int nv = static_cast<int>(e.vertices.size());
    const int n = nt + np;
    // Plain loops over column-major scratch (these sizes are too small for Eigen's dynamic
    // kernels to pay): GM = G M[theta rows, :] (3 nv x n), then H = sum_j GM[:, j] g_j^T.
    const int rows = 3 * nv;
    double* GM = gm_buffer.data();
    std::fill(GM, GM + rows * n, 0.0);
    for (int i = 0; i < nt; ++i) {
      const double* g = grads[e.theta[i]].data();
      for (int q = 0; q < 4; ++q)
        for (int k = 0; k < n; ++k) {
          const double m = e.M(i, k);
          double* out = GM + k * rows + 3 * e.local[i][q];
          for (int p = 0; p < 3; ++p) out[p] += g[3 * q + p] * m;
        }
    }
    double* H = h_buffer.data();
    std::fill(H, H + rows * rows, 0.0);
    for (int j = 0; j < nt; ++j) {
      const double* g = grads[e.theta[j]].data();
      const double* gm = GM + j * rows;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 3; ++c) {
          const double gc = g[3 * r + c];
          double* out = H + (3 * e.local[j][r] + c) * rows;
          const int upper = 3 * (e.local[j][r] + 1);  // rows add_element reads (see build_elements)
          for (int row = 0; row < upper; ++row) out[row] += gm[row] * gc;
        }
    }
    hessian->add_element(e.vertices.data(), nv, m_slots.slots(static_cast<int>(ei)), H);
    const int* at = m_slots.positions(static_cast<int>(ei));
    for (int j = 0; j < np; ++j) {
      const int col = slope_column(e, j);
      hessian->add_column(col, e.vertices.data(), nv, at, GM + (nt + j) * rows);
      at += nv;
      for (int i = 0; i < np; ++i)
        if (slope_column(e, i) <= col) hessian->add_at(*at++, e.M(nt + i, nt + j));
    }
  }
  // The unused components of the last auxiliary block: identity (their right-hand side is 0).
  if (m_num_psi % 3 != 0) {
    Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
    for (int c = m_num_psi % 3; c < 3; ++c) I(c, c) = 1;
    const int block = m_first_block + m_num_psi / 3;
    hessian->add_element(&block, 1, I.data());
  }
  if (curvature_term)
    for (int h = 0; h < nh; ++h) {
      if (!used[h] || dE[h] == 0) continue;
      Eigen::Matrix<double, 12, 12> Hh = dE[h] * hesses[h];
      if (m_hessian_kind == BendingHessian::projected) Hh = project_psd(Hh);
      const Eigen::Vector4i v = m_hinges.vertices.row(h);
      hessian->add_element<4>({v[0], v[1], v[2], v[3]}, Hh);
    }
}

}  // namespace papersim::simulation
