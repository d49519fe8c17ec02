// Takahashi selected inversion against the dense inverse on random sparse SPD matrices.

#include "core/selected_inverse.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "tests/test_util.h"

namespace foresight {
namespace {

using Sparse = Eigen::SparseMatrix<double>;

/// Lower triangle of a dense symmetric matrix, as a compressed sparse matrix (zeros dropped).
Sparse LowerOf(const Eigen::MatrixXd& a) {
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < a.cols(); ++j)
    for (int i = j; i < a.rows(); ++i)
      if (a(i, j) != 0) t.emplace_back(i, j, a(i, j));
  Sparse s(a.rows(), a.cols());
  s.setFromTriplets(t.begin(), t.end());
  s.makeCompressed();
  return s;
}

/// Random sparse SPD: symmetric random couplings with probability `density`, diagonally dominant.
Eigen::MatrixXd RandomSparseSpd(int n, double density, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), coin(0, 1);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = j + 1; i < n; ++i)
      if (coin(rng) < density) a(i, j) = a(j, i) = u(rng);
  for (int i = 0; i < n; ++i) a(i, i) = a.row(i).cwiseAbs().sum() + 0.1 + coin(rng);
  return a;
}

/// 2-D grid Laplacian (4-neighbour) on nx x ny nodes plus `shift` on the diagonal.
Eigen::MatrixXd GridLaplacian(int nx, int ny, double shift) {
  const int n = nx * ny;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const int i = y * nx + x;
      a(i, i) = shift;
      const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto& q : nb) {
        if (q[0] < 0 || q[0] >= nx || q[1] < 0 || q[1] >= ny) continue;
        a(i, i) += 1;
        a(i, q[1] * nx + q[0]) = -1;
      }
    }
  }
  return a;
}

/// SPD matrix coupling every pair of nodes of an nx x ny grid within `reach` cells (Chebyshev),
/// with random weights, diagonally dominant by `shift`.
Eigen::MatrixXd WideGrid(int nx, int ny, int reach, double shift) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(nx * 100 + ny * 10 + reach));
  std::uniform_real_distribution<double> u(0.1, 1.0);
  const int n = nx * ny;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (std::abs(i % nx - j % nx) <= reach && std::abs(i / nx - j / nx) <= reach)
        a(i, j) = a(j, i) = -u(rng);
  for (int i = 0; i < n; ++i) a(i, i) = a.row(i).cwiseAbs().sum() + shift;
  return a;
}

/// Every entry of the selected inverse equals the dense inverse, the pattern covers the diagonal
/// and the pattern of A, and QuadraticForm matches phi' Sigma phi.
void CheckAgainstDense(const Eigen::MatrixXd& a) {
  const Sparse lower = LowerOf(a);
  const SparseCholesky llt(lower);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const SelectedInverse s = ComputeSelectedInverse(llt);
  const Eigen::MatrixXd inv = a.inverse();
  const double scale = inv.cwiseAbs().maxCoeff();
  ASSERT_EQ(s.lower.rows(), a.rows());
  for (int j = 0; j < s.lower.outerSize(); ++j) {
    for (Sparse::InnerIterator it(s.lower, j); it; ++it) {
      EXPECT_GE(it.row(), it.col());
      EXPECT_NEAR(it.value(), inv(it.row(), it.col()), 1e-12 * scale)
          << "(" << it.row() << ", " << it.col() << ")";
    }
  }
  for (int j = 0; j < a.cols(); ++j) {
    for (int i = 0; i < a.rows(); ++i) {
      if (a(i, j) == 0 && i != j) continue;
      EXPECT_NEAR(s.Entry(i, j), inv(i, j), 1e-12 * scale) << "(" << i << ", " << j << ")";
    }
  }
  // log det A of the reusable inverter against the dense LLT.
  SelectedInverter inverter;
  inverter.Compute(llt);
  const Eigen::LLT<Eigen::MatrixXd> dense(a);
  const double log_det = 2 * dense.matrixLLT().diagonal().array().log().sum();
  EXPECT_NEAR(inverter.LogDetA(), log_det, 1e-10 * std::max(1.0, std::abs(log_det)));
  for (int i = 0; i < a.rows(); ++i) EXPECT_NEAR(inverter.Diagonal(i), inv(i, i), 1e-12 * scale);
  // phi on a clique of A's pattern: the neighbours of node 0 (and node 0 itself).
  std::vector<int> idx;
  std::vector<double> val;
  for (int i = 0; i < a.rows(); ++i) {
    if (i == 0 || a(i, 0) != 0) {
      idx.push_back(i);
      val.push_back(0.3 + 0.1 * i);
    }
  }
  if (idx.size() > 2) idx.resize(2), val.resize(2);  // pairs (0, i) are in A's pattern
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(a.rows());
  for (std::size_t k = 0; k < idx.size(); ++k) phi[idx[k]] = val[k];
  EXPECT_NEAR(QuadraticForm(s, idx.data(), val.data(), static_cast<int>(idx.size())),
              phi.dot(inv * phi), 1e-12 * scale);
}

TEST(SelectedInverse, RandomSparseSpdMatchesDenseInverse) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed)
    CheckAgainstDense(RandomSparseSpd(40, 0.08, seed));
}

TEST(SelectedInverse, GridLaplacianMatchesDenseInverse) {
  CheckAgainstDense(GridLaplacian(9, 7, 0.05));
}

// Supernodes of every size: a dense matrix (one supernode), a wide-stencil grid (the coupled
// BHM's precision: every pair within 2 cells), a banded matrix, and a reused inverter on a second
// factor of the same pattern (the EM loop) and of another pattern.
TEST(SelectedInverse, SupernodalBlocksMatchDenseInverse) {
  CheckAgainstDense(RandomSparseSpd(25, 1.0, 7));
  CheckAgainstDense(WideGrid(12, 9, 2, 0.1));
  CheckAgainstDense(WideGrid(30, 1, 3, 0.01));  // a band: one chain of supernodes
}

TEST(SelectedInverse, AReusedInverterFollowsNewValuesAndNewPatterns) {
  SelectedInverter inverter;
  for (const Eigen::MatrixXd& a : {WideGrid(8, 6, 2, 0.1), WideGrid(8, 6, 2, 3.0),
                                   RandomSparseSpd(30, 0.1, 3), WideGrid(8, 6, 2, 0.1)}) {
    const SparseCholesky llt(LowerOf(a));
    ASSERT_EQ(llt.info(), Eigen::Success);
    inverter.Compute(llt);
    const Eigen::MatrixXd inv = a.inverse();
    const double scale = inv.cwiseAbs().maxCoeff();
    for (int j = 0; j < a.cols(); ++j) {
      for (int i = j; i < a.rows(); ++i) {
        if (a(i, j) == 0 && i != j) continue;
        const std::ptrdiff_t slot = inverter.Slot(i, j);
        ASSERT_GE(slot, 0) << "(" << i << ", " << j << ")";
        EXPECT_NEAR(inverter.values()[slot], inv(i, j), 1e-12 * scale)
            << "(" << i << ", " << j << ")";
      }
    }
  }
}

TEST(SelectedInverse, OneByOne) {
  Eigen::MatrixXd a(1, 1);
  a(0, 0) = 4.0;
  CheckAgainstDense(a);
  const SparseCholesky llt(LowerOf(a));
  EXPECT_DOUBLE_EQ(ComputeSelectedInverse(llt).Entry(0, 0), 0.25);
}

TEST(SelectedInverse, MissingEntryIsAnErrorNamingIt) {
  // A diagonal matrix: L is diagonal, so (3, 1) is not in the pattern.
  const Eigen::MatrixXd a = Eigen::VectorXd::LinSpaced(5, 1, 5).asDiagonal();
  const SparseCholesky llt(LowerOf(a));
  const SelectedInverse s = ComputeSelectedInverse(llt);
  testing::ExpectErrorContains([&] { s.Entry(3, 1); }, {"(3, 1)", "not in the pattern"});
  const int idx[2] = {1, 3};
  const double val[2] = {1.0, 2.0};
  testing::ExpectErrorContains([&] { QuadraticForm(s, idx, val, 2); }, {"(3, 1)"});
  testing::ExpectErrorContains([&] { s.Entry(7, 0); }, {"(7, 0)", "outside"});
}

TEST(SelectedInverse, FailedFactorisationIsAnError) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(3, 3);
  a(1, 1) = -1;
  const SparseCholesky llt(LowerOf(a));
  testing::ExpectErrorContains([&] { ComputeSelectedInverse(llt); }, {"did not succeed"});
}

}  // namespace
}  // namespace foresight
