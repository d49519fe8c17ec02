#pragma once
/// Hilbert map (Ramos & Ott 2015; thesis ch 2 "Hilbert Maps"): logistic regression on hinge
/// features, p(occupied | x) = sigmoid(w' phi(x)) (errata ch 2), trained by stochastic gradient
/// descent on the elastic-net penalised log loss
///   L(w) = sum_n log(1 + exp(-s_n w' phi_n)) + alpha (rho |w|_1 + (1 - rho)/2 ||w||^2),  s_n =
///   +-1,
/// with the L2 part applied through a global scale and the L1 part by the cumulative penalty of
/// Tsuruoka, Tsujii and Ananiadou (2009), so each step touches only the active features.

#include <Eigen/Core>
#include <cstdint>

#include "core/config.h"
#include "core/hinge_grid.h"
#include "inference/mapping/hinge_map.h"

namespace foresight::occupancy {

struct HilbertMapConfig {
  double alpha = 1e-5;         ///< regularisation strength
  double l1_ratio = 0.15;      ///< rho: share of the L1 penalty
  double learning_rate = 0.5;  ///< eta0 of eta_t = eta0 / (1 + eta0 alpha t)
  int epochs = 1;              ///< passes over the shuffled training points

  template <class A>
  void Serialize(A* a) {
    a->Visit("alpha", &alpha, config::Range::NonNegative(), "elastic-net regularisation strength");
    a->Visit("l1_ratio", &l1_ratio, config::Range::Closed(0, 1), "share of the L1 penalty");
    a->Visit("learning_rate", &learning_rate, config::Range::Positive(), "initial SGD step");
    a->Visit("epochs", &epochs, config::Range::Closed(1, 1000), "passes over the training points");
  }
};

/// Trains on points xy [2 x n] with labels occupied [n] (0/1), in a seeded random order.
HingeMap TrainHilbertMap(const HingeGrid& grid, const HilbertMapConfig& config,
                         const Eigen::Ref<const Eigen::Matrix2Xd>& xy, const std::uint8_t* occupied,
                         std::uint64_t seed);

}  // namespace foresight::occupancy
