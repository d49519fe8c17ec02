#pragma once
/// The Euclideanizing-Flows baseline (Rana, Li, Fox, Boots, Ramos, Ratliff, "Euclideanizing Flows:
/// Diffeomorphic Reduction for Learning Stable Dynamical Systems", L4DC 2020) in LibTorch, double
/// precision. psi is a stack of affine coupling layers with random-Fourier-feature scale and
/// translation functions; the formulas and the artifact are those of the torch-free engine
/// (inference/imitation/eflow.h), to which the net exports itself (ToEngine):
///   layer l changes coordinate b = l mod d (d = 2: alternating; d = 3: cycling), a = the others:
///   y_a = x_a,  y_b = x_b exp(s(x_a)) + t(x_a),  s = sigma' r(x_a),  t = tau' r(x_a),
///   r(u) = sqrt(2/F) cos(Omega u + beta),  Omega ~ N(0, bandwidth^2), beta ~ U[0, 2 pi)  (fixed).
/// J = d psi/dx is the exact product of the analytic block-triangular layer Jacobians (not
/// autograd). The velocity and the loss are those of RbfFlowNet (flow_net.h): the same
/// natural-gradient attractor -speed J^-1 (z - z_e)/||z - z_e|| with a learned log_speed and the
/// same VelocityLoss, so that a comparison isolates the family of diffeomorphisms.

#include <torch/torch.h>

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "inference/imitation/eflow.h"
#include "models/imitation/flow_net.h"

namespace foresight::imitation {

/// Hyper-parameters. The defaults are those of the authors' public implementation
/// (github.com/mrana6/euclideanizing_flows, coupling_layer_type "rffn"): 10 coupling layers, 200
/// random features per layer and a length scale of 0.45 on their normalised data, i.e. a
/// bandwidth (std of Omega) of 1 / 0.45. The length scale should be chosen relative to the extent
/// of the (normalised) demonstrations.
struct EFlowNetOptions {
  int dimension = 2;            ///< d in [2, EFlowModel::kMaxDimension]
  int layers = 10;              ///< L >= 1 coupling layers
  int features = 200;           ///< F >= 1 random Fourier features per layer
  double bandwidth = 1 / 0.45;  ///< std of the frequencies Omega [1 / length]
  double initial_speed = 1;     ///< speed = exp(log_speed) at the start [length / time]
  std::uint64_t seed = 0;       ///< draws Omega and beta (std::mt19937_64)
};

class EFlowNetImpl : public VelocityModel {
 public:
  /// Checks the options (an Error naming the bad value). sigma and tau start at zero (psi =
  /// identity), log_speed at log(initial_speed).
  explicit EFlowNetImpl(const EFlowNetOptions& options);

  /// z = psi(x) [B, d] and J = d psi/dx [B, d, d] for x [B, d] (kFloat64).
  std::pair<torch::Tensor, torch::Tensor> Forward(const torch::Tensor& x);
  /// psi(x) [B, d] only.
  torch::Tensor Map(const torch::Tensor& x);
  /// psi^-1(z) [B, d], exact, layer by layer.
  torch::Tensor Inverse(const torch::Tensor& z);
  /// Coupling layer l alone, and its exact inverse x_b = (y_b - t(y_a)) exp(-s(y_a)).
  torch::Tensor ForwardLayer(int l, const torch::Tensor& x);
  torch::Tensor InverseLayer(int l, const torch::Tensor& y);
  /// -speed J^-1 (z - z_e)/||z - z_e|| (flow_net.h: NaturalGradientVelocity), z_e = psi(goal).
  torch::Tensor Velocity(const torch::Tensor& x, const torch::Tensor& goal) override;

  /// The torch-free engine of this net with the attractor `goal` [d].
  EFlowModel ToEngine(const Eigen::VectorXd& goal) const;
  double speed() const;
  const EFlowNetOptions& options() const { return options_; }
  int dimension() const { return options_.dimension; }
  int num_layers() const { return options_.layers; }

  torch::Tensor log_speed;  ///< scalar, parameter "log_speed"

 private:
  struct Layer {
    int transformed = 0;
    torch::Tensor fixed, changed;  // int64 index tensors [d-1], [1]
    torch::Tensor omega;           // buffer "omega<l>" [F, d-1]
    torch::Tensor phase;           // buffer "phase<l>" [F]
    torch::Tensor scale;           // parameter "scale<l>" [F]
    torch::Tensor translate;       // parameter "translate<l>" [F]
  };
  /// s(x_a), t(x_a) [B]; with ds, dt not null also ds/dx_a, dt/dx_a [B, d-1].
  void Terms(const Layer& layer, const torch::Tensor& x, torch::Tensor* s, torch::Tensor* t,
             torch::Tensor* ds, torch::Tensor* dt) const;
  /// One layer on x [B, d]; updates *jacobian [B, d, d] when not null.
  torch::Tensor Apply(const Layer& layer, const torch::Tensor& x, torch::Tensor* jacobian) const;
  torch::Tensor Propagate(const torch::Tensor& x, torch::Tensor* jacobian) const;
  void CheckPoints(const torch::Tensor& x, const char* what) const;
  const Layer& LayerAt(int l) const;

  EFlowNetOptions options_;
  std::vector<Layer> layers_;
};
TORCH_MODULE(EFlowNet);

}  // namespace foresight::imitation
