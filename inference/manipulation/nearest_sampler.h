#pragma once
/// The nearest-neighbour GFCS sampler: the trivial baseline of the learned one. It retrieves the
/// command sequences that solved the self-supervised loop's training problems (the energy
/// artifact's solution memory) from the problems whose context is closest to the query's, with no
/// model at all. The learned sampler has to beat this to show that it generalises rather than
/// recalls.
///
/// Distance between the query's context c and a memory problem's c' (both EnergyModel::Context:
/// normalised start, start velocity and goal, then the world's encoding), each dimension
/// standardised by its spread over the memory's problems, the two blocks weighted equally:
///   d^2 = mean_{i in state, s_i > 0} ((c_i - c'_i) / s_i)^2 + mean_{i in encoding, s_i > 0}
///   (...)^2
/// (dimensions that do not vary over the memory, such as a zero start velocity, are left out).
/// A batch of `count` takes the memory's problems from the nearest, and from each its
/// `per_problem` cheapest solutions, cheapest first; ties in distance go to the lower index. If
/// the memory holds fewer solutions than asked for, uniform draws in the joint limits fill the
/// rest (last_filled()). Fixed in advance, not tuned: the weighting and per_problem (the loop's
/// top-m, the number of solutions a solve keeps).

#include <Eigen/Core>
#include <random>
#include <string>
#include <vector>

#include "inference/manipulation/energy_model.h"
#include "inference/manipulation/gfcs.h"

namespace foresight::manipulation {

class NearestSampler : public ContextSampler {
 public:
  /// `model` must outlive the sampler and hold a solution memory (else Error naming what is
  /// missing); per_problem >= 1.
  NearestSampler(const EnergyModel& model, int per_problem);
  std::string name() const override { return "nearest"; }
  /// `out` [7n x count] in radians. Error when intermediate_commands != the model's n or SetWorld
  /// was not called.
  void Sample(const GfcsQuery& query, int intermediate_commands, int count, std::mt19937_64* rng,
              Eigen::MatrixXd* out) override;

  /// Squared distances of `context` to every memory problem (the definition above).
  Eigen::VectorXd Distances(const Eigen::VectorXf& context) const;
  int last_filled() const { return last_filled_; }      ///< uniform draws in the last Sample
  int last_problems() const { return last_problems_; }  ///< memory problems the last batch used

 private:
  int per_problem_;
  Eigen::VectorXd inv_spread_;  ///< [context] 1 / s_i, 0 for constant dimensions
  Eigen::VectorXd weight_;      ///< [context] the block weight 1 / (varying dims in the block)
  std::vector<std::vector<int>> by_problem_;  ///< solutions of each problem, cheapest first
  int last_filled_ = 0, last_problems_ = 0;
};

}  // namespace foresight::manipulation
