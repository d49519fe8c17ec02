#pragma once
/// The config of an OTNet run (thesis ch 6): the maps and their trajectories (Occ-Traj120 or the
/// synthetic rooms), the map-level split, the map encoding, the trajectory basis, the mixture
/// density network and its training, the evaluation against k-NN and the mean trajectory, and the
/// optional transfer to sections of a real occupancy map. `foresight train
/// configs/otnet/<name>.yaml`. Torch-free.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "training/train_config.h"

namespace foresight::otnet {

enum class Source { kOccTraj, kSynthetic };
enum class Family { kNormal, kLaplace };
enum class BadWaypoints { kDrop, kError };
/// Symmetric copies of the training maps: none, or the 8 symmetries of the square (dihedral).
enum class Augment { kNone, kDihedral };

struct DataConfig {
  Source source = Source::kSynthetic;
  std::string root;   ///< occ_traj: <root>/occ_traj120; empty: $FORESIGHT_DATA, ../shared/data
  int map_size = 40;  ///< maps are map_size x map_size cells
  int max_maps = 0;   ///< occ_traj: use the first n ids (sorted) before splitting; 0: all
  int max_trajectories = 0;  ///< per map, the first n; 0: all
  BadWaypoints bad_waypoints = BadWaypoints::kDrop;
  double val_fraction = 0.1;   ///< share of the maps for validation (model selection)
  double test_fraction = 0.2;  ///< share of the maps for the test (thesis: 80-20)
  int synthetic_maps = 60;
  int synthetic_trajectories = 50;
  int synthetic_layouts =
      12;  ///< layout families (SyntheticRoomsOptions::layouts); 0: all distinct
  /// Training maps only: each map and its trajectories also in its 7 other orientations (rotations
  /// by multiples of 90 degrees and reflections). Validation and test maps are never transformed.
  Augment augment = Augment::kNone;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->VisitEnum("source", &source,
                 config::EnumNames<Source>{{Source::kOccTraj, "occ_traj"},
                                           {Source::kSynthetic, "synthetic"}},
                 "occ_traj (../shared/data/occ_traj120) or synthetic rooms and corridors");
    a->Visit("root", &root, Range::Any(), "data root; empty: $FORESIGHT_DATA, else ../shared/data");
    a->Visit("map_size", &map_size, Range::Closed(8, 4096), "maps are map_size x map_size cells");
    a->Visit("max_maps", &max_maps, Range::Closed(0, 1000000),
             "occ_traj: only the first n map ids (sorted), before the split; 0: all");
    a->Visit("max_trajectories", &max_trajectories, Range::Closed(0, 1000000),
             "per map, only the first n trajectories; 0: all");
    a->VisitEnum("bad_waypoints", &bad_waypoints,
                 config::EnumNames<BadWaypoints>{{BadWaypoints::kDrop, "drop"},
                                                 {BadWaypoints::kError, "error"}},
                 "a trajectory with a waypoint outside the map or in an occupied cell: drop it "
                 "(counted in the log) or stop with an error");
    a->Visit("val_fraction", &val_fraction, Range::Closed(0, 0.9), "share of maps for validation");
    a->Visit("test_fraction", &test_fraction, Range::Closed(0, 0.9), "share of maps for the test");
    a->Visit("synthetic_maps", &synthetic_maps, Range::Closed(3, 100000), "synthetic maps");
    a->Visit("synthetic_trajectories", &synthetic_trajectories, Range::Closed(1, 100000),
             "trajectories per synthetic map");
    a->Visit(
        "synthetic_layouts", &synthetic_layouts, Range::Closed(0, 100000),
        "synthetic layout families (maps of a family differ by a few pillars); 0: all distinct");
    a->VisitEnum(
        "augment", &augment,
        config::EnumNames<Augment>{{Augment::kNone, "none"}, {Augment::kDihedral, "dihedral"}},
        "training maps only: none, or dihedral (each map and its trajectories also "
        "rotated by 90/180/270 degrees and reflected: 8 copies; the encoder's database "
        "keeps the maps as read)");
  }
};

struct ModelConfig {
  // Map encoding: S_H = exp(-delta_H^2 / (2 l_H)); thesis: l_H = 50 and all training maps.
  double length_scale = 50;  ///< l_H (squared cells)
  /// Representative maps: 0 = every training map (thesis); n > 0 = n training maps chosen by
  /// farthest-point sampling on delta_H (greedy k-centre from the first map), which spreads the
  /// database over the space of maps.
  int database_size = 0;
  // Trajectory basis: M Gaussian RBFs on tau in [0, 1]; thesis M = 15. The thesis's l_b = 5 has
  // no stated form; the width is set by gamma (exp(-gamma (tau - c)^2)), default ~ one centre
  // spacing.
  int basis = 15;
  double basis_gamma = 100;
  double ridge = 1e-3;
  // The mixture density network; thesis Q = 4.
  int components = 4;
  std::vector<int> hidden{256, 256};
  double dropout = 0.0;
  Family family = Family::kNormal;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("length_scale", &length_scale, Range::Positive(), "l_H of the map similarity");
    a->Visit("database_size", &database_size, Range::Closed(0, 1000000),
             "representative maps: 0 = all training maps, n = farthest-point subset");
    a->Visit("basis", &basis, Range::Closed(2, 200), "M, RBFs per coordinate");
    a->Visit("basis_gamma", &basis_gamma, Range::Positive(), "RBF width: exp(-gamma (tau - c)^2)");
    a->Visit("ridge", &ridge, Range::Closed(0, 1e6), "ridge penalty of the weight fit");
    a->Visit("components", &components, Range::Closed(1, 64), "Q, mixture components");
    a->Visit("hidden", &hidden, Range::Any(), "hidden layer widths of the MLP");
    a->Visit("dropout", &dropout, Range::Closed(0, 0.95), "dropout after each hidden layer");
    a->VisitEnum(
        "family", &family,
        config::EnumNames<Family>{{Family::kNormal, "normal"}, {Family::kLaplace, "laplace"}},
        "mean-field component family");
  }
};

struct EvalConfig {
  int generated = 100;           ///< trajectories generated per test map
  int points = 100;              ///< resampling of every trajectory (thesis: 100)
  int max_attempts = 5000;       ///< samples drawn at most per map (collision rejection)
  double check_step = 0.25;      ///< collision check spacing (cells)
  double variance_floor = 0.05;  ///< added to fitted per-time variances (cells^2; k-NN, mean)
  bool conditioned = true;       ///< also score start-conditioned generation
  bool plots = true;
  int plot_maps = 6;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("generated", &generated, Range::Closed(1, 100000), "trajectories generated per map");
    a->Visit("points", &points, Range::Closed(2, 100000), "points per trajectory (uniform tau)");
    a->Visit("max_attempts", &max_attempts, Range::Closed(1, 100000000),
             "samples drawn at most per map");
    a->Visit("check_step", &check_step, Range::Positive(), "collision check spacing (cells)");
    a->Visit("variance_floor", &variance_floor, Range::Positive(),
             "variance added to fitted per-time Gaussians (cells^2)");
    a->Visit("conditioned", &conditioned, Range::Any(),
             "also score generation conditioned on each test map's mean start");
    a->Visit("plots", &plots, Range::Any(), "write PNGs of generated trajectories");
    a->Visit("plot_maps", &plot_maps, Range::Closed(1, 100), "test maps in the picture");
  }
};

/// Generate on sections of a real occupancy map (thesis Fig. TransferEx): each section is
/// rasterised to map_size x map_size cells (p(occupied) >= threshold is occupied).
struct TransferConfig {
  std::string occupancy_artifact;  ///< an occupancy-map artifact (model.h5); empty: no transfer
  std::vector<double> sections;    ///< x_min, y_min, side (m) per section, flat
  std::vector<double> starts;      ///< start points (cells of the section), x, y pairs, flat
  int openings = 2;                ///< with no starts: the longest border openings (BorderOpenings)
  double threshold = 0.5;
  int generated = 30;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("occupancy_artifact", &occupancy_artifact, Range::Any(),
             "occupancy-map artifact to transfer to; empty: no transfer");
    a->Visit("sections", &sections, Range::Any(), "x_min, y_min, side (m) per section, flat");
    a->Visit("starts", &starts, Range::Any(),
             "start points in section cells, x, y pairs, flat (moved to the nearest free cell); "
             "empty: the section's border openings");
    a->Visit("openings", &openings, Range::Closed(1, 100),
             "with no starts: start at this many of the longest border openings");
    a->Visit("threshold", &threshold, Range::Closed(0, 1), "p(occupied) at or above is occupied");
    a->Visit("generated", &generated, Range::Closed(1, 100000), "trajectories per start");
  }
};

struct ExperimentConfig {
  std::string model = "otnet";
  std::int64_t seed = 0;
  DataConfig data;
  ModelConfig otnet;
  TrainConfig train = [] {
    TrainConfig t;
    t.epochs = 100;
    t.batch_size = 256;
    t.learning_rate = 1e-3;
    t.patience = 15;
    t.progress = ProgressStyle::kNone;
    return t;
  }();
  EvalConfig eval;
  TransferConfig transfer;

  template <class A>
  void Serialize(A* a) {
    using config::Range;
    a->Visit("model", &model, Range::Any(), "experiment type (otnet)");
    a->Visit("seed", &seed, Range::Any(), "seed of the split, the network and the sampling");
    a->Visit("data", &data, Range::Any(), "maps and trajectories");
    a->Visit("otnet", &otnet, Range::Any(), "encoding, basis and network");
    a->Visit("train", &train, Range::Any(), "trainer settings");
    a->Visit("eval", &eval, Range::Any(), "evaluation");
    a->Visit("transfer", &transfer, Range::Any(), "transfer to a real occupancy map");
  }
  void Validate(const std::string& source) const;
};

}  // namespace foresight::otnet
