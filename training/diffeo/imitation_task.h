#pragma once
/// The trainer's task for the imitation learners of thesis ch 8 (RbfFlowNet, EFlowNet: any
/// VelocityModel of models/imitation/flow_net.h): the velocity loss of eq. learn_cost on a batch of
/// demonstrated (position, velocity) pairs, with the optional invertibility penalty. It lives here,
/// beside the trainer it plugs into; the models stay free of the trainer (docs/architecture.md).

#include <torch/torch.h>

#include <cstdint>
#include <memory>

#include "models/imitation/flow_net.h"
#include "training/trainer.h"

namespace foresight::imitation {

/// Demonstrations for a VelocityModel: BatchLoss(indices) = VelocityLoss on those training rows,
/// ValidationLoss = VelocityLoss on the validation pairs, without gradients.
class ImitationTask : public TrainingTask {
 public:
  /// @param positions, velocities [N, d] training pairs (N >= 1);
  /// @param val_positions, val_velocities [N_v, d] validation pairs (N_v >= 1);
  /// @param goal [d] the attractor. Converted to kFloat64; bad shapes or non-finite values are an
  /// Error.
  /// @param penalty_points [R, d] where the model must stay invertible besides the batch (e.g. a
  /// lattice over the region it is used in); @param penalty_weight >= 0 multiplies
  /// VelocityModel::InvertibilityPenalty over [batch; penalty_points] in BatchLoss.
  ImitationTask(std::shared_ptr<VelocityModel> model, torch::Tensor positions,
                torch::Tensor velocities, torch::Tensor val_positions, torch::Tensor val_velocities,
                torch::Tensor goal, torch::Tensor penalty_points = {}, double penalty_weight = 0);

  torch::nn::Module& module() override { return *model_; }
  std::int64_t num_train() const override { return positions_.size(0); }
  torch::Tensor BatchLoss(const torch::Tensor& indices) override;
  double ValidationLoss() override;

  VelocityModel& model() { return *model_; }
  const torch::Tensor& goal() const { return goal_; }

 private:
  std::shared_ptr<VelocityModel> model_;
  torch::Tensor positions_, velocities_, val_positions_, val_velocities_, goal_;
  torch::Tensor penalty_points_;
  double penalty_weight_ = 0;
};

}  // namespace foresight::imitation
