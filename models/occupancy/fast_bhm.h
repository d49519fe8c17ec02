#pragma once
/// Fast Bayesian Hilbert maps (thesis ch 3, "Fast Bayesian Hilbert Maps"): mean-field Gaussian
/// weights w_t ~ N(mu_t, s2_t) on sparse hinge features, trained scan by scan with variational EM
/// (Jaakkola-Jordan bound), the posterior of one scan being the prior of the next.
///
/// Per scan k with points (x_n, y_n), prior (mu0_t, s20_t), bound parameters z_n:
///   E-step  1/s2_t = 1/s20_t + 2 sum_n lambda(z_n) phi_t(x_n)^2
///           mu_t   = s2_t (mu0_t / s20_t + sum_n (y_n - 1/2) phi_t(x_n))          (as published:
///           the coupling between weights is dropped; see spec/errata.md, ch 3)
///   M-step  z_n^2  = sum_t phi_t^2 s2_t + (sum_t phi_t mu_t)^2     (exact expectation; errata)
///           or the printed sum_t phi_t^2 (s2_t + mu_t^2) when m_step = printed.
///   lambda(z) = (sigmoid(z) - 1/2) / (2 z),  lambda(0) = 1/8.
/// Cost per scan is linear in its points times the features within the cut-off radius.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/config.h"
#include "core/hinge_grid.h"
#include "inference/mapping/hinge_map.h"

namespace foresight::occupancy {

/// How z_n starts in each scan before the first E-step.
/// Validation on Intel (every 10th training scan held out, configs/occupancy/intel.yaml) chose
/// kOne: val AUC 0.960 against 0.873 for kPrior; more EM iterations also lowered it (0.938 for 2),
/// since the published mean update ignores the coupling between weights.
enum class BoundInit {
  kOne,    ///< z_n = 1 (a fixed starting bound)
  kPrior,  ///< z from the prior of the scan (an M-step on the previous posterior)
};
enum class MStepForm { kExact, kPrinted };
/// Which Fast-BHM update trains the map.
enum class FastBhmUpdate {
  kPublished,  ///< as published: decoupled mean update, scan by scan (FastBhmLearner)
  kCoupled,    ///< the coupled weights and a learned bound (CoupledBhmLearner, coupled_bhm.h)
};

struct FastBhmConfig {
  /// The published update stays the default of code-built configs (navigation and constrained
  /// maps fitted to rasters); configs/occupancy/*.yaml choose the coupled one.
  FastBhmUpdate update = FastBhmUpdate::kPublished;
  int bound_updates = 5;  ///< kCoupled: M-steps of the bound after the first E-step
  double prior_mean = 0.0;
  double prior_variance = 1e4;
  int em_iterations = 1;  ///< E-steps per scan (an M-step between consecutive ones)
  BoundInit bound_init = BoundInit::kOne;
  MStepForm m_step = MStepForm::kExact;

  template <class A>
  void Serialize(A* a) {
    a->VisitEnum("update", &update,
                 config::EnumNames<FastBhmUpdate>{{FastBhmUpdate::kPublished, "published"},
                                                  {FastBhmUpdate::kCoupled, "coupled"}},
                 "published: decoupled mean update scan by scan, z from em_iterations / "
                 "bound_init (thesis); coupled: sparse coupled weights and a learned bound");
    a->Visit("bound_updates", &bound_updates, config::Range::Closed(0, 100),
             "update: coupled: bound (z) updates after the first E-step (0: z = 1)");
    a->Visit("prior_mean", &prior_mean, config::Range::Any(), "mean of the weight prior");
    a->Visit("prior_variance", &prior_variance, config::Range::Positive(),
             "variance of the weight prior");
    a->Visit("em_iterations", &em_iterations, config::Range::Closed(1, 100),
             "update: published: EM iterations per scan");
    a->VisitEnum(
        "bound_init", &bound_init,
        config::EnumNames<BoundInit>{{BoundInit::kPrior, "prior"}, {BoundInit::kOne, "one"}},
        "update: published: starting variational parameter z of each scan");
    a->VisitEnum("m_step", &m_step,
                 config::EnumNames<MStepForm>{{MStepForm::kExact, "exact"},
                                              {MStepForm::kPrinted, "printed"}},
                 "update: published: M-step form (exact expectation, or as printed in the thesis)");
  }
};

/// lambda(z) = (sigmoid(z) - 1/2) / (2 z), even in z, lambda(0) = 1/8.
double JaakkolaLambda(double z);

/// Sparse features of a batch of points, computed once and reused by the EM iterations.
struct SparseFeatures {
  int stride = 0;             ///< max features per point
  std::vector<int> count;     ///< [n]
  std::vector<int> index;     ///< [n * stride]
  std::vector<double> value;  ///< [n * stride]
  void Compute(const HingeGrid& grid, const Eigen::Ref<const Eigen::Matrix2Xd>& xy);
};

class FastBhmLearner {
 public:
  /// Starts from the prior N(prior_mean, prior_variance) on every weight.
  FastBhmLearner(HingeGrid grid, const FastBhmConfig& config);
  /// Continues from an existing Fast-BHM (a robot's copy of the last global map).
  FastBhmLearner(const HingeMap& start, const FastBhmConfig& config);

  /// One sequential update with the points of one scan: xy [2 x n], occupied [n] (0/1).
  void Update(const Eigen::Ref<const Eigen::Matrix2Xd>& xy, const std::uint8_t* occupied);

  const Eigen::VectorXd& mean() const { return mean_; }
  const Eigen::VectorXd& variance() const { return variance_; }
  const HingeGrid& grid() const { return grid_; }
  HingeMap ToMap() const;

 private:
  void BoundsFromPosterior(const SparseFeatures& f);  // M-step into z_
  HingeGrid grid_;
  FastBhmConfig config_;
  Eigen::VectorXd mean_, variance_;
  // Scan buffers, reused.
  SparseFeatures features_;
  std::vector<double> z_, acc_precision_, acc_data_, prior_precision_, prior_info_;
  std::vector<int> touched_;
  std::vector<std::uint8_t> is_touched_;
};

}  // namespace foresight::occupancy
