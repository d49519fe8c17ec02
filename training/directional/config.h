#pragma once
/// The config of a continuous directional-map experiment (configs/directional/*.yaml,
/// top-level `model: directional`): data source, kernel features, network, trainer and the
/// cross-validated evaluation against directional grid maps. Torch-free (CLI, docs generator).

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/directional.h"
#include "inference/directional/features.h"
#include "training/train_config.h"

namespace foresight::directional {

enum class Source { kCrossing, kGridCsv, kEdinburgh };
/// How K-fold cross-validation splits the samples: whole paths (every way-point of a path in one
/// fold; neighbours on a path are near-copies of each other) or single points (the thesis).
enum class FoldsBy { kPath, kPoint };

struct CrossingSection {
  CrossingFlowConfig flow;
  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("num_tracks", &flow.num_tracks, Range::Closed(1, 1000000), "pedestrian tracks");
    a->Visit("duration", &flow.duration, Range::Positive(),
             "time axis of the map (s); the flow flips halfway");
    a->Visit("size", &flow.size, Range::Positive(), "side of the square crossing (m)");
    a->Visit("speed", &flow.speed, Range::Positive(), "walking speed (m/s)");
    a->Visit("heading_noise", &flow.heading_noise, Range::NonNegative(),
             "heading noise per step (rad)");
    a->Visit("sample_period", &flow.sample_period, Range::Positive(),
             "time between samples along a track (s)");
    a->Visit("dominant_fraction", &flow.dominant_fraction, Range::Closed(0.5, 1),
             "share of the tracks of each half of the time axis that go the dominant way");
  }
};

struct FilterSection {
  HeadingFilter filter;
  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("min_speed", &filter.min_speed, Range::NonNegative(),
             "slower steps are standing, dropped (m/s)");
    a->Visit("max_speed", &filter.max_speed, Range::Positive(),
             "faster steps are tracking jumps, dropped (m/s)");
    a->Visit("max_gap", &filter.max_gap, Range::Positive(), "longer gaps break a track (s)");
    a->Visit("min_track_points", &filter.min_track_points, Range::AtLeast(0),
             "tracks with fewer points (false detections) are dropped whole");
  }
};

struct DataConfig {
  Source format = Source::kCrossing;
  std::string
      root;  ///< directory of relative file names (empty: $FORESIGHT_DATA or ../shared/data)
  std::string file;  ///< grid_csv: P1/P2 csv; edinburgh: tracks.*.txt
  double train_fraction =
      1.0;  ///< keep this random fraction of each fold's training split (5 % experiment)
  int max_samples = 0;  ///< random subsample of the whole data set (0: all)
  FilterSection edinburgh;
  CrossingSection crossing;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->VisitEnum(
        "format", &format,
        config::EnumNames<Source>{{Source::kCrossing, "crossing"},
                                  {Source::kGridCsv, "grid_csv"},
                                  {Source::kEdinburgh, "edinburgh"}},
        "crossing: synthetic time-varying flow; grid_csv: P1/P2 csv; edinburgh: tracks file");
    a->Visit("root", &root, Range::Any(),
             "directory for relative file names (empty: $FORESIGHT_DATA or ../shared/data)");
    a->Visit("file", &file, Range::Any(), "data file (grid_csv, edinburgh)");
    a->Visit("train_fraction", &train_fraction, Range::OpenClosed(0, 1),
             "random fraction f of each fold's training split that is kept (test folds stay "
             "whole); the networks "
             "then train epochs / f passes (the same number of steps), patience likewise");
    a->Visit("max_samples", &max_samples, Range::AtLeast(0),
             "random subsample of the data set (0: all)");
    a->Visit("edinburgh", &edinburgh, Range::Any(),
             "heading filter of tracked pedestrians (edinburgh)");
    a->Visit("crossing", &crossing, Range::Any(),
             "synthetic crossing whose flow flips over time (crossing)");
  }
};

struct NetworkConfig {
  int components = 5;           ///< R
  int hidden = 0;               ///< LSTM width; 0: 40 R (thesis)
  double lambda_alpha = 0.001;  ///< L2 on the mixing-weight head (added to the loss, errata)
  double lambda_mu = 0.0;
  double lambda_kappa = 0.001;
  int spatial_epochs = 0;    ///< epochs of the spatial-only network (0: train.epochs)
  double max_kappa = 100.0;  ///< cap on every concentration: networks and grid baselines alike
  int Hidden() const { return hidden > 0 ? hidden : 40 * components; }

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("components", &components, Range::Closed(1, 64), "von Mises components R");
    a->Visit("hidden", &hidden, Range::Closed(0, 4096), "LSTM width (0: 40 R as in the thesis)");
    a->Visit("lambda_alpha", &lambda_alpha, Range::NonNegative(),
             "L2 penalty on the alpha head weights");
    a->Visit("lambda_mu", &lambda_mu, Range::NonNegative(), "L2 penalty on the mu head weights");
    a->Visit("lambda_kappa", &lambda_kappa, Range::NonNegative(),
             "L2 penalty on the kappa head weights");
    a->Visit("max_kappa", &max_kappa, Range::Closed(1e-3, 1e8),
             "cap on every von Mises concentration, for the networks (log-kappa clamp) and the "
             "grid maps alike");
    a->Visit("spatial_epochs", &spatial_epochs, Range::AtLeast(0),
             "epochs of the spatial-only network (0: train.epochs); it is linear in the features "
             "and cheap");
  }
};

struct EvalConfig {
  int folds = 10;  ///< K of K-fold cross-validation
  FoldsBy folds_by = FoldsBy::kPath;
  int knn_k = 10;                ///< k of the k-nearest-neighbour baseline (1-NN always runs)
  double mre_min_weight = 0.05;  ///< mre_w: components lighter than this are ignored
  std::vector<double> metric_caps{10, 30, 100};  ///< AL also reported with kappa capped at each
  int max_folds = 0;                             ///< evaluate only the first k folds (0: all K)
  double val_fraction = 0.1;   ///< of each training split, held out for early stopping / best epoch
  bool spatiotemporal = true;  ///< train the spatiotemporal model (model.h5)
  bool spatial = true;         ///< also train the spatial-only model
  bool dense = true;           ///< also evaluate the dense grid variants
  int grid_components = 5;     ///< components of the multimodal grid map (MM)
  double grid_length_scale = 0;  ///< RBF blending of the dense grids (m); 0: the cell spacing
  bool plots = true;
  int plot_trajectories = 12;  ///< generated trajectories per panel
  double plot_step = 0;        ///< step of generated trajectories (m); 0: 1/6 of the cell spacing
  int plot_steps = 200;        ///< steps per generated trajectory (it ends where it leaves the map)

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("folds", &folds, Range::Closed(2, 100), "K of K-fold cross-validation (thesis: 10)");
    a->VisitEnum("folds_by", &folds_by,
                 config::EnumNames<FoldsBy>{{FoldsBy::kPath, "path"}, {FoldsBy::kPoint, "point"}},
                 "fold unit: whole paths (default) or single points (the thesis's protocol)");
    a->Visit("knn_k", &knn_k, Range::Closed(1, 100),
             "k of the k-nearest-neighbour baseline (knn; nn1 always runs); both use max_kappa");
    a->Visit("mre_min_weight", &mre_min_weight, Range::Closed(0, 1),
             "mre_w ignores components lighter than this (the heaviest always counts)");
    a->Visit("metric_caps", &metric_caps, Range::Positive(),
             "AL is also reported with every concentration capped at each of these (al_cap<c>)");
    a->Visit("max_folds", &max_folds, Range::AtLeast(0),
             "evaluate only the first k folds (0: all)");
    a->Visit("val_fraction", &val_fraction, Range::Open(0, 1),
             "fraction of each training split held out for early stopping and the best epoch");
    a->Visit("spatiotemporal", &spatiotemporal, Range::Any(),
             "train and evaluate the spatiotemporal model (off: spatial only, e.g. for sweeps on "
             "untimed data)");
    a->Visit("spatial", &spatial, Range::Any(), "also train and evaluate the spatial-only model");
    a->Visit("dense", &dense, Range::Any(),
             "also evaluate the dense grid variants (grid_um_dense, grid_mm_dense)");
    a->Visit("grid_components", &grid_components, Range::Closed(1, 64),
             "components of the MM grid map");
    a->Visit("grid_length_scale", &grid_length_scale, Range::NonNegative(),
             "RBF blending length of the dense grids (m; 0: the cell spacing)");
    a->Visit("plots", &plots, Range::Any(),
             "write plots/directions.png and plots/trajectories.png");
    a->Visit("plot_trajectories", &plot_trajectories, Range::Closed(0, 1000),
             "generated trajectories per panel");
    a->Visit("plot_step", &plot_step, Range::NonNegative(),
             "step of generated trajectories (m; 0: cell / 6)");
    a->Visit("plot_steps", &plot_steps, Range::Closed(1, 100000), "steps per generated trajectory");
  }
};

struct ExperimentConfig {
  std::string model = "directional";
  std::int64_t seed = 0;
  DataConfig data;
  FeatureConfig features;
  NetworkConfig network;
  TrainConfig train;
  EvalConfig eval;

  template <class A>
  void Serialize(A* a) {
    a->Visit("model", &model, config::Range::Any(), "model type (directional)");
    a->Visit("seed", &seed, config::Range::Any(),
             "seed of data generation, folds, initialisation and shuffling");
    a->Visit("data", &data, config::Range::Any(), "direction samples (x, y, t, theta)");
    a->Visit("features", &features, config::Range::Any(),
             "spatial and temporal inducing points (RBF features)");
    a->Visit("network", &network, config::Range::Any(), "LSTM and von Mises mixture heads");
    a->Visit("train", &train, config::Range::Any(), "trainer");
    a->Visit("eval", &eval, config::Range::Any(), "cross-validated evaluation and plots");
  }
  /// Rules across keys; errors name `source` and the key.
  void Validate(const std::string& source) const;
};

}  // namespace foresight::directional
