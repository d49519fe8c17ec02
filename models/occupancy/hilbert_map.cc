#include "models/occupancy/hilbert_map.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "core/error.h"

namespace foresight::occupancy {

HingeMap TrainHilbertMap(const HingeGrid& grid, const HilbertMapConfig& config,
                         const Eigen::Ref<const Eigen::Matrix2Xd>& xy, const std::uint8_t* occupied,
                         std::uint64_t seed) {
  const int t_size = grid.size();
  const auto n = static_cast<std::size_t>(xy.cols());
  FS_THROW_UNLESS(n > 0, "Hilbert map: no training points");
  std::vector<double> v(t_size, 0.0), q(t_size, 0.0);  // w = scale * v; q: applied L1 penalty
  double scale = 1.0, u = 0.0;                         // u: total L1 penalty so far
  std::vector<int> idx(grid.max_active());
  std::vector<double> phi(grid.max_active());
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 rng(seed);
  const double l2 = config.alpha * (1.0 - config.l1_ratio), l1 = config.alpha * config.l1_ratio;
  double step = 0;
  for (int epoch = 0; epoch < config.epochs; ++epoch) {
    std::shuffle(order.begin(), order.end(), rng);
    for (const std::size_t s : order) {
      const double eta = config.learning_rate / (1.0 + config.learning_rate * config.alpha * step);
      step += 1;
      const int k = grid.Features(xy(0, s), xy(1, s), idx.data(), phi.data());
      if (k == 0) continue;
      double f = 0;
      for (int i = 0; i < k; ++i) f += phi[i] * v[idx[i]];
      f *= scale;
      const double y = occupied[s] ? 1.0 : 0.0;
      const double g = 1.0 / (1.0 + std::exp(-f)) - y;  // d loss / d f
      scale *= 1.0 - eta * l2;
      if (scale < 1e-9) {
        for (double& x : v) x *= scale;
        scale = 1.0;
      }
      for (int i = 0; i < k; ++i) v[idx[i]] -= eta * g * phi[i] / scale;
      if (l1 > 0) {
        u += eta * l1;
        for (int i = 0; i < k; ++i) {
          const int t = idx[i];
          const double w = scale * v[t];
          double w_new = w;
          if (w > 0)
            w_new = std::max(0.0, w - (u + q[t]));
          else if (w < 0)
            w_new = std::min(0.0, w + (u - q[t]));
          q[t] += w_new - w;
          v[t] = w_new / scale;
        }
      }
    }
  }
  HingeWeights weights;
  weights.mean = Eigen::Map<Eigen::VectorXd>(v.data(), t_size) * scale;
  FS_THROW_UNLESS(weights.mean.allFinite(), "Hilbert map: SGD diverged (learning_rate ",
                  config.learning_rate, " too large?)");
  return HingeMap(HingeMapKind::kHilbert, grid, std::move(weights), 0.0, 1.0);
}

}  // namespace foresight::occupancy
