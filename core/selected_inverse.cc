#include "core/selected_inverse.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"

namespace foresight {

void SelectedInverter::Compute(const SparseCholesky& llt) {
  FS_THROW_UNLESS(llt.info() == Eigen::Success,
                  "selected inverse: the Cholesky factorisation did not succeed (matrix not "
                  "positive definite, or not factorised)");
  const Eigen::SparseMatrix<double>& l = llt.matrixL().nestedExpression();
  FS_THROW_UNLESS(l.isCompressed(), "selected inverse: the factor L is not compressed");
  const int n = static_cast<int>(l.cols());
  const auto nnz = static_cast<std::size_t>(l.nonZeros());
  outer_.assign(l.outerIndexPtr(), l.outerIndexPtr() + n + 1);
  inner_.assign(l.innerIndexPtr(), l.innerIndexPtr() + nnz);
  const double* lx = l.valuePtr();
  perm_.resize(n);
  pinv_.resize(n);
  const auto& p = llt.permutationP();
  for (int i = 0; i < n; ++i) perm_[i] = p.size() > 0 ? p.indices()[i] : i;
  for (int i = 0; i < n; ++i) pinv_[perm_[i]] = i;
  z_.assign(nnz, 0.0);
  pos_.assign(n, -1);
  acc_.resize(n);
  log_det_ = 0;
  for (int j = n - 1; j >= 0; --j) {
    const int begin = outer_[j], end = outer_[j + 1];
    FS_THROW_UNLESS(end > begin && inner_[begin] == j, "selected inverse: column ", j,
                    " of L does not start with its diagonal");
    const double ljj = lx[begin];
    log_det_ += 2.0 * std::log(ljj);
    const int m = end - begin - 1;  // off-diagonal rows r_a = inner_[begin + 1 + a]
    for (int a = 0; a < m; ++a) {
      pos_[inner_[begin + 1 + a]] = a;
      acc_[a] = 0.0;
    }
    // acc[b] = sum_a Z(r_b, r_a) L(r_a, j): scan column k = r_a of Z (rows >= k).
    for (int a = 0; a < m; ++a) {
      const int k = inner_[begin + 1 + a];
      const double lkj = lx[begin + 1 + a];
      for (int q = outer_[k]; q < outer_[k + 1]; ++q) {
        const int b = pos_[inner_[q]];
        if (b < 0) continue;
        acc_[b] += z_[q] * lkj;                            // Z(r_b, k) L(k, j), b >= a
        if (b != a) acc_[a] += z_[q] * lx[begin + 1 + b];  // Z(k, r_b) L(r_b, j), b > a
      }
    }
    double diag = 1.0 / ljj;
    for (int a = 0; a < m; ++a) {
      const double zij = -acc_[a] / ljj;
      z_[begin + 1 + a] = zij;
      diag -= zij * lx[begin + 1 + a];
      pos_[inner_[begin + 1 + a]] = -1;
    }
    z_[begin] = diag / ljj;
  }
}

std::ptrdiff_t SelectedInverter::Slot(int i, int j) const {
  const int n = size();
  if (i < 0 || j < 0 || i >= n || j >= n) return -1;
  int r = perm_[i], c = perm_[j];
  if (r < c) std::swap(r, c);
  if (r == c) return outer_[c];
  const int* first = inner_.data() + outer_[c] + 1;
  const int* last = inner_.data() + outer_[c + 1];
  const int* it = std::lower_bound(first, last, r);
  return (it != last && *it == r) ? it - inner_.data() : -1;
}

SelectedInverse SelectedInverter::ToSparse() const {
  const int n = size();
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(z_.size());
  for (int c = 0; c < n; ++c) {
    for (int q = outer_[c]; q < outer_[c + 1]; ++q) {
      int oi = pinv_[inner_[q]], oj = pinv_[c];
      if (oi < oj) std::swap(oi, oj);
      t.emplace_back(oi, oj, z_[q]);
    }
  }
  SelectedInverse s;
  s.lower.resize(n, n);
  s.lower.setFromTriplets(t.begin(), t.end());
  s.lower.makeCompressed();
  return s;
}

SelectedInverse ComputeSelectedInverse(const SparseCholesky& llt) {
  SelectedInverter inverter;
  inverter.Compute(llt);
  return inverter.ToSparse();
}

double SelectedInverse::Entry(int i, int j) const {
  const auto n = lower.rows();
  FS_THROW_UNLESS(i >= 0 && j >= 0 && i < n && j < n, "selected inverse: entry (", i, ", ", j,
                  ") is outside the ", n, " x ", n, " matrix");
  if (i < j) std::swap(i, j);
  const int* first = lower.innerIndexPtr() + lower.outerIndexPtr()[j];
  const int* last = lower.innerIndexPtr() + lower.outerIndexPtr()[j + 1];
  const int* it = std::lower_bound(first, last, i);
  FS_THROW_UNLESS(it != last && *it == i, "selected inverse: entry (", i, ", ", j,
                  ") is not in the pattern of the Cholesky factor (features that never share a "
                  "point, or a pattern other than the factorised matrix's)");
  return lower.valuePtr()[it - lower.innerIndexPtr()];
}

double QuadraticForm(const SelectedInverse& sigma, const int* idx, const double* val, int count) {
  double q = 0;
  for (int a = 0; a < count; ++a) {
    q += val[a] * val[a] * sigma.Entry(idx[a], idx[a]);
    for (int b = a + 1; b < count; ++b) q += 2.0 * val[a] * val[b] * sigma.Entry(idx[a], idx[b]);
  }
  return q;
}

}  // namespace foresight
