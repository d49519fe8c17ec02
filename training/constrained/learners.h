#pragma once
/// The three learners of structurally constrained prediction (thesis ch 7, "Learning
/// continuous-time trajectory distributions as priors"), trained from given windows:
///   - the prior: the SPAN net with an R-component mixture head (diagonal U), trained by the
///     mixture NLL of the ridge targets (training/span/pipeline.h), served by SpanPredictor;
///   - KTM (Kernel Trajectory Maps, Zhi et al. 2019): kernel similarities of the observed segment
///     to K reference segments, then the same mixture head; served by SpanPredictor's KTM stage;
///   - the naive network: ReLU MLP 560 -> 180 -> 180 -> 2f, MSE on ego-frame futures; served by
///     NaivePredictor (inference/prediction/naive_predictor.h).
/// Torch-free header.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/windows.h"
#include "models/span/span_config.h"
#include "training/train_config.h"

namespace foresight {
struct TrainHooks;  // training/trainer.h
}

namespace foresight::constrained {

/// What the learners share: windows of `observed` + `predicted` points every `seconds_per_step`.
struct LearnerSpec {
  int observed = 10, predicted = 15;
  double seconds_per_step = 0.4;  ///< s; must equal the windows' step
  std::int64_t seed = 0;
  span::TrajectoryBasisConfig basis;  ///< the future basis of the prior and KTM heads
  span::NetConfig network;  ///< the prior's net; components R (thesis 2), u_param must be diagonal
  TrainConfig train;        ///< epochs, patience, lr, ... of every learner
};

/// Kernel Trajectory Maps. Features of an observed segment q (ego frame, 2p numbers):
/// k(q, r_i) = exp(-d(q, r_i)^2 / (2 l^2)), d = RMS pointwise distance between the synchronous
/// segments, d^2 = (1/p) sum_j |q_j - r_{i,j}|^2 (KTM's trajectory distance, here on segments
/// that share length and sampling, so the pointwise RMS is the natural choice; l is in metres).
/// References: farthest-point sampling of the training segments under d, starting from a
/// seed-chosen window (covers the observed motions evenly; deterministic for a seed).
struct KtmSpec {
  int references = 100;      ///< K reference segments (at most the training windows)
  double lengthscale = 1.0;  ///< l (m)

  template <class A>
  void Serialize(A* a) {
    a->Visit("references", &references, config::Range::Closed(1, 100000),
             "K, reference segments chosen from the training windows (farthest-point)");
    a->Visit("lengthscale", &lengthscale, config::Range::Positive(),
             "l (m) of the kernel exp(-d^2 / (2 l^2)), d = RMS pointwise distance");
  }
};

/// The naive network's hidden ReLU layers (thesis: 560, 180, 180).
struct NaiveSpec {
  std::vector<int> hidden = {560, 180, 180};

  template <class A>
  void Serialize(A* a) {
    a->Visit("hidden", &hidden, config::Range::Closed(1, 4096), "hidden layer widths (ReLU)");
  }
};

/// Each trains in `dir` (dir/checkpoints, dir/metrics.csv, dir/normalisation.h5; KTM also
/// dir/ktm_references.h5; resumable with the trainer's resume: resume = true continues from dir's
/// last checkpoint), then writes `artifact` from the best checkpoint. Returns false when
/// interrupted (hooks.interrupt or hooks.continue_after_epoch) — then no artifact is written.
/// `config_yaml` is stored in the artifact. Errors: no train/val windows, windows of another
/// shape or step than `spec`, u_param not diagonal (prior), more KTM references than windows.
bool TrainPrior(const LearnerSpec& spec, const WindowSet& train, const WindowSet& val,
                const std::string& dir, bool resume, const TrainHooks& hooks,
                const std::string& artifact, const std::string& config_yaml);
bool TrainKtm(const LearnerSpec& spec, const KtmSpec& ktm, const WindowSet& train,
              const WindowSet& val, const std::string& dir, bool resume, const TrainHooks& hooks,
              const std::string& artifact, const std::string& config_yaml);
bool TrainNaive(const LearnerSpec& spec, const NaiveSpec& naive, const WindowSet& train,
                const WindowSet& val, const std::string& dir, bool resume, const TrainHooks& hooks,
                const std::string& artifact, const std::string& config_yaml);

/// Write `artifact` from the best checkpoint (else the last) in `dir` of a learner trained there
/// with the same spec (the export step; training calls them at its end). Missing checkpoints,
/// normalisation or KTM references are Errors naming the file.
void ExportPrior(const LearnerSpec& spec, const std::string& dir, const std::string& artifact,
                 const std::string& config_yaml);
void ExportKtm(const LearnerSpec& spec, const KtmSpec& ktm, const std::string& dir,
               const std::string& artifact, const std::string& config_yaml);
void ExportNaive(const LearnerSpec& spec, const NaiveSpec& naive, const std::string& dir,
                 const std::string& artifact, const std::string& config_yaml);
/// KTM features [N x K] of ego-frame segments `ego_past` [N x 2p] (x_1, y_1, ...) against
/// `references` [K x 2p]: exp(-d^2 / (2 l^2)), d^2 = (1/p) sum_j |q_j - r_j|^2.
Eigen::MatrixXd KtmFeatures(const Eigen::MatrixXd& ego_past, const Eigen::MatrixXd& references,
                            double lengthscale);
/// `count` rows of `ego_past` [N x 2p] by farthest-point sampling under d, the first chosen
/// uniformly with `seed`; ties go to the lowest index. count <= N (an Error otherwise).
Eigen::MatrixXd ChooseKtmReferences(const Eigen::MatrixXd& ego_past, int count, std::int64_t seed);

}  // namespace foresight::constrained
