#pragma once
/// The complete config of a SPAN predictor experiment (configs/quickstart.yaml,
/// configs/span/*.yaml). Torch-free: used by the CLI, the docs generator and the engine tools.

#include <cstdint>
#include <string>

#include "core/config.h"
#include "datasets/pedestrian_data.h"
#include "datasets/windows.h"
#include "models/span/span_config.h"
#include "training/train_config.h"

namespace foresight::span {

struct EvalConfig {
  int num_samples = 20;          ///< samples for best-of-N metrics
  std::int64_t sample_seed = 7;  ///< seed of the evaluation sampler
  int plot_tracks = 6;           ///< windows drawn in plots/samples.png
  int max_windows = 0;           ///< evaluate at most this many test windows (0: all)

  template <class A>
  void Serialize(A* a) {
    a->Visit("num_samples", &num_samples, config::Range::Closed(1, 1000), "N of best-of-N ADE/FDE");
    a->Visit("sample_seed", &sample_seed, config::Range::Any(), "seed of the evaluation sampler");
    a->Visit("plot_tracks", &plot_tracks, config::Range::Closed(0, 64), "windows drawn in the PNG");
    a->Visit("max_windows", &max_windows, config::Range::AtLeast(0),
             "cap on evaluated test windows (0: all)");
  }
};

struct ExperimentConfig {
  std::string model = "span_predictor";
  std::int64_t seed = 0;
  PedestrianDataConfig data;
  WindowConfig windows;
  TrajectoryBasisConfig basis;
  NetConfig network;
  AugmentConfig augment;
  TrainConfig train;
  /// Export fits one scale on every predicted covariance to the validation windows
  /// (training/span/calibration.h); off: the net's covariances as trained (the thesis).
  bool calibrate_covariance = false;
  EvalConfig eval;

  template <class A>
  void Serialize(A* a) {
    a->Visit("model", &model, config::Range::Any(), "model type (span_predictor)");
    a->Visit("seed", &seed, config::Range::Any(), "seed of initialisation, shuffling and splits");
    a->Visit("data", &data, config::Range::Any(), "pedestrian tracks");
    a->Visit("windows", &windows, config::Range::Any(), "observation / prediction windows");
    a->Visit("basis", &basis, config::Range::Any(), "RBF trajectory representation of futures");
    a->Visit("network", &network, config::Range::Any(), "predictor network and head");
    a->Visit("augment", &augment, config::Range::Any(),
             "training-set augmentation by speed scaling and mirroring (extension)");
    a->Visit("train", &train, config::Range::Any(), "trainer");
    a->Visit("calibrate_covariance", &calibrate_covariance, config::Range::Any(),
             "export scales every predicted covariance by the c that minimises the validation "
             "NLL (extension)");
    a->Visit("eval", &eval, config::Range::Any(), "evaluation");
  }
  /// Rules across keys; errors name `source` and the key.
  void Validate(const std::string& source) const;
};

}  // namespace foresight::span
