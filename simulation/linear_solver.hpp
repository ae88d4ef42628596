#pragma once
/// Sparse Cholesky for the Newton systems. CHOLMOD stays behind this class: no CHOLMOD type
/// appears here. The symbolic analysis (fill-reducing ordering, supernodes) is reused until
/// the sparsity pattern changes.
#include <Eigen/Core>
#include <memory>
#include <string>

#include "simulation/sparse_matrix.hpp"
#include "simulation/trace.hpp"

namespace papersim::simulation {

/// The dense kernels the BLAS runs (OpenBLAS's core name, e.g. "SkylakeX"), empty for another
/// BLAS; the kernels are chosen when the first LinearSolver is made (see the .cpp).
std::string blas_kernels();

/// How many OpenMP parallel regions this process has run on their calling thread (the
/// GOMP_parallel of linear_solver.cpp, which replaces libgomp's: see there). A test reads it
/// to see that CHOLMOD's regions come here.
long serial_openmp_regions();

class LinearSolver {
 public:
  /// `trace`: its `solver` topic tells each symbolic analysis.
  explicit LinearSolver(Trace trace = {});
  ~LinearSolver();
  LinearSolver(const LinearSolver&) = delete;
  LinearSolver& operator=(const LinearSolver&) = delete;

  /// Factor A (symmetric; upper triangle stored). `pattern_id` names the sparsity pattern:
  /// the symbolic analysis is redone only when it differs from the last call's.
  /// @return false when A is not positive definite (the caller regularises and retries).
  /// @throw NumericError when A holds NaN or inf, or CHOLMOD fails for another reason.
  bool factorize(const BlockSymmetricMatrix& A, long pattern_id);

  /// Factor a matrix that is positive semi-definite in exact arithmetic (a sum of projected
  /// element Hessians and inertia) whose factorisation round-off may stop: retries with
  /// s + 1e-3 s |A_ii| added to each diagonal entry, s = 1e-10, 1e-9, ..., 1e3. The absolute
  /// part covers the static limit (no inertia); the relative part (from 1e-13 of the entry)
  /// covers entries far apart in size, e.g. a barrier's ~1e22 beside inertia ~0.1, which no
  /// absolute shift reaches.
  /// @return the s used (0: none), or a negative number when even s = 1e3 failed (A shifted)
  double factorize_shifted(BlockSymmetricMatrix& A, long pattern_id);

  /// Solve A x = b with the last factorisation.
  Eigen::VectorXd solve(const Eigen::VectorXd& b);

  /// How often the symbolic analysis ran (for statistics and tests).
  int analyses() const { return m_analyses; }

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  int m_analyses = 0;
  Trace m_trace;
};

}  // namespace papersim::simulation
