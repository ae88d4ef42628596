// The sparse Cholesky wrapper: factorize() succeeds exactly on positive definite matrices, so
// Newton can try the exact Hessian and project it when it is indefinite.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <vector>

#include "simulation/linear_solver.hpp"
#include "simulation/sparse_matrix.hpp"

using namespace papersim::simulation;

namespace {

/// The sum over the edges of an nx x ny grid of vertices of the element [2I -I; -I 2I]
/// (eigenvalues 1 and 3): positive definite with eigenvalues in [1, 12], plus `shift` on the
/// first degree of freedom.
BlockSymmetricMatrix grid(int nx, int ny, double shift) {
  const int n = nx * ny;
  std::vector<std::vector<int>> upper(n);
  std::vector<std::array<int, 2>> edges;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int v = j * nx + i;
      if (i + 1 < nx) edges.push_back({v, v + 1});
      if (j + 1 < ny) edges.push_back({v, v + nx});
      upper[v].push_back(v);
    }
  for (const auto& e : edges) upper[e[1]].push_back(e[0]);
  for (auto& u : upper) std::sort(u.begin(), u.end());
  BlockSymmetricMatrix A(upper);
  Eigen::Matrix<double, 6, 6> element;
  element << 2 * Eigen::Matrix3d::Identity(), -Eigen::Matrix3d::Identity(), -Eigen::Matrix3d::Identity(),
      2 * Eigen::Matrix3d::Identity();
  for (const auto& e : edges) A.add_element<2>(e, element);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(1);
  d[0] = shift;
  A.add_diagonal(d);
  return A;
}

}  // namespace

// Small and large systems alike (CHOLMOD factors the small ones by its simplicial method, the
// large grid by its supernodal one): an indefinite matrix is refused, a definite one is factored
// and solved to round-off. The shift of -20 makes a diagonal entry negative (it is at most 8),
// so the matrix is indefinite; an LDL' factorisation would accept it and give Newton a
// direction that is not one of descent.
TEST(LinearSolver, FactorsExactlyThePositiveDefiniteMatrices) {
  for (int n : {2, 3, 60}) {
    LinearSolver solver;
    const BlockSymmetricMatrix indefinite = grid(n, n == 2 ? 1 : n, -20.0);
    EXPECT_FALSE(solver.factorize(indefinite, 1)) << n << " per side";
    const BlockSymmetricMatrix definite = grid(n, n == 2 ? 1 : n, 0.0);
    ASSERT_TRUE(solver.factorize(definite, 1)) << n << " per side";
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(definite.size(), -1.0, 1.0);
    const Eigen::VectorXd x = solver.solve(b);
    EXPECT_LT((definite.multiply(x) - b).norm(), 1e-12 * b.norm()) << n << " per side";
  }
}
