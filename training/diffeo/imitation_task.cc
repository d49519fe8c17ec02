#include "training/diffeo/imitation_task.h"

#include <cmath>
#include <utility>

#include "core/error.h"

namespace foresight::imitation {

namespace {

bool AllFinite(const torch::Tensor& t) { return torch::isfinite(t).all().item<bool>(); }

}  // namespace

ImitationTask::ImitationTask(std::shared_ptr<VelocityModel> model, torch::Tensor positions,
                             torch::Tensor velocities, torch::Tensor val_positions,
                             torch::Tensor val_velocities, torch::Tensor goal,
                             torch::Tensor penalty_points, double penalty_weight)
    : model_(std::move(model)),
      positions_(positions.detach().to(torch::kFloat64).contiguous()),
      velocities_(velocities.detach().to(torch::kFloat64).contiguous()),
      val_positions_(val_positions.detach().to(torch::kFloat64).contiguous()),
      val_velocities_(val_velocities.detach().to(torch::kFloat64).contiguous()),
      goal_(goal.detach().to(torch::kFloat64).contiguous()),
      penalty_weight_(penalty_weight) {
  FS_THROW_UNLESS(model_ != nullptr, "ImitationTask: no model");
  FS_THROW_UNLESS(goal_.dim() == 1 && goal_.size(0) >= 1, "ImitationTask: goal must be [d], got ",
                  goal_.sizes());
  const std::int64_t d = goal_.size(0);
  const auto check = [d](const torch::Tensor& t, const char* name) {
    FS_THROW_UNLESS(t.dim() == 2 && t.size(0) >= 1 && t.size(1) == d, "ImitationTask: ", name,
                    " must be [N, ", d, "] with N >= 1, got ", t.sizes());
    FS_THROW_UNLESS(AllFinite(t), "ImitationTask: ", name, " contain a non-finite value");
  };
  check(positions_, "positions");
  check(velocities_, "velocities");
  check(val_positions_, "validation positions");
  check(val_velocities_, "validation velocities");
  FS_THROW_UNLESS(AllFinite(goal_), "ImitationTask: goal contains a non-finite value");
  FS_THROW_UNLESS(positions_.size(0) == velocities_.size(0), "ImitationTask: ", positions_.size(0),
                  " positions but ", velocities_.size(0), " velocities");
  FS_THROW_UNLESS(penalty_weight >= 0 && std::isfinite(penalty_weight),
                  "ImitationTask: penalty weight ", penalty_weight, " must be finite and >= 0");
  if (penalty_points.defined() && penalty_points.numel() > 0) {
    penalty_points_ = penalty_points.detach().to(torch::kFloat64).contiguous();
    check(penalty_points_, "penalty points");
  }
  FS_THROW_UNLESS(val_positions_.size(0) == val_velocities_.size(0),
                  "ImitationTask: ", val_positions_.size(0), " validation positions but ",
                  val_velocities_.size(0), " validation velocities");
}

torch::Tensor ImitationTask::BatchLoss(const torch::Tensor& indices) {
  const torch::Tensor i = indices.to(torch::kInt64);
  const torch::Tensor x = positions_.index_select(0, i);
  const torch::Tensor objective =
      model_->ObjectiveLoss(x, velocities_.index_select(0, i), goal_, penalty_points_,
                            penalty_weight_, /*with_gradient=*/true);
  if (objective.defined()) return objective;
  torch::Tensor loss = VelocityLoss(model_->Velocity(x, goal_), velocities_.index_select(0, i));
  if (penalty_weight_ > 0)
    loss = loss +
           penalty_weight_ * model_->InvertibilityPenalty(
                                 penalty_points_.defined() ? torch::cat({x, penalty_points_}) : x);
  return loss;
}

double ImitationTask::ValidationLoss() {
  torch::NoGradGuard no_grad;
  const torch::Tensor objective = model_->ObjectiveLoss(val_positions_, val_velocities_, goal_, {},
                                                        0.0, /*with_gradient=*/false);
  if (objective.defined()) return objective.item<double>();
  return VelocityLoss(model_->Velocity(val_positions_, goal_), val_velocities_).item<double>();
}

}  // namespace foresight::imitation
