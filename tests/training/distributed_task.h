#pragma once
/// A tiny regression TrainingTask shared by distributed_test.cc and its worker binary
/// (distributed_worker.cc): the data depend only on `n`, the initial weights on `init_seed`.

#include <torch/torch.h>

#include <cstdint>

#include "training/trainer.h"

namespace foresight::testing {

class TinyRegressionTask : public TrainingTask {
 public:
  TinyRegressionTask(std::int64_t n, std::uint64_t init_seed) {
    torch::manual_seed(12345);
    x_ = torch::randn({n, 4});
    y_ = torch::sin(x_.sum(1, true)) + 0.1 * torch::randn({n, 1});
    x_val_ = torch::randn({32, 4});
    y_val_ = torch::sin(x_val_.sum(1, true));
    torch::manual_seed(init_seed);
    net_ =
        torch::nn::Sequential(torch::nn::Linear(4, 8), torch::nn::Tanh(), torch::nn::Linear(8, 1));
  }
  torch::nn::Module& module() override { return *net_; }
  std::int64_t num_train() const override { return x_.size(0); }
  torch::Tensor BatchLoss(const torch::Tensor& indices) override {
    return torch::mse_loss(net_->forward(x_.index_select(0, indices)), y_.index_select(0, indices));
  }
  double ValidationLoss() override {
    return torch::mse_loss(net_->forward(x_val_), y_val_).item<double>();
  }

 private:
  torch::Tensor x_, y_, x_val_, y_val_;
  torch::nn::Sequential net_{nullptr};
};

/// The trainer settings of the distributed tests (a few quick epochs, no early stop).
inline TrainConfig TinyTrainConfig(int batch_size, int epochs) {
  TrainConfig c;
  c.epochs = epochs;
  c.batch_size = batch_size;
  c.learning_rate = 0.01;
  c.patience = 0;
  c.threads = 1;
  c.progress = ProgressStyle::kNone;
  return c;
}

}  // namespace foresight::testing
