#pragma once
/// Copies of LibTorch parameters as Eigen float arrays (exporters turn tensors into engine weights
/// with these). Any dtype is converted to float; a 2-d tensor is read row-major.

#include <torch/torch.h>

#include <Eigen/Core>

namespace foresight {

/// A 2-d tensor [rows x cols] as a matrix.
inline Eigen::MatrixXf ToEigenMatrix(const torch::Tensor& tensor) {
  const torch::Tensor t = tensor.detach().contiguous().to(torch::kFloat32);
  return Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      t.data_ptr<float>(), t.size(0), t.size(1));
}

/// A 1-d tensor [n] as a vector.
inline Eigen::VectorXf ToEigenVector(const torch::Tensor& tensor) {
  const torch::Tensor t = tensor.detach().contiguous().to(torch::kFloat32);
  return Eigen::Map<const Eigen::VectorXf>(t.data_ptr<float>(), t.size(0));
}

}  // namespace foresight
