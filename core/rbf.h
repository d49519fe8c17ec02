#pragma once
/// Squared-exponential basis over time and the ridge fit that turns timestamped points into
/// trajectory weights. Thesis ch 5, "From timestamped data to continuous functions" (eq. lsuqares):
///   o(t) = W' phi(t),  phi_j(t) = exp(-gamma (t - t'_j)^2),
///   W = argmin sum_i ||y_i - W' phi(t_i)||^2 + lambda ||vec W||^2 = (P'P + lambda I)^-1 P'Y.

#include <Eigen/Core>

namespace foresight {

class TimeBasis {
 public:
  TimeBasis() = default;
  /// @param num_centres m >= 1 centres evenly spaced on [t_begin, t_end] (s).
  /// @param gamma length-scale parameter (1/s^2), > 0.
  TimeBasis(int num_centres, double t_begin, double t_end, double gamma);
  TimeBasis(Eigen::VectorXd centres, double gamma);

  int size() const { return static_cast<int>(centres_.size()); }
  double gamma() const { return gamma_; }
  const Eigen::VectorXd& centres() const { return centres_; }

  /// phi(t) [m] into `out` (no allocation when `out` has size m).
  template <typename Out>
  void Evaluate(double t, Out&& out) const {
    for (int j = 0; j < size(); ++j) {
      const double d = t - centres_[j];
      out[j] = static_cast<typename std::decay_t<Out>::Scalar>(std::exp(-gamma_ * d * d));
    }
  }
  Eigen::VectorXd Evaluate(double t) const;
  /// Design matrix [n x m] for times [n].
  Eigen::MatrixXd Design(const Eigen::VectorXd& times) const;

  /// Ridge fit: W [m x d] for times [n] (s) and points [n x d].
  Eigen::MatrixXd FitRidge(const Eigen::VectorXd& times, const Eigen::MatrixXd& points,
                           double lambda) const;

 private:
  Eigen::VectorXd centres_;
  double gamma_ = 1.0;
};

/// Precomputed ridge solver for a fixed set of sample times: W = S Y with S = (P'P + lambda I)^-1
/// P'.
class RidgeProjector {
 public:
  RidgeProjector(const TimeBasis& basis, const Eigen::VectorXd& times, double lambda);
  /// W [m x d] for points [n x d] sampled at the construction times.
  Eigen::MatrixXd Fit(const Eigen::MatrixXd& points) const { return solve_ * points; }
  const Eigen::MatrixXd& matrix() const { return solve_; }

 private:
  Eigen::MatrixXd solve_;
};

}  // namespace foresight
