#pragma once
/// The config of an occupancy-map experiment (configs/occupancy/*.yaml): where the scans come
/// from, how they become labelled points and splits, the feature grid and the learner of each map
/// kind, fusion, export and evaluation. Torch-free.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/hinge_grid.h"
#include "datasets/occupancy_points.h"
#include "datasets/synthetic_floorplan.h"
#include "inference/mapping/fusion.h"
#include "inference/mapping/hinge_map.h"
#include "models/occupancy/fast_bhm.h"
#include "models/occupancy/grid_builder.h"
#include "models/occupancy/hilbert_map.h"

namespace foresight::occupancy {

enum class ScanSource { kCarmen, kSynthetic };

struct DataConfig {
  ScanSource format = ScanSource::kSynthetic;
  std::string
      root;  ///< directory of relative file names (empty: $FORESIGHT_DATA or ../shared/data)
  std::string file;  ///< CARMEN log (format: carmen)
  OccupancyPointsConfig points;
  int test_every = 10;  ///< scan i is a test scan when i % test_every == test_offset
  int test_offset = 9;
  int train_scan_stride = 1;  ///< train on every k-th training scan (10: the sparse case)
  int val_every = 0;          ///< > 0: every val_every-th training scan is held out for validation
  SyntheticFloorplanConfig synthetic;

  template <class A>
  void Serialize(A* a) {
    a->VisitEnum("format", &format,
                 config::EnumNames<ScanSource>{{ScanSource::kCarmen, "carmen"},
                                               {ScanSource::kSynthetic, "synthetic"}},
                 "source of the laser scans");
    a->Visit("root", &root, config::Range::Any(),
             "directory for relative file names (empty: $FORESIGHT_DATA or ../shared/data)");
    a->Visit("file", &file, config::Range::Any(), "CARMEN log (format: carmen)");
    a->Visit("points", &points, config::Range::Any(), "labelled points from beams");
    a->Visit("test_every", &test_every, config::Range::Closed(2, 1000),
             "every k-th scan is a test scan");
    a->Visit("test_offset", &test_offset, config::Range::AtLeast(0),
             "which scan of each k is the test scan");
    a->Visit("train_scan_stride", &train_scan_stride, config::Range::Closed(1, 1000),
             "train on every k-th training scan only (sparse case: 10)");
    a->Visit("val_every", &val_every, config::Range::Closed(0, 1000),
             "> 0: hold out every k-th training scan for validation (hyper-parameter choice)");
    a->Visit("synthetic", &synthetic, config::Range::Any(),
             "simulated floor plan and robots (format: synthetic)");
  }
};

struct FusionExperimentConfig {
  enum class Robots { kQuadrants, kRecorded };
  Robots robots = Robots::kQuadrants;  ///< how scans are assigned to robots
  double centre_x = 0, centre_y = 0;   ///< quadrant centre (m)
  int merges = 4;  ///< repeated fusion after each 1/merges of every robot's data
  FusionOptions options;

  template <class A>
  void Serialize(A* a) {
    a->VisitEnum("robots", &robots,
                 config::EnumNames<Robots>{{Robots::kQuadrants, "quadrants"},
                                           {Robots::kRecorded, "recorded"}},
                 "robots of the scans: quadrant of the mean hit point, or as recorded (synthetic)");
    a->Visit("centre_x", &centre_x, config::Range::Any(), "quadrant centre x (m)");
    a->Visit("centre_y", &centre_y, config::Range::Any(), "quadrant centre y (m)");
    a->Visit("merges", &merges, config::Range::Closed(1, 100), "number of repeated merges");
    a->Visit("variance_threshold", &options.variance_threshold, config::Range::Positive(),
             "local weight estimates with a variance at or above this are left out of a merge");
  }
};

struct EvalConfig {
  double plot_resolution = 0.1;  ///< m per pixel of plots/map.png
  int roc_points = 200;          ///< rows of roc.csv

  template <class A>
  void Serialize(A* a) {
    a->Visit("plot_resolution", &plot_resolution, config::Range::Positive(),
             "m per pixel of the map PNG");
    a->Visit("roc_points", &roc_points, config::Range::Closed(2, 100000), "rows of roc.csv");
  }
};

struct ExperimentConfig {
  /// occupancy.fast_bhm | occupancy.bhm | occupancy.hilbert | occupancy.grid | occupancy.fusion
  std::string model = "occupancy.fast_bhm";
  std::int64_t seed = 0;
  DataConfig data;
  HingeGridConfig features;
  FastBhmConfig fast_bhm;
  HilbertMapConfig hilbert;
  GridMapConfig grid;
  FusionExperimentConfig fusion;
  StoredPrecision precision = StoredPrecision::kFloat32;
  EvalConfig eval;

  template <class A>
  void Serialize(A* a) {
    a->Visit("model", &model, config::Range::Any(),
             "occupancy.fast_bhm | occupancy.bhm | occupancy.hilbert | occupancy.grid | "
             "occupancy.fusion");
    a->Visit("seed", &seed, config::Range::Any(), "seed of point sampling and SGD order");
    a->Visit("data", &data, config::Range::Any(), "scans, labelled points and splits");
    a->Visit("features", &features, config::Range::Any(),
             "hinge feature grid (Hilbert maps, BHMs)");
    a->Visit("fast_bhm", &fast_bhm, config::Range::Any(), "Fast-BHM / BHM variational EM");
    a->Visit("hilbert", &hilbert, config::Range::Any(), "Hilbert map SGD");
    a->Visit("grid", &grid, config::Range::Any(), "occupancy grid baseline");
    a->Visit("fusion", &fusion, config::Range::Any(),
             "multi-robot fusion (model: occupancy.fusion)");
    a->VisitEnum("precision", &precision,
                 config::EnumNames<StoredPrecision>{{StoredPrecision::kFloat32, "float32"},
                                                    {StoredPrecision::kFloat64, "float64"}},
                 "floating-point type of the stored weights");
    a->Visit("eval", &eval, config::Range::Any(), "evaluation outputs");
  }
  /// Rules across keys; errors name `source` and the key.
  void Validate(const std::string& source) const;
};

}  // namespace foresight::occupancy
