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
  const bool same_pattern = static_cast<int>(outer_.size()) == n + 1 && inner_.size() == nnz &&
                            std::equal(outer_.begin(), outer_.end(), l.outerIndexPtr()) &&
                            std::equal(inner_.begin(), inner_.end(), l.innerIndexPtr());
  if (!same_pattern) {
    // Checked before it is kept: a refused pattern must not pass as "the same" next time.
    const int* outer = l.outerIndexPtr();
    const int* inner = l.innerIndexPtr();
    for (int j = 0; j < n; ++j)
      FS_THROW_UNLESS(outer[j + 1] > outer[j] && inner[outer[j]] == j, "selected inverse: column ",
                      j, " of L does not start with its diagonal");
    outer_.assign(outer, outer + n + 1);
    inner_.assign(inner, inner + nnz);
    FindSupernodes();
  }
  const double* lx = l.valuePtr();
  perm_.resize(n);
  pinv_.resize(n);
  const auto& p = llt.permutationP();
  for (int i = 0; i < n; ++i) perm_[i] = p.size() > 0 ? p.indices()[i] : i;
  for (int i = 0; i < n; ++i) pinv_[perm_[i]] = i;
  z_.assign(nnz, 0.0);
  pos_.assign(n, -1);
  log_det_ = 0;
  for (int j = 0; j < n; ++j) log_det_ += 2.0 * std::log(lx[outer_[j]]);
  // Supernodes from the last to the first: J = columns [c0, c1] share the rows S below them.
  for (std::size_t sn = supernode_start_.size() - 1; sn-- > 0;) {
    const int c0 = supernode_start_[sn], c1 = supernode_start_[sn + 1] - 1, s = c1 - c0 + 1;
    const int s_begin = outer_[c1] + 1, r = outer_[c1 + 1] - s_begin;  // S = inner_[s_begin..]
    // Dense blocks of L: L_JJ (s x s lower) and L_SJ (r x s).
    ljj_.setZero(s, s);
    lsj_.resize(r, s);
    for (int k = 0; k < s; ++k) {
      const int col = outer_[c0 + k];
      for (int i = k; i < s; ++i) ljj_(i, k) = lx[col + (i - k)];
      for (int t = 0; t < r; ++t) lsj_(t, k) = lx[col + (s - k) + t];
    }
    // Z_SS (already final: every row of S is after J), gathered from the columns of S.
    zss_.setZero(r, r);
    for (int t = 0; t < r; ++t) pos_[inner_[s_begin + t]] = t;
    for (int a = 0; a < r; ++a) {
      const int k = inner_[s_begin + a];
      for (int q = outer_[k]; q < outer_[k + 1]; ++q) {
        const int b = pos_[inner_[q]];
        if (b >= 0) zss_(b, a) = zss_(a, b) = z_[q];
      }
    }
    for (int t = 0; t < r; ++t) pos_[inner_[s_begin + t]] = -1;
    // U = L_SJ L_JJ^-1; Z_SJ = -Z_SS U; Z_JJ = L_JJ^-T L_JJ^-1 - U' Z_SJ (block Takahashi).
    const auto tri = ljj_.triangularView<Eigen::Lower>();
    zjj_.setIdentity(s, s);
    tri.solveInPlace(zjj_);                   // L_JJ^-1
    zjj_ = (zjj_.transpose() * zjj_).eval();  // L_JJ^-T L_JJ^-1
    if (r > 0) {                              // (Eigen's solvers touch the data of an empty matrix)
      u_ = lsj_;
      tri.solveInPlace<Eigen::OnTheRight>(u_);
      zsj_.noalias() = -zss_ * u_;
      zjj_.noalias() -= u_.transpose() * zsj_;
    }
    for (int k = 0; k < s; ++k) {
      const int col = outer_[c0 + k];
      for (int i = k; i < s; ++i) z_[col + (i - k)] = zjj_(i, k);
      for (int t = 0; t < r; ++t) z_[col + (s - k) + t] = zsj_(t, k);
    }
  }
}

void SelectedInverter::FindSupernodes() {
  // Columns c and c + 1 share a supernode when struct(L_:c) = {c} + struct(L_:c+1): then every
  // column of the run has the rows of the run below it (a dense triangle) and the same rows S.
  const int n = static_cast<int>(outer_.size()) - 1;
  supernode_start_.clear();
  for (int c = 0; c < n; ++c) {
    const bool joins_previous = c > 0 &&
                                outer_[c] - outer_[c - 1] == outer_[c + 1] - outer_[c] + 1 &&
                                inner_[outer_[c - 1] + 1] == c &&
                                std::equal(inner_.begin() + outer_[c - 1] + 1,
                                           inner_.begin() + outer_[c], inner_.begin() + outer_[c]);
    if (!joins_previous) supernode_start_.push_back(c);
  }
  supernode_start_.push_back(n);
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
