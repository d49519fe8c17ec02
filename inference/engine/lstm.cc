#include "inference/engine/lstm.h"

#include <cmath>

#include "core/error.h"

namespace foresight {

Lstm::Lstm(LstmWeights weights) : w_(std::move(weights)) {
  const auto four_h = w_.weight_hh.rows();
  const auto h = w_.weight_hh.cols();
  FS_THROW_UNLESS(h >= 1 && four_h == 4 * h, "Lstm: weight_hh is ", four_h, " x ", h,
                  ", expected 4H x H");
  FS_THROW_UNLESS(w_.weight_ih.rows() == four_h && w_.weight_ih.cols() >= 1, "Lstm: weight_ih is ",
                  w_.weight_ih.rows(), " x ", w_.weight_ih.cols(), ", expected ", four_h, " x I");
  FS_THROW_UNLESS(w_.bias_ih.size() == four_h && w_.bias_hh.size() == four_h, "Lstm: biases have ",
                  w_.bias_ih.size(), " and ", w_.bias_hh.size(), " entries, expected ", four_h);
  FS_THROW_UNLESS(w_.weight_ih.allFinite() && w_.weight_hh.allFinite() && w_.bias_ih.allFinite() &&
                      w_.bias_hh.allFinite(),
                  "Lstm: non-finite weights");
  bias_ = w_.bias_ih + w_.bias_hh;
  weight_hh_rows_ = w_.weight_hh;
}

Lstm Lstm::Load(const h5::File& file, const std::string& prefix) {
  LstmWeights w;
  w.weight_hh = file.ReadMatrixF(prefix + "weight_hh_l0");
  const long four_h = static_cast<long>(w.weight_hh.rows());
  w.weight_ih = file.ReadMatrixF(prefix + "weight_ih_l0", four_h, -1);
  w.bias_ih = file.ReadMatrixF(prefix + "bias_ih_l0", four_h, 1).col(0);
  w.bias_hh = file.ReadMatrixF(prefix + "bias_hh_l0", four_h, 1).col(0);
  try {
    return Lstm(std::move(w));
  } catch (const Error& e) {
    Fail(file.path(), ": ", prefix, ": ", e.what());
  }
}

Lstm::Workspace Lstm::MakeWorkspace() const {
  const int h = hidden_size();
  return {Eigen::VectorXf::Zero(4 * h), Eigen::VectorXf::Zero(h), Eigen::VectorXf::Zero(h), true};
}

void Lstm::Reset(Workspace* ws) const {
  ws->h.setZero();
  ws->c.setZero();
  ws->zero_state = true;
}

void Lstm::Finish(Workspace* ws) const {
  const Eigen::Index h = hidden_size();
  if (!ws->zero_state) ws->gates.noalias() += weight_hh_rows_ * ws->h;
  ws->zero_state = false;
  // Gate nonlinearities as whole-vector array expressions: Eigen evaluates logistic and tanh with
  // SIMD (about 2x faster than a scalar loop over std::exp / std::tanh at H = 200; within 2e-7).
  auto gates = ws->gates.array();
  gates.segment(0, h) = gates.segment(0, h).logistic();          // i
  gates.segment(h, h) = gates.segment(h, h).logistic();          // f
  gates.segment(2 * h, h) = gates.segment(2 * h, h).tanh();      // g
  gates.segment(3 * h, h) = gates.segment(3 * h, h).logistic();  // o
  ws->c.array() =
      gates.segment(h, h) * ws->c.array() + gates.segment(0, h) * gates.segment(2 * h, h);
  ws->h.array() = gates.segment(3 * h, h) * ws->c.array().tanh();
}

void Lstm::Step(const Eigen::Ref<const Eigen::VectorXf>& x, Workspace* ws) const {
  ws->gates = bias_;
  ws->gates.noalias() += w_.weight_ih * x;
  Finish(ws);
}

void Lstm::StepProjected(const Eigen::Ref<const Eigen::VectorXf>& u, float scale,
                         Workspace* ws) const {
  ws->gates = scale * u + bias_;
  Finish(ws);
}

Eigen::Ref<const Eigen::VectorXf> Lstm::Forward(const Eigen::Ref<const Eigen::MatrixXf>& sequence,
                                                Workspace* ws) const {
  FS_THROW_UNLESS(sequence.cols() == input_size(), "Lstm: sequence has ", sequence.cols(),
                  " inputs per step, expected ", input_size());
  Reset(ws);
  for (Eigen::Index k = 0; k < sequence.rows(); ++k) {
    ws->gates = bias_;
    ws->gates.noalias() += w_.weight_ih * sequence.row(k).transpose();
    Finish(ws);
  }
  return ws->h;
}

}  // namespace foresight
