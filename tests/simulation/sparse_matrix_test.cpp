// Assembly into the block matrix: an element's blocks added at places found once (ElementSlots)
// are the sums the searching add_element makes and the dense sum of the elements, and a matrix of
// another layout is told apart.
#include "simulation/sparse_matrix.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "simulation/linear_solver.hpp"

using namespace papersim::simulation;

namespace {

/// Elements of 1-12 distinct vertices out of 40, in random order.
std::vector<std::vector<int>> random_elements(int count, std::mt19937& rng) {
  std::vector<std::vector<int>> elements;
  std::vector<int> all(40);
  for (int i = 0; i < 40; ++i) all[i] = i;
  for (int e = 0; e < count; ++e) {
    std::shuffle(all.begin(), all.end(), rng);
    const int n = 1 + static_cast<int>(rng() % 12);
    elements.emplace_back(all.begin(), all.begin() + n);
  }
  return elements;
}

Eigen::MatrixXd random_symmetric(int size, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd A(size, size);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) A(i, j) = u(rng);
  return A + A.transpose();
}

/// Adds every element's Hessian to `m`: with slots found for m's layout, or by searching.
void assemble(BlockSymmetricMatrix& m, const std::vector<std::vector<int>>& elements,
              const std::vector<Eigen::MatrixXd>& hessians, ElementSlots* slots) {
  m.set_zero();
  if (slots && slots->stale(m)) {
    slots->reset(m);
    for (const auto& e : elements) slots->add(m, e.data(), static_cast<int>(e.size()));
  }
  for (std::size_t k = 0; k < elements.size(); ++k) {
    const int n = static_cast<int>(elements[k].size());
    if (slots)
      m.add_element(elements[k].data(), n, slots->slots(static_cast<int>(k)), hessians[k].data());
    else
      m.add_element(elements[k].data(), n, hessians[k].data());
  }
}

}  // namespace

TEST(ElementSlots, AddWhatTheSearchAddsAndAreFoundAgainForANewLayout) {
  std::mt19937 rng(7);
  const auto elements = random_elements(60, rng);
  std::vector<Eigen::MatrixXd> hessians;
  for (const auto& e : elements)
    hessians.push_back(random_symmetric(3 * static_cast<int>(e.size()), rng));
  SparsityBuilder builder(40);
  for (const auto& e : elements) builder.add_clique(e.data(), static_cast<int>(e.size()));
  const BlockPattern pattern = builder.finish();

  BlockSymmetricMatrix searched(pattern), slotted(pattern);
  EXPECT_NE(searched.layout(), slotted.layout());  // each construction is a layout of its own
  ElementSlots slots;
  assemble(searched, elements, hessians, nullptr);
  assemble(slotted, elements, hessians, &slots);
  ASSERT_EQ(searched.values().size(), slotted.values().size());
  for (std::size_t k = 0; k < searched.values().size(); ++k)
    ASSERT_EQ(searched.values()[k], slotted.values()[k])
        << "entry " << k;  // the same sums, bit for bit
  // And they are the elements' sum: against the dense matrix, column by column.
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(120, 120);
  for (std::size_t k = 0; k < elements.size(); ++k)
    for (std::size_t a = 0; a < elements[k].size(); ++a)
      for (std::size_t b = 0; b < elements[k].size(); ++b)
        dense.block<3, 3>(3 * elements[k][a], 3 * elements[k][b]) +=
            hessians[k].block<3, 3>(3 * static_cast<int>(a), 3 * static_cast<int>(b));
  for (int c = 0; c < 120; ++c) {
    const Eigen::VectorXd e = Eigen::VectorXd::Unit(120, c);
    ASSERT_LT((slotted.multiply(e) - dense.col(c)).norm(), 1e-12 * (1 + dense.col(c).norm()))
        << "column " << c;
  }

  // A copy has the layout: the slots hold on it.
  BlockSymmetricMatrix copy = slotted;
  EXPECT_FALSE(slots.stale(copy));
  // Contact couples two vertices the elements did not: blocks move, so the old places are wrong
  // and the slots are found again.
  SparsityBuilder more(pattern);
  int pair[2] = {-1, -1};
  for (int i = 0; i < 40 && pair[0] < 0; ++i)
    for (int j = i + 1; j < 40; ++j)
      if (!std::binary_search(pattern.neighbours[j].begin(), pattern.neighbours[j].end(), i)) {
        pair[0] = i, pair[1] = j;
        break;
      }
  ASSERT_GE(pair[0], 0) << "the random elements couple every pair";
  more.add_clique(pair, 2);
  BlockSymmetricMatrix wider(more.finish()), wider_searched(wider);
  EXPECT_TRUE(slots.stale(wider));
  const std::vector<int> before(slots.slots(0), slots.slots(static_cast<int>(elements.size()) - 1));
  assemble(wider, elements, hessians, &slots);
  assemble(wider_searched, elements, hessians, nullptr);
  for (std::size_t k = 0; k < wider.values().size(); ++k)
    ASSERT_EQ(wider.values()[k], wider_searched.values()[k]);
  const std::vector<int> after(slots.slots(0), slots.slots(static_cast<int>(elements.size()) - 1));
  EXPECT_NE(before, after) << "the new coupling moves some block of column " << pair[1];
  // Both layouts' matrices hold the same element sums (the new coupling's block stays zero).
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(120, -1, 1);
  EXPECT_LT((wider.multiply(x) - searched.multiply(x)).norm(), 1e-12 * searched.multiply(x).norm());
}

TEST(ElementSlots, PositionsFoundOnceAddTheColumnsAndEntriesTheSearchAdds) {
  // Blocks 0-29 are vertices, 30-39 hold auxiliary unknowns, one component each (as the Morley
  // edge slopes): each element couples some vertices with some auxiliary unknowns, and adds
  // the unknowns' columns over its vertices and their entries among themselves one by one.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  struct Element {
    std::vector<int> vertices;
    std::vector<int> columns;  // scalar columns of auxiliary unknowns
  };
  std::vector<Element> elements;
  SparsityBuilder builder(40, 30);
  for (int k = 0; k < 50; ++k) {
    Element e;
    std::vector<int> all(30);
    for (int i = 0; i < 30; ++i) all[i] = i;
    std::shuffle(all.begin(), all.end(), rng);
    e.vertices.assign(all.begin(), all.begin() + 1 + static_cast<int>(rng() % 6));
    for (int c = 0, n = 1 + static_cast<int>(rng() % 4); c < n; ++c)
      e.columns.push_back(90 + static_cast<int>(rng() % 30));
    std::vector<int> blocks = e.vertices;
    std::vector<unsigned char> components(blocks.size(), 7);
    for (int c : e.columns) {
      blocks.push_back(c / 3);
      components.push_back(static_cast<unsigned char>(1u << (c % 3)));
    }
    builder.add_clique(blocks.data(), components.data(), static_cast<int>(blocks.size()));
    elements.push_back(e);
  }
  const BlockPattern pattern = builder.finish();
  // Values to add: per element, each column over its vertices, then each entry row <= column.
  std::vector<std::vector<double>> column_values, entry_values;
  for (const Element& e : elements) {
    column_values.emplace_back(3 * e.vertices.size() * e.columns.size());
    for (double& v : column_values.back()) v = u(rng);
    entry_values.emplace_back(e.columns.size() * e.columns.size());
    for (double& v : entry_values.back()) v = u(rng);
  }
  auto add = [&](BlockSymmetricMatrix& m, ElementSlots* slots) {
    m.set_zero();
    if (slots) {
      slots->reset(m);
      std::vector<int> positions;
      for (const Element& e : elements) {
        positions.clear();
        for (int col : e.columns) {
          for (int v : e.vertices) positions.push_back(m.position(3 * v, col));
          for (int row : e.columns)
            if (row <= col) positions.push_back(m.position(row, col));
        }
        slots->add(m, e.vertices.data(), static_cast<int>(e.vertices.size()), positions);
      }
    }
    for (std::size_t k = 0; k < elements.size(); ++k) {
      const Element& e = elements[k];
      const int nv = static_cast<int>(e.vertices.size());
      const int* at = slots ? slots->positions(static_cast<int>(k)) : nullptr;
      for (std::size_t j = 0; j < e.columns.size(); ++j) {
        const int col = e.columns[j];
        const double* values = column_values[k].data() + 3 * nv * j;
        if (at) {
          m.add_column(col, e.vertices.data(), nv, at, values);
          at += nv;
        } else {
          m.add_column(col, e.vertices.data(), nv, values);
        }
        for (std::size_t i = 0; i < e.columns.size(); ++i) {
          if (e.columns[i] > col) continue;
          const double v = entry_values[k][i + e.columns.size() * j];
          if (at)
            m.add_at(*at++, v);
          else
            m.add_entry(e.columns[i], col, v);
        }
      }
    }
  };
  BlockSymmetricMatrix searched(pattern), slotted(pattern);
  ElementSlots slots;
  add(searched, nullptr);
  add(slotted, &slots);
  for (std::size_t k = 0; k < searched.values().size(); ++k)
    ASSERT_EQ(searched.values()[k], slotted.values()[k])
        << "entry " << k;  // the same sums, bit for bit
  // And they are the sums asked for: against a dense matrix of the upper triangle.
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(120, 120);
  for (std::size_t k = 0; k < elements.size(); ++k) {
    const Element& e = elements[k];
    const int nv = static_cast<int>(e.vertices.size());
    for (std::size_t j = 0; j < e.columns.size(); ++j) {
      for (int a = 0; a < nv; ++a)
        for (int p = 0; p < 3; ++p)
          dense(3 * e.vertices[a] + p, e.columns[j]) += column_values[k][3 * nv * j + 3 * a + p];
      for (std::size_t i = 0; i < e.columns.size(); ++i)
        if (e.columns[i] <= e.columns[j])
          dense(e.columns[i], e.columns[j]) += entry_values[k][i + e.columns.size() * j];
    }
  }
  const auto& starts = slotted.column_starts();
  const auto& rows = slotted.row_indices();
  double checked = 0;
  for (int c = 0; c < 120; ++c)
    for (int k = starts[c]; k < starts[c + 1]; ++k) {
      ASSERT_NEAR(slotted.values()[k], dense(rows[k], c), 1e-12)
          << "entry (" << rows[k] << ", " << c << ")";
      checked += std::abs(dense(rows[k], c));
    }
  EXPECT_NEAR(checked, dense.cwiseAbs().sum(), 1e-9);  // no sum fell outside the stored entries
  EXPECT_GT(checked, 0);
}

// With the invariant checks on (Debug, or PAPERSIM_ASSERTS as in the test build), the matrix's
// and the solver's public entries refuse a size or an index that does not fit, naming the entry,
// instead of reading or writing past their arrays.
TEST(InvariantChecks, TheMatrixAndTheSolverRefuseSizesAndIndicesThatDoNotFit) {
#ifndef PAPERSIM_ENABLE_ASSERTS
  GTEST_SKIP() << "built without PAPERSIM_ASSERTS";
#else
  BlockSymmetricMatrix m({{0}, {0, 1}});  // two blocks, coupled
  const auto refused = [](auto&& call, const std::string& entry) {
    try {
      call();
      ADD_FAILURE() << entry << " accepted a bad argument";
    } catch (const std::logic_error& e) {
      EXPECT_NE(std::string(e.what()).find(entry), std::string::npos) << e.what();
    }
  };
  refused([&] { m.multiply(Eigen::VectorXd::Zero(5)); }, "BlockSymmetricMatrix::multiply");
  refused([&] { m.add_diagonal(Eigen::VectorXd::Ones(7)); }, "BlockSymmetricMatrix::add_diagonal");
  const int outside[2] = {0, 2};
  std::vector<int> slots;
  refused([&] { m.find_slots(outside, 2, slots); }, "block index out of range");
  refused([&] { m.add_entry(4, 1, 1.0); }, "BlockSymmetricMatrix::add_entry");
  EXPECT_EQ(m.multiply(Eigen::VectorXd::Ones(6)).size(), 6);  // the right size passes
  LinearSolver solver;
  refused([&] { solver.solve(Eigen::VectorXd::Ones(6)); }, "LinearSolver::solve");
  m.add_diagonal(Eigen::VectorXd::Ones(6));
  ASSERT_TRUE(solver.factorize(m, 0));
  refused([&] { solver.solve(Eigen::VectorXd::Ones(3)); }, "LinearSolver::solve");
  EXPECT_TRUE(solver.solve(Eigen::VectorXd::Ones(6)).isApprox(Eigen::VectorXd::Ones(6)));
#endif
}
