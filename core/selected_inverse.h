#pragma once
/// Selected inversion (Takahashi, Fagan & Chin 1973; Erisman & Tinney 1975): the entries of
/// Sigma = A^-1 on the sparsity pattern of the Cholesky factor of a sparse SPD matrix A, without
/// forming the dense inverse. With P A P' = L L' (Eigen's SimplicialLLT, AMD ordering) and
/// Z = (L L')^-1, the identity Z L = L^-T (upper triangular, diagonal 1 / L_jj) gives, for each
/// column j from the last to the first and every i > j in struct(L_:j),
///   Z_ij = -(1 / L_jj) sum_{k > j, k in struct(L_:j)} Z_ik L_kj
///   Z_jj = (1 / L_jj) (1 / L_jj - sum_{k > j, k in struct(L_:j)} Z_kj L_kj),
/// and every Z_ik needed lies in the pattern of L (struct(L_:j) is a clique of the filled graph).
/// Columns with nested structure (supernodes J, rows S below them shared) are done as dense blocks:
///   U = L_SJ L_JJ^-1,  Z_SJ = -Z_SS U,  Z_JJ = L_JJ^-T L_JJ^-1 - U' Z_SJ
/// (the same identity for a block of columns), so Z_SS is gathered once per supernode and the rest
/// is dense triangular solves and products. Cost ~ sum_J (|S_J|^2 |J| + gather), memory nnz(L).
/// Sigma_ij = Z_{p(i) p(j)}, where p is the fill-reducing permutation (P x)[p(i)] = x[i].

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstddef>
#include <vector>

namespace foresight {

/// The sparse Cholesky factorisation the selected inverse reads: P A P' = L L'.
using SparseCholesky =
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>>;

/// Entries of Sigma = A^-1 on the pattern of L + L', in the ORIGINAL ordering of A, stored as the
/// LOWER triangle (row >= column, compressed column-major, rows sorted within each column). It
/// contains the diagonal and every (i, j) with A_ij != 0 (structurally).
struct SelectedInverse {
  Eigen::SparseMatrix<double> lower;  ///< [T x T]
  /// Sigma_ij for any order of (i, j); throws an Error naming (i, j) when outside the pattern.
  double Entry(int i, int j) const;
};

/// Runs Takahashi's recursion on a successful factorisation (Error otherwise) and returns the
/// selected inverse in the original ordering.
SelectedInverse ComputeSelectedInverse(const SparseCholesky& llt);

/// phi' Sigma phi for a sparse phi with `count` entries idx[k] (distinct, in [0, T)) and values
/// val[k]; every pair (idx[a], idx[b]) must lie in the pattern (Error naming the pair otherwise).
double QuadraticForm(const SelectedInverse& sigma, const int* idx, const double* val, int count);

/// The recursion with buffers kept between calls, for repeated factorisations of matrices with one
/// sparsity pattern (variational EM): Compute() once per factorisation, then read entries by slot.
/// Slots index values() (Sigma on the pattern of L, in the factor's permuted ordering).
class SelectedInverter {
 public:
  /// Z = (L L')^-1 on the pattern of L. Error when `llt` did not succeed.
  void Compute(const SparseCholesky& llt);
  /// Slot of Sigma_ij (original indices, either order) in values(), or -1 when outside the
  /// pattern. Valid for every later Compute() on a factor with the same pattern. O(log nnz col).
  std::ptrdiff_t Slot(int i, int j) const;
  const std::vector<double>& values() const { return z_; }
  double Diagonal(int i) const { return z_[outer_[perm_[i]]]; }
  /// log det A = 2 sum_j log L_jj of the last factor.
  double LogDetA() const { return log_det_; }
  int size() const { return static_cast<int>(perm_.size()); }
  /// The selected inverse in the original ordering (lower triangle).
  SelectedInverse ToSparse() const;

 private:
  void FindSupernodes();  // supernode_start_ from the pattern of L

  std::vector<int> outer_, inner_;    // pattern of L (diagonal first, rows ascending)
  std::vector<int> supernode_start_;  // first column of each supernode, then n
  std::vector<int> perm_, pinv_;      // perm_[orig] = permuted index; pinv_ its inverse
  std::vector<double> z_;             // Z on the pattern of L
  std::vector<int> pos_;              // scatter: row -> position in the current column, or -1
  Eigen::MatrixXd ljj_, lsj_, zss_, u_, zsj_, zjj_;  // dense blocks of one supernode
  double log_det_ = 0;
};

}  // namespace foresight
