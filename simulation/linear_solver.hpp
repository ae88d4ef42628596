#pragma once
/// Sparse Cholesky for the Newton systems. CHOLMOD stays behind this class: no CHOLMOD type
/// appears here. The symbolic analysis (fill-reducing ordering, supernodes) is reused until
/// the sparsity pattern changes.
#include <Eigen/Core>
#include <memory>

#include "simulation/sparse_matrix.hpp"

namespace papersim::simulation {

class LinearSolver {
 public:
  LinearSolver();
  ~LinearSolver();
  LinearSolver(const LinearSolver&) = delete;
  LinearSolver& operator=(const LinearSolver&) = delete;

  /// Factor A (symmetric; upper triangle stored). `pattern_id` names the sparsity pattern:
  /// the symbolic analysis is redone only when it differs from the last call's.
  /// @return false when A is not positive definite (the caller regularises and retries).
  /// @throw NumericError when A holds NaN or inf, or CHOLMOD fails for another reason.
  bool factorize(const BlockSymmetricMatrix& A, long pattern_id);

  /// Solve A x = b with the last factorisation.
  Eigen::VectorXd solve(const Eigen::VectorXd& b);

  /// How often the symbolic analysis ran (for statistics and tests).
  int analyses() const { return m_analyses; }

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  int m_analyses = 0;
};

}  // namespace papersim::simulation
