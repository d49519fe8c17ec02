#pragma once
/// LibTorch learners of the imitation transform psi_i (thesis ch 8, "Learning Infinitesimal
/// Generators from Demonstrations"), double precision (kFloat64) throughout.
///
/// RbfFlowNet computes exactly the function of the torch-free engine
/// (inference/imitation/rbf_flow.h) so that WeightsAsEigen() and speed() exported into RbfFlow /
/// ImitationSystem give the same velocities:
///   phi_t(s) = exp(-gamma ||s - c_t||^2) if ||s - c_t|| <= cutoff_radius, else 0   (errata ch 8)
///   V_g(s) = W_g' phi(s),  s_0 = x,  s_{k+1} = s_k + h V_{g(k)}(s_k),  psi(x) = s_K,  h = T / K,
///   J_0 = I,  J_{k+1} = (I + h DV_{g(k)}(s_k)) J_k,  DV(s) = sum_t W_t (d phi_t/ds)',
///   g(k) = floor(k S / K) the time segment of step k (S = 1: one stationary field),
///   d phi_t/ds = -2 gamma phi_t (s - c_t).
/// J is propagated explicitly (not by autograd), so autograd differentiates the training loss
/// through the Euler integration and through J.
///
/// The natural-gradient system (thesis eq. naturalDesc; errata: solve with J, never form G^-1):
///   f(x) = -speed * J(x)^-1 (z - z_e) / ||z - z_e||,  z = psi(x),  z_e = psi(x_goal),
/// trained by the thesis's eq. learn_cost, the mean squared error ||x_dot - f(x)||^2 over the
/// demonstrated (position, velocity) pairs (VelocityLoss). speed = exp(log_speed) > 0 is learned.

#include <torch/torch.h>

#include <Eigen/Core>
#include <memory>
#include <utility>

#include "models/imitation/flow_objective.h"

namespace foresight::imitation {

/// Options of the double-precision tensors the imitation networks hold and return.
inline const torch::TensorOptions kDouble = torch::TensorOptions().dtype(torch::kFloat64);

/// Regularises ||z - z_e|| as sqrt(||z - z_e||^2 + kGoalEpsilon^2) (length units of z): at the
/// goal (z = z_e up to rounding, ~1e-16) the velocity is 0 (below speed * 1e-6) with a finite
/// gradient, and elsewhere the relative change of the velocity is kGoalEpsilon^2 / (2 ||z -
/// z_e||^2) (below 1e-12 for ||z - z_e|| > 1e-3). The engines use the exact norm (0 at z = z_e).
inline constexpr double kGoalEpsilon = 1e-9;

/// -speed * J^-1 (z - z_e) / sqrt(||z - z_e||^2 + kGoalEpsilon^2) by torch::linalg::solve.
/// @param z [B, d] images psi(x); @param jacobian [B, d, d] d psi/dx; @param goal_image [d];
/// @param speed scalar tensor. @return [B, d].
torch::Tensor NaturalGradientVelocity(const torch::Tensor& z, const torch::Tensor& jacobian,
                                      const torch::Tensor& goal_image, const torch::Tensor& speed);

/// A module with a stable velocity field x_dot = f(x; goal), trained by ImitationTask
/// (training/diffeo/imitation_task.h).
class VelocityModel : public torch::nn::Module {
 public:
  /// @param x [B, d] positions; @param goal [d]. @return [B, d] velocities (differentiable).
  virtual torch::Tensor Velocity(const torch::Tensor& x, const torch::Tensor& goal) = 0;
  /// A penalty that keeps the model invertible where it is evaluated at x [B, d] (scalar, >= 0,
  /// differentiable); 0 for models invertible by construction (the default).
  virtual torch::Tensor InvertibilityPenalty(const torch::Tensor& x) {
    return torch::zeros({}, x.options());
  }
  /// ImitationTask's loss by a hand-written objective (flow_objective.h) instead of autograd:
  /// mean ||Velocity(x) - v||^2 + penalty_weight * InvertibilityPenalty([x; penalty_points]), a
  /// scalar whose backward gives the parameters' gradients (computed eagerly when with_gradient);
  /// an undefined tensor when the model has none (the default: ImitationTask uses autograd).
  virtual torch::Tensor ObjectiveLoss(const torch::Tensor& x, const torch::Tensor& v,
                                      const torch::Tensor& goal,
                                      const torch::Tensor& penalty_points, double penalty_weight,
                                      bool with_gradient) {
    (void)x, (void)v, (void)goal, (void)penalty_points, (void)penalty_weight, (void)with_gradient;
    return {};
  }
};

/// The RBF flow psi_i (see the file comment).
class RbfFlowNetImpl : public VelocityModel {
 public:
  /// @param centres [m, d] inducing states c_t (as RbfGrid::Centre(t)), d >= 1;
  /// @param gamma > 0 kernel width; @param cutoff_radius > 0; @param time T > 0;
  /// @param steps K >= 1 Euler steps; @param initial_speed > 0;
  /// @param segments S in [1, K] time segments with their own weights.
  /// W starts at zero (psi = identity), log_speed at log(initial_speed). Bad values are an Error.
  RbfFlowNetImpl(const torch::Tensor& centres, double gamma, double cutoff_radius, double time,
                 int steps, double initial_speed, int segments = 1);

  /// z = psi(x) [B, d] and J = d psi/dx [B, d, d] for x [B, d].
  std::pair<torch::Tensor, torch::Tensor> Forward(const torch::Tensor& x);
  /// psi(x) [B, d] only (no Jacobian).
  torch::Tensor Map(const torch::Tensor& x);
  /// V_g(s) [B, d] and DV_g(s) [B, d, d] of segment g's field at s [B, d].
  std::pair<torch::Tensor, torch::Tensor> Field(const torch::Tensor& s, int segment = 0);
  /// The natural-gradient velocity (file comment); z_e = psi(goal) is computed in the same pass as
  /// psi(x) (differentiable).
  torch::Tensor Velocity(const torch::Tensor& x, const torch::Tensor& goal) override;
  /// Each Euler step s -> s + h V(s) is a contraction-perturbed identity, hence invertible (and
  /// its inverse found by the engine's fixed-point iteration), where h ||DV(s)||_2 < 1. The penalty
  /// is the mean over the points x and the K steps of max(0, h ||DV(s_k)||_F - kStepLipschitz)^2
  /// (the Frobenius norm bounds the spectral norm): zero when every step is safely contracting.
  torch::Tensor InvertibilityPenalty(const torch::Tensor& x) override;
  static constexpr double kStepLipschitz = 0.7;

  /// Trains through `objective` (MakeFlowObjective on this net's grid, time, steps, segments,
  /// kStepLipschitz and kGoalEpsilon: the same loss to rounding, sparse in the cut-off, no graph)
  /// instead of autograd; null = autograd. An objective for another grid, time, step or segment
  /// count is an Error.
  void SetObjective(std::shared_ptr<const FlowObjective> objective);
  bool has_objective() const { return objective_ != nullptr; }
  torch::Tensor ObjectiveLoss(const torch::Tensor& x, const torch::Tensor& v,
                              const torch::Tensor& goal, const torch::Tensor& penalty_points,
                              double penalty_weight, bool with_gradient) override;

  /// W [S m, d] as the engine's weights matrix.
  Eigen::MatrixXd WeightsAsEigen() const;
  double speed() const;
  int dimension() const { return static_cast<int>(centres_.size(1)); }
  int num_centres() const { return static_cast<int>(centres_.size(0)); }
  int segments() const { return segments_; }

  torch::Tensor weights;    ///< W [S m, d], parameter "weights"
  torch::Tensor log_speed;  ///< scalar, parameter "log_speed"

 private:
  /// The Euler integration; J is computed when `jacobian` is not null.
  torch::Tensor Integrate(const torch::Tensor& x, torch::Tensor* jacobian);
  /// phi [B, m] (zero beyond the cut-off) and s - c_t [B, m, d].
  std::pair<torch::Tensor, torch::Tensor> Features(const torch::Tensor& s) const;
  void CheckPoints(const torch::Tensor& x, const char* what) const;
  /// W_g [m, d] of segment g, and of the segment floor(k S / K) of Euler step k.
  torch::Tensor SegmentWeights(int segment) const;
  torch::Tensor StepWeights(int k) const;

  torch::Tensor centres_;  // buffer "centres" [m, d]
  double gamma_, cutoff_radius_, time_;
  int steps_, segments_;
  std::shared_ptr<const FlowObjective> objective_;
};
TORCH_MODULE(RbfFlowNet);

/// Thesis eq. learn_cost: mean over the batch of ||predicted - target||^2 (squared Euclidean norm
/// per row). With predicted = f(x) = -speed J^-1 grad Phi this is ||x_dot + speed J^-1 grad
/// Phi||^2.
/// @param predicted, target [B, d] (same shape; an Error otherwise).
torch::Tensor VelocityLoss(const torch::Tensor& predicted, const torch::Tensor& target);

}  // namespace foresight::imitation
