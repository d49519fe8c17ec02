#include "models/directional/knn_directional.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace foresight::directional {
namespace {

/// Leaves hold at most this many points.
constexpr Eigen::Index kLeafSize = 8;

}  // namespace

/// The k best (squared distance, training index) pairs so far, sorted ascending, stored with a
/// stride in caller memory (a row of the output batch, or a small vector).
struct KnnMap::Candidates {
  double* d2 = nullptr;     ///< [k] squared distances
  double* index = nullptr;  ///< [k] training indices (exact as doubles below 2^53)
  Eigen::Index stride = 1;
  int k = 1, count = 0;

  double& D(int j) const { return d2[j * stride]; }
  double& I(int j) const { return index[j * stride]; }
  bool full() const { return count == k; }
  double worst() const { return D(k - 1); }
  /// Keeps (d, i) if it is among the k smallest in (distance, index) order.
  void Offer(double d, Eigen::Index i) {
    const double di = static_cast<double>(i);
    int j = count;
    if (full()) {
      if (d > D(k - 1) || (d == D(k - 1) && di > I(k - 1))) return;
      j = k - 1;
    } else {
      ++count;
    }
    while (j > 0 && (d < D(j - 1) || (d == D(j - 1) && di < I(j - 1)))) {
      D(j) = D(j - 1);
      I(j) = I(j - 1);
      --j;
    }
    D(j) = d;
    I(j) = di;
  }
};

KnnMap KnnMap::Fit(const DirectionalSamples& train, const KnnConfig& config) {
  train.Validate("knn directional map: training samples");
  const Eigen::Index n = train.size();
  FS_THROW_UNLESS(config.k >= 1, "knn directional map: k ", config.k, " must be >= 1");
  FS_THROW_UNLESS(config.k <= n, "knn directional map: k ", config.k, " is more than the ", n,
                  " training samples");
  FS_THROW_UNLESS(config.kappa > 0 && std::isfinite(config.kappa), "knn directional map: kappa ",
                  config.kappa, " must be finite and > 0");
  FS_THROW_UNLESS(config.time_scale > 0 && std::isfinite(config.time_scale),
                  "knn directional map: time_scale ", config.time_scale,
                  " must be finite and > 0 (m per s)");
  KnnMap map;
  map.config_ = config;
  map.dims_ = config.use_time ? 3 : 2;
  map.theta_ = train.theta;
  // Coordinates in training order while building, then in tree order.
  map.points_.resize(map.dims_, n);
  map.points_.row(0) = train.x.transpose();
  map.points_.row(1) = train.y.transpose();
  if (config.use_time) map.points_.row(2) = config.time_scale * train.t.transpose();
  map.order_.resize(static_cast<std::size_t>(n));
  std::iota(map.order_.begin(), map.order_.end(), Eigen::Index{0});
  map.nodes_.reserve(static_cast<std::size_t>(2 * (n / kLeafSize + 1)));
  map.Build(0, n);
  Eigen::MatrixXd sorted(map.dims_, n);
  for (Eigen::Index p = 0; p < n; ++p)
    sorted.col(p) = map.points_.col(map.order_[static_cast<std::size_t>(p)]);
  map.points_ = std::move(sorted);
  return map;
}

int KnnMap::Build(Eigen::Index begin, Eigen::Index end) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{begin, end, -1, 0.0, -1, -1});
  if (end - begin <= kLeafSize) return id;
  // Split at the median of the widest coordinate (points_ is in training order here).
  int dim = 0;
  double widest = -1;
  for (int d = 0; d < dims_; ++d) {
    double lo = points_(d, order_[static_cast<std::size_t>(begin)]), hi = lo;
    for (Eigen::Index p = begin; p < end; ++p) {
      const double v = points_(d, order_[static_cast<std::size_t>(p)]);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (hi - lo > widest) {
      widest = hi - lo;
      dim = d;
    }
  }
  const Eigen::Index mid = begin + (end - begin) / 2;
  const auto first = order_.begin() + static_cast<std::ptrdiff_t>(begin);
  std::nth_element(first, order_.begin() + static_cast<std::ptrdiff_t>(mid),
                   order_.begin() + static_cast<std::ptrdiff_t>(end),
                   [&](Eigen::Index a, Eigen::Index b) {
                     const double va = points_(dim, a), vb = points_(dim, b);
                     return va < vb || (va == vb && a < b);
                   });
  const double split = points_(dim, order_[static_cast<std::size_t>(mid)]);
  const int left = Build(begin, mid);
  const int right = Build(mid, end);
  Node& node = nodes_[static_cast<std::size_t>(id)];
  node.dim = dim;
  node.split = split;
  node.left = left;
  node.right = right;
  return id;
}

void KnnMap::Search(int id, const double* q, Candidates* c) const {
  const Node& node = nodes_[static_cast<std::size_t>(id)];
  if (node.dim < 0) {
    for (Eigen::Index p = node.begin; p < node.end; ++p) {
      double d2 = 0;
      for (int d = 0; d < dims_; ++d) {
        const double diff = q[d] - points_(d, p);
        d2 += diff * diff;
      }
      c->Offer(d2, order_[static_cast<std::size_t>(p)]);
    }
    return;
  }
  // Left points have coordinate <= split, right ones >= split: the far side is at least
  // |q - split| away. Equal distances are searched (a tie may have a lower index).
  const double diff = q[node.dim] - node.split;
  const int near_side = diff < 0 ? node.left : node.right;
  const int far_side = diff < 0 ? node.right : node.left;
  Search(near_side, q, c);
  if (!c->full() || diff * diff <= c->worst()) Search(far_side, q, c);
}

void KnnMap::FindNearest(const double* q, Candidates* c) const { Search(0, q, c); }

void KnnMap::Query(const Eigen::Ref<const Eigen::VectorXd>& x,
                   const Eigen::Ref<const Eigen::VectorXd>& y,
                   const Eigen::Ref<const Eigen::VectorXd>& t, VonMisesMixtureBatch* out) const {
  FS_THROW_UNLESS(out != nullptr, "KnnDirectionalMap::Query: no output batch");
  const Eigen::Index n = x.size();
  FS_THROW_UNLESS(y.size() == n && (!config_.use_time || t.size() == n),
                  "KnnDirectionalMap::Query: x [", x.size(), "], y [", y.size(), "] and t [",
                  t.size(), "] must have the same size",
                  config_.use_time ? "" : " (t may be empty without use_time)");
  const int k = config_.k;
  if (out->alpha.rows() != n || out->alpha.cols() != k || out->mu.rows() != n ||
      out->mu.cols() != k || out->kappa.rows() != n || out->kappa.cols() != k)
    out->Resize(n, k);
  const double weight = 1.0 / k;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double ti = config_.use_time ? t[i] : 0.0;
    FS_THROW_UNLESS(std::isfinite(x[i]) && std::isfinite(y[i]) && std::isfinite(ti),
                    "KnnDirectionalMap::Query: query ", i, " (x ", x[i], ", y ", y[i], ", t ", ti,
                    ") is not finite");
    const double q[3] = {x[i], y[i], config_.time_scale * ti};
    Candidates c;
    c.d2 = out->kappa.data() + i;
    c.index = out->mu.data() + i;
    c.stride = out->kappa.outerStride();
    c.k = k;
    FindNearest(q, &c);
    for (int j = 0; j < k; ++j) {
      out->mu(i, j) = theta_[static_cast<Eigen::Index>(out->mu(i, j))];
      out->kappa(i, j) = config_.kappa;
      out->alpha(i, j) = weight;
    }
  }
}

std::vector<Eigen::Index> KnnMap::Neighbours(double x, double y, double t) const {
  const double ti = config_.use_time ? t : 0.0;
  FS_THROW_UNLESS(std::isfinite(x) && std::isfinite(y) && std::isfinite(ti),
                  "KnnDirectionalMap::Neighbours: query (x ", x, ", y ", y, ", t ", t,
                  ") is not finite");
  std::vector<double> d2(static_cast<std::size_t>(config_.k)),
      index(static_cast<std::size_t>(config_.k));
  Candidates c;
  c.d2 = d2.data();
  c.index = index.data();
  c.k = config_.k;
  const double q[3] = {x, y, config_.time_scale * ti};
  FindNearest(q, &c);
  std::vector<Eigen::Index> out(index.size());
  for (std::size_t j = 0; j < index.size(); ++j) out[j] = static_cast<Eigen::Index>(index[j]);
  return out;
}

}  // namespace foresight::directional
