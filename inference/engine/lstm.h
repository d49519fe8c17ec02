#pragma once
/// One LSTM layer evaluated with Eigen in float, laid out as PyTorch's torch::nn::LSTM (one layer,
/// unidirectional): gates [i, f, g, o] stacked in that order,
///   i = sigmoid(W_ii x + b_ii + W_hi h + b_hi),  f = sigmoid(W_if x + b_if + W_hf h + b_hf),
///   g = tanh(W_ig x + b_ig + W_hg h + b_hg),     o = sigmoid(W_io x + b_io + W_ho h + b_ho),
///   c' = f * c + i * g,  h' = o * tanh(c').
/// Immutable weights plus a caller-owned Workspace; no allocation after MakeWorkspace().

#include <Eigen/Core>
#include <string>

#include "core/h5.h"

namespace foresight {

struct LstmWeights {
  Eigen::MatrixXf weight_ih;  ///< [4H x I]
  Eigen::MatrixXf weight_hh;  ///< [4H x H]
  Eigen::VectorXf bias_ih;    ///< [4H]
  Eigen::VectorXf bias_hh;    ///< [4H]
};

class Lstm {
 public:
  struct Workspace {
    Eigen::VectorXf gates;   ///< [4H]
    Eigen::VectorXf h, c;    ///< [H] state
    bool zero_state = true;  ///< h = c = 0 (after Reset): the recurrent product is skipped
  };

  Lstm() = default;
  /// Checks the shapes (Error naming the mismatch).
  explicit Lstm(LstmWeights weights);
  /// Reads `<prefix>weight_ih_l0`, `weight_hh_l0`, `bias_ih_l0`, `bias_hh_l0` (PyTorch names).
  static Lstm Load(const h5::File& file, const std::string& prefix);

  int input_size() const { return static_cast<int>(w_.weight_ih.cols()); }
  int hidden_size() const { return static_cast<int>(w_.weight_hh.cols()); }
  const LstmWeights& weights() const { return w_; }

  Workspace MakeWorkspace() const;
  /// h = c = 0.
  void Reset(Workspace* ws) const;
  /// One step with input x [I].
  void Step(const Eigen::Ref<const Eigen::VectorXf>& x, Workspace* ws) const;
  /// One step given the input projection W_ih x = scale * u, u [4H] (callers that know W_ih x
  /// cheaply, e.g. sparse or scaled inputs). The biases are added here.
  void StepProjected(const Eigen::Ref<const Eigen::VectorXf>& u, float scale, Workspace* ws) const;
  /// Runs a sequence from the zero state: `sequence` [T x I], one row per step.
  /// @return a view of the last hidden state [H] inside `ws`.
  Eigen::Ref<const Eigen::VectorXf> Forward(const Eigen::Ref<const Eigen::MatrixXf>& sequence,
                                            Workspace* ws) const;

 private:
  void Finish(Workspace* ws) const;  // gates (pre-activation, biases included) -> h, c
  LstmWeights w_;
  Eigen::VectorXf bias_;  ///< bias_ih + bias_hh
  /// weight_hh stored row-major: the recurrent product as row dot products streams each row
  /// contiguously (faster than the column-major product at batch 1).
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> weight_hh_rows_;
};

}  // namespace foresight
