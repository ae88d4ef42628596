#pragma once
/// A symmetric sparse matrix over 3D vertex blocks, stored as the upper triangle in compressed
/// columns (the layout CHOLMOD takes with stype = 1), and the assembly of per-element Hessians.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace papersim::simulation {

/// Which blocks couple, and which scalar entries of each coupling can be non-zero. A vertex
/// couples in all three of its components; an auxiliary unknown is one component of its block
/// (EnergyTerm::auxiliary_blocks packs three to a block), and stating that keeps the three
/// unrelated unknowns of a block from being coupled to each other's neighbours in the
/// factorisation (docs/performance.md, "The edge slopes in the factorisation").
struct BlockPattern {
  /// Sorted, unique upper neighbours i <= j of every block j, itself included.
  std::vector<std::vector<int>> neighbours;
  /// Per neighbour i of j: bit 3 q + p set when entry (row p of block i, column q of block j) can
  /// be non-zero. Every diagonal entry is set.
  std::vector<std::vector<std::uint16_t>> masks;
};

/// Builds a BlockPattern from every element's blocks: once per topology, and again from that
/// start when contact adds couplings.
class SparsityBuilder {
 public:
  /// Blocks from `first_auxiliary` on hold auxiliary unknowns: their diagonal blocks start with
  /// the diagonal entries only (the cliques add the rest); every other block's whole.
  explicit SparsityBuilder(int num_blocks, int first_auxiliary = -1);
  /// Starts from a finished pattern (finish()'s result) and adds to it.
  explicit SparsityBuilder(BlockPattern pattern);
  /// Every pair of blocks in `blocks` couples in all components.
  void add_clique(const int* blocks, int count);
  /// Every pair of members couples in their components: member k is component set
  /// `components[k]` (bit c: component c) of block `blocks[k]`; a block may appear more than once.
  void add_clique(const int* blocks, const unsigned char* components, int count);
  int num_blocks() const { return static_cast<int>(m_neighbours.size()); }
  BlockPattern finish();

 private:
  void couple(int i, unsigned ci, int j, unsigned cj);
  std::vector<std::vector<std::pair<int, std::uint16_t>>> m_neighbours;
};

/// Upper-triangular CSC matrix of size 3N x 3N with a fixed block pattern. Every entry of a
/// coupled block is stored (so assembly indexes whole blocks); the structure, the entries the
/// pattern's masks allow, is what the factorisation takes.
class BlockSymmetricMatrix {
 public:
  BlockSymmetricMatrix() = default;
  explicit BlockSymmetricMatrix(const BlockPattern& pattern);
  /// Every entry of every coupled block in the structure (`upper_neighbours[j]`: sorted blocks
  /// i <= j coupled to j, j included).
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
  /// Same, with the blocks' places found beforehand by find_slots on this layout: the same sums
  /// without searching the pattern (ElementSlots keeps them for a term's elements).
  void add_element(const int* vertices, int n, const int* slots, const double* hessian);
  /// Appends to `slots` the place of each block add_element adds for these vertices, (a, b) with
  /// vertices[a] < vertices[b] or a == b, b outer and a inner.
  void find_slots(const int* vertices, int n, std::vector<int>& slots) const;
  /// Which layout this is (where each coupled block is stored): a copy keeps it, a matrix built
  /// from a pattern gets a new one, so slots found on a matrix hold on any with its layout.
  std::uint64_t layout() const { return m_layout; }
  /// Adds values[3 k + p] to entry (3 blocks[k] + p, column) for k < n: part of one column, for
  /// an element whose other columns are zero there (every blocks[k] <= column / 3, so the
  /// entries are in the stored upper triangle).
  void add_column(int column, const int* blocks, int n, const double* values);
  /// Same, with positions[k] = position(3 blocks[k], column) found beforehand: the same sums
  /// without searching the pattern.
  void add_column(int column, const int* blocks, int n, const int* positions, const double* values);
  /// Adds v to entry (row, column), row <= column.
  void add_entry(int row, int column, double v);
  /// Where entry (row, column), row <= column, of a coupled block is stored in values(): slots
  /// for add_column and add_at that hold on any matrix of this layout.
  int position(int row, int column) const;
  /// Adds v to values()[position].
  void add_at(int position, double v) { m_values[position] += v; }
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

  /// The structure in compressed columns: column starts (size() + 1), row indices, and each
  /// entry's position in values(). Entries outside it must stay 0 (in_structure()).
  const std::vector<int>& structure_starts() const { return m_structure_start; }
  const std::vector<int>& structure_rows() const { return m_structure_rows; }
  const std::vector<int>& structure_positions() const { return m_structure_at; }
  /// Per entry of values(): whether the structure holds it.
  const std::vector<char>& in_structure() const { return m_in_structure; }
  /// The positions in values() outside the structure.
  const std::vector<int>& outside_positions() const { return m_outside; }

 private:
  void add_block(int vi, int vj, int a, int b, const double* h, int ld);
  int block_offset(int i, int j) const;  // position of block row i within column block j
  std::vector<std::vector<int>> m_neighbours;
  std::vector<int> m_col_start;  // 3N + 1
  std::vector<int> m_rows;
  std::vector<double> m_values;
  std::vector<int> m_structure_start, m_structure_rows, m_structure_at;
  std::vector<char> m_in_structure;
  std::vector<int> m_outside;
  std::uint64_t m_layout = 0;  // 0: no blocks (default-constructed)
};

/// One energy term's elements' places in a matrix (BlockSymmetricMatrix::find_slots), found
/// again whenever the term meets a matrix of another layout. The term's elements must not change
/// while it lives (a new mesh builds new terms).
class ElementSlots {
 public:
  /// Whether the slots must be found again for `matrix`: then reset(matrix) and add() every
  /// element in the order slots(e) will ask for them.
  bool stale(const BlockSymmetricMatrix& matrix) const { return matrix.layout() != m_layout; }
  void reset(const BlockSymmetricMatrix& matrix) {
    m_layout = matrix.layout();
    m_slots.clear();
    m_start.assign(1, 0);
    m_positions.clear();
  }
  void add(const BlockSymmetricMatrix& matrix, const int* vertices, int n) {
    add(matrix, vertices, n, {});
  }
  /// Same, and keeps `positions` (BlockSymmetricMatrix::position) of the entries the element adds
  /// column by column or one by one, for positions(element).
  void add(const BlockSymmetricMatrix& matrix, const int* vertices, int n,
           const std::vector<int>& positions) {
    matrix.find_slots(vertices, n, m_slots);
    m_positions.push_back(static_cast<int>(m_slots.size()));
    m_slots.insert(m_slots.end(), positions.begin(), positions.end());
    m_start.push_back(static_cast<int>(m_slots.size()));
  }
  const int* slots(int element) const { return m_slots.data() + m_start[element]; }
  const int* positions(int element) const { return m_slots.data() + m_positions[element]; }

 private:
  std::uint64_t m_layout = ~std::uint64_t{0};  // none: a matrix of any layout, 0 too, is new to it
  std::vector<int> m_slots, m_start, m_positions;
};

}  // namespace papersim::simulation
