#include "simulation/sparse_matrix.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <string>

#include "common/assert.hpp"

namespace papersim::simulation {

namespace {
constexpr std::uint16_t DIAGONAL = 0x111;  // bits 0, 4, 8: entries (0, 0), (1, 1), (2, 2)
constexpr std::uint16_t WHOLE = 0x1FF;
constexpr unsigned ALL_COMPONENTS = 7;
std::atomic<std::uint64_t> g_layouts{0};  // layouts made so far (BlockSymmetricMatrix::layout)
}  // namespace

SparsityBuilder::SparsityBuilder(int num_blocks, int first_auxiliary) : m_neighbours(num_blocks) {
  if (first_auxiliary < 0) first_auxiliary = num_blocks;
  for (int j = 0; j < num_blocks; ++j)
    m_neighbours[j].emplace_back(j, j < first_auxiliary ? WHOLE : DIAGONAL);
}

SparsityBuilder::SparsityBuilder(BlockPattern pattern) : m_neighbours(pattern.neighbours.size()) {
  for (std::size_t j = 0; j < m_neighbours.size(); ++j)
    for (std::size_t k = 0; k < pattern.neighbours[j].size(); ++k)
      m_neighbours[j].emplace_back(pattern.neighbours[j][k], pattern.masks[j][k]);
}

void SparsityBuilder::couple(int i, unsigned ci, int j, unsigned cj) {
  // Rows are the lower block's components, columns the higher one's; in a diagonal block both
  // orders, since only its upper triangle is stored and either may be it.
  if (i > j) std::swap(i, j), std::swap(ci, cj);
  std::uint16_t mask = 0;
  for (unsigned p = 0; p < 3; ++p)
    for (unsigned q = 0; q < 3; ++q)
      if ((ci >> p & 1) && (cj >> q & 1)) {
        mask |= static_cast<std::uint16_t>(1u << (3 * q + p));
        if (i == j) mask |= static_cast<std::uint16_t>(1u << (3 * p + q));
      }
  m_neighbours[j].emplace_back(i, mask);
}

void SparsityBuilder::add_clique(const int* blocks, int count) {
  for (int a = 0; a < count; ++a)
    for (int b = a; b < count; ++b) couple(blocks[a], ALL_COMPONENTS, blocks[b], ALL_COMPONENTS);
}

void SparsityBuilder::add_clique(const int* blocks, const unsigned char* components, int count) {
  for (int a = 0; a < count; ++a)
    for (int b = a; b < count; ++b) couple(blocks[a], components[a], blocks[b], components[b]);
}

BlockPattern SparsityBuilder::finish() {
  BlockPattern out;
  out.neighbours.resize(m_neighbours.size());
  out.masks.resize(m_neighbours.size());
  for (std::size_t j = 0; j < m_neighbours.size(); ++j) {
    auto& n = m_neighbours[j];
    std::sort(n.begin(), n.end());
    for (const auto& [i, mask] : n)
      if (!out.neighbours[j].empty() && out.neighbours[j].back() == i)
        out.masks[j].back() |= mask;
      else
        out.neighbours[j].push_back(i), out.masks[j].push_back(mask);
    n = {};
  }
  return out;
}

BlockSymmetricMatrix::BlockSymmetricMatrix(const BlockPattern& pattern)
    : m_neighbours(pattern.neighbours), m_layout(++g_layouts) {
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
  m_in_structure.assign(m_rows.size(), 0);
  m_structure_start.assign(3 * n + 1, 0);
  m_structure_rows.clear();
  m_structure_at.clear();
  m_outside.clear();
  for (int j = 0; j < n; ++j)
    for (int b = 0; b < 3; ++b) {
      int k = m_col_start[3 * j + b];
      for (std::size_t t = 0; t < m_neighbours[j].size(); ++t) {
        const int i = m_neighbours[j][t];
        const int rows_in_block = i < j ? 3 : b + 1;
        for (int a = 0; a < rows_in_block; ++a, ++k) {
          m_rows[k] = 3 * i + a;
          if (pattern.masks[j][t] >> (3 * b + a) & 1) {
            m_in_structure[k] = 1;
            m_structure_rows.push_back(3 * i + a);
            m_structure_at.push_back(k);
          } else {
            m_outside.push_back(k);
          }
        }
      }
      m_structure_start[3 * j + b + 1] = static_cast<int>(m_structure_rows.size());
    }
  m_values.assign(m_rows.size(), 0.0);
}

namespace {
BlockPattern full_pattern(std::vector<std::vector<int>> neighbours) {
  BlockPattern p;
  p.masks.resize(neighbours.size());
  for (std::size_t j = 0; j < neighbours.size(); ++j)
    p.masks[j].assign(neighbours[j].size(), WHOLE);
  p.neighbours = std::move(neighbours);
  return p;
}
}  // namespace

BlockSymmetricMatrix::BlockSymmetricMatrix(std::vector<std::vector<int>> upper_neighbours)
    : BlockSymmetricMatrix(full_pattern(std::move(upper_neighbours))) {}

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
  std::vector<int> slots;
  find_slots(vertices, n, slots);
  add_element(vertices, n, slots.data(), hessian);
}

void BlockSymmetricMatrix::find_slots(const int* vertices, int n, std::vector<int>& slots) const {
  for (int a = 0; a < n; ++a)
    PAPERSIM_ASSERT(vertices[a] >= 0 && 3 * vertices[a] < size(),
                    "BlockSymmetricMatrix: a block index out of range");
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
      if (vertices[a] < vertices[b] || a == b)
        slots.push_back(3 * block_offset(vertices[a], vertices[b]));
}

void BlockSymmetricMatrix::add_element(const int* vertices, int n, const int* slots,
                                       const double* hessian) {
  // As add_block, block by block, with the places from `slots` (find_slots's order).
  const int ld = 3 * n;
  for (int b = 0; b < n; ++b) {
    const int vj = vertices[b];
    double* col[3];
    for (int q = 0; q < 3; ++q) col[q] = &m_values[m_col_start[3 * vj + q]];
    for (int a = 0; a < n; ++a) {
      const int vi = vertices[a];
      if (vi < vj) {
        const int pos = *slots++;
        for (int q = 0; q < 3; ++q)
          for (int p = 0; p < 3; ++p) col[q][pos + p] += hessian[(3 * b + q) * ld + 3 * a + p];
      } else if (a == b) {
        const int pos = *slots++;
        for (int q = 0; q < 3; ++q)
          for (int p = 0; p <= q; ++p) col[q][pos + p] += hessian[(3 * b + q) * ld + 3 * a + p];
      }
    }
  }
}

void BlockSymmetricMatrix::add_column(int column, const int* blocks, int n, const double* values) {
  for (int k = 0; k < n; ++k) {
    PAPERSIM_ASSERT(blocks[k] <= column / 3,
                    "BlockSymmetricMatrix::add_column: an entry below the diagonal");
    const int position = this->position(3 * blocks[k], column);
    add_column(column, blocks + k, 1, &position, values + 3 * k);
  }
}

void BlockSymmetricMatrix::add_column(int column, const int* blocks, int n, const int* positions,
                                      const double* values) {
  const int j = column / 3;
  for (int k = 0; k < n; ++k) {
    double* entry = &m_values[positions[k]];
    const int rows = blocks[k] == j ? column % 3 + 1 : 3;  // the upper triangle of a diagonal block
    for (int p = 0; p < rows; ++p) entry[p] += values[3 * k + p];
  }
}

void BlockSymmetricMatrix::add_entry(int row, int column, double v) {
  add_at(position(row, column), v);
}

int BlockSymmetricMatrix::position(int row, int column) const {
  PAPERSIM_ASSERT(row <= column, "BlockSymmetricMatrix::add_entry: an entry below the diagonal");
  return m_col_start[column] + 3 * block_offset(row / 3, column / 3) + row % 3;
}

void BlockSymmetricMatrix::add_diagonal(const Eigen::VectorXd& d) {
  PAPERSIM_ASSERT(d.size() <= size(), "BlockSymmetricMatrix::add_diagonal: longer than the matrix");
  for (int c = 0; c < d.size(); ++c) m_values[m_col_start[c + 1] - 1] += d[c];
}

Eigen::VectorXd BlockSymmetricMatrix::diagonal() const {
  Eigen::VectorXd d(size());
  for (int c = 0; c < size(); ++c) d[c] = m_values[m_col_start[c + 1] - 1];
  return d;
}

Eigen::VectorXd BlockSymmetricMatrix::multiply(const Eigen::VectorXd& x) const {
  PAPERSIM_ASSERT(x.size() == size(),
                  "BlockSymmetricMatrix::multiply: x is not of the matrix's size");
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
