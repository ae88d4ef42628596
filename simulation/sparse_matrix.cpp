#include "simulation/sparse_matrix.hpp"

#include <cassert>

#include <algorithm>
#include <string>

#include "remesh/errors.hpp"

namespace papersim::simulation {

SparsityBuilder::SparsityBuilder(int num_vertices) : m_neighbours(num_vertices) {
  for (int j = 0; j < num_vertices; ++j) m_neighbours[j].push_back(j);
}

SparsityBuilder::SparsityBuilder(std::vector<std::vector<int>> upper_neighbours)
    : m_neighbours(std::move(upper_neighbours)) {}

void SparsityBuilder::add_clique(const int* vertices, int count) {
  for (int a = 0; a < count; ++a)
    for (int b = 0; b < count; ++b)
      if (vertices[a] < vertices[b]) m_neighbours[vertices[b]].push_back(vertices[a]);
}

std::vector<std::vector<int>> SparsityBuilder::finish() {
  for (auto& n : m_neighbours) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return std::move(m_neighbours);
}

BlockSymmetricMatrix::BlockSymmetricMatrix(std::vector<std::vector<int>> upper_neighbours)
    : m_neighbours(std::move(upper_neighbours)) {
  const int n = static_cast<int>(m_neighbours.size());
  m_col_start.assign(3 * n + 1, 0);
  for (int j = 0; j < n; ++j) {
    const int off_diag = static_cast<int>(m_neighbours[j].size()) - 1;  // blocks i < j
    for (int b = 0; b < 3; ++b) {
      const int c = 3 * j + b;
      m_col_start[c + 1] = m_col_start[c] + 3 * off_diag + b + 1;
    }
  }
  m_rows.resize(m_col_start.back());
  for (int j = 0; j < n; ++j)
    for (int b = 0; b < 3; ++b) {
      int k = m_col_start[3 * j + b];
      for (int i : m_neighbours[j]) {
        const int rows_in_block = i < j ? 3 : b + 1;
        for (int a = 0; a < rows_in_block; ++a) m_rows[k++] = 3 * i + a;
      }
    }
  m_values.assign(m_rows.size(), 0.0);
}

int BlockSymmetricMatrix::block_offset(int i, int j) const {
  const auto& n = m_neighbours[j];
  const auto it = std::lower_bound(n.begin(), n.end(), i);
  PAPERSIM_ASSERT(it != n.end() && *it == i, "element coupling missing from the sparsity pattern");
  return static_cast<int>(it - n.begin());
}

void BlockSymmetricMatrix::add_block(int vi, int vj, int a, int b, const double* h, int ld) {
  // Local block (a, b) sits at rows 3a.., columns 3b.. of the column-major element matrix.
  if (vi < vj) {
    const int pos = 3 * block_offset(vi, vj);
    for (int q = 0; q < 3; ++q) {
      double* col = &m_values[m_col_start[3 * vj + q] + pos];
      for (int p = 0; p < 3; ++p) col[p] += h[(3 * b + q) * ld + 3 * a + p];
    }
  } else if (vi == vj && a == b) {
    const int pos = 3 * block_offset(vi, vj);
    for (int q = 0; q < 3; ++q) {
      double* col = &m_values[m_col_start[3 * vj + q] + pos];
      for (int p = 0; p <= q; ++p) col[p] += h[(3 * b + q) * ld + 3 * a + p];
    }
  }
}

void BlockSymmetricMatrix::add_element(const int* vertices, int n, const double* hessian) {
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) add_block(vertices[a], vertices[b], a, b, hessian, 3 * n);
}

void BlockSymmetricMatrix::add_diagonal(const Eigen::VectorXd& d) {
  assert(d.size() <= size());
  for (int c = 0; c < d.size(); ++c) m_values[m_col_start[c + 1] - 1] += d[c];
}

Eigen::VectorXd BlockSymmetricMatrix::diagonal() const {
  Eigen::VectorXd d(size());
  for (int c = 0; c < size(); ++c) d[c] = m_values[m_col_start[c + 1] - 1];
  return d;
}

Eigen::VectorXd BlockSymmetricMatrix::multiply(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(size());
  for (int c = 0; c < size(); ++c)
    for (int k = m_col_start[c]; k < m_col_start[c + 1]; ++k) {
      const int r = m_rows[k];
      y[r] += m_values[k] * x[c];
      if (r != c) y[c] += m_values[k] * x[r];
    }
  return y;
}

}  // namespace papersim::simulation
