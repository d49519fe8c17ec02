#pragma once
/// What the trainer runs for OTNet (thesis ch 6): the mixture NLL of trajectory weights given
/// their map's similarity vector (models/otnet/otnet_net.h).

#include <torch/torch.h>

#include "models/otnet/otnet_net.h"
#include "training/trainer.h"

namespace foresight::otnet {

/// What the trainer runs: trajectories index maps, so phi is stored once per map.
/// Loss = mean mixture NLL of standardised weights (per weight dimension, i.e. divided by 2M, so
/// the number is comparable across M).
class OtnetTask : public TrainingTask {
 public:
  /// @param phi_train [maps x D], map_train [N] (int64 row of phi_train per trajectory), w_train
  /// [N x 2M]: all standardised; likewise the validation tensors. Error on inconsistent sizes.
  OtnetTask(OtnetNet net, torch::Tensor phi_train, torch::Tensor map_train, torch::Tensor w_train,
            torch::Tensor phi_val, torch::Tensor map_val, torch::Tensor w_val);
  torch::nn::Module& module() override { return *net_; }
  std::int64_t num_train() const override { return w_train_.size(0); }
  torch::Tensor BatchLoss(const torch::Tensor& indices) override;
  double ValidationLoss() override;

 private:
  OtnetNet net_;
  torch::Tensor phi_train_, map_train_, w_train_, phi_val_, map_val_, w_val_;
};

}  // namespace foresight::otnet
