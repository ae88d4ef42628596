#pragma once
/// A symmetric sparse matrix over 3D vertex blocks, stored as the upper triangle in compressed
/// columns (the layout CHOLMOD takes with stype = 1), and the assembly of per-element Hessians.
#include <Eigen/Core>
#include <array>
#include <vector>

namespace papersim::simulation {

/// Which vertex pairs couple: built once per topology from every element's vertex list.
class SparsityBuilder {
 public:
  explicit SparsityBuilder(int num_vertices);
  /// Starts from a finished pattern (finish()'s result) and adds to it.
  explicit SparsityBuilder(std::vector<std::vector<int>> upper_neighbours);
  /// Every pair of vertices in `vertices` couples.
  void add_clique(const int* vertices, int count);
  int num_vertices() const { return static_cast<int>(m_neighbours.size()); }
  /// Sorted, unique lower neighbours (i <= j) of every vertex j, itself included.
  std::vector<std::vector<int>> finish();

 private:
  std::vector<std::vector<int>> m_neighbours;
};

/// Upper-triangular CSC matrix of size 3N x 3N with a fixed block pattern.
class BlockSymmetricMatrix {
 public:
  BlockSymmetricMatrix() = default;
  /// `upper_neighbours[j]`: sorted vertices i <= j coupled to j (j included).
  explicit BlockSymmetricMatrix(std::vector<std::vector<int>> upper_neighbours);

  int size() const { return 3 * static_cast<int>(m_neighbours.size()); }
  void set_zero() { std::fill(m_values.begin(), m_values.end(), 0.0); }

  /// Adds a symmetric element Hessian (3n x 3n, rows ordered as `vertices`).
  template <int N>
  void add_element(const std::array<int, N>& vertices,
                   const Eigen::Matrix<double, 3 * N, 3 * N>& hessian) {
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b) add_block(vertices[a], vertices[b], a, b, hessian.data(), 3 * N);
  }
  /// Same for a dynamically sized element (n vertices, column-major 3n x 3n data).
  void add_element(const int* vertices, int n, const double* hessian);
  /// Adds d[i] to the diagonal entry of the first d.size() degrees of freedom (the vertices';
  /// auxiliary unknowns after them are left alone when d is shorter).
  void add_diagonal(const Eigen::VectorXd& d);
  /// The diagonal entries (size()).
  Eigen::VectorXd diagonal() const;

  /// y = A x
  Eigen::VectorXd multiply(const Eigen::VectorXd& x) const;

  const std::vector<int>& column_starts() const { return m_col_start; }
  const std::vector<int>& row_indices() const { return m_rows; }
  std::vector<double>& values() { return m_values; }
  const std::vector<double>& values() const { return m_values; }

 private:
  void add_block(int vi, int vj, int a, int b, const double* h, int ld);
  int block_offset(int i, int j) const;  // position of block row i within column block j
  std::vector<std::vector<int>> m_neighbours;
  std::vector<int> m_col_start;  // 3N + 1
  std::vector<int> m_rows;
  std::vector<double> m_values;
};

}  // namespace papersim::simulation
