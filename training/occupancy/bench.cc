// The occupancy kind's bench (`foresight bench CONFIG|RUN_DIR`): occupancy-map figures measured
// side by side in one run on one thread: Fast-BHM training time on the full training set, the full
// BHM on a coarser grid against Fast-BHM on that same grid and data, engine query throughput
// (probability, gradient and variance), and OctoMap (insertion time, serialized size, memory, AUC).

#include "core/bench.h"

#include <algorithm>
#include <iostream>
#include <memory>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "inference/mapping/hinge_map.h"
#include "models/occupancy/bhm.h"
#include "models/occupancy/fast_bhm.h"
#include "models/occupancy/scan_training.h"
#include "training/kinds.h"
#include "training/occupancy/octomap_baseline.h"
#include "training/occupancy/pipeline.h"

namespace foresight::occupancy {
namespace {

using bench::MedianSeconds;

struct BenchOptions {
  int repeats = 5;
  double bhm_spacing = 1.0;
  int bhm_scans = 40;
  double octomap_resolution = 0.1;

  template <class A>
  void Serialize(A* a) {
    a->Visit("repeats", &repeats, config::Range::Closed(1, 100), "timed runs (median reported)");
    a->Visit("bhm_spacing", &bhm_spacing, config::Range::Positive(),
             "feature spacing of the full-BHM comparison (m)");
    a->Visit("bhm_scans", &bhm_scans, config::Range::Closed(1, 100000),
             "training scans of the full-BHM comparison");
    a->Visit("octomap_resolution", &octomap_resolution, config::Range::Positive(),
             "OctoMap voxel size (m)");
  }
};

void RunBench(const BenchRequest& req, const BenchOptions& a) {
  const auto c = LoadBenchConfig<ExperimentConfig>(req);
  const Data data = LoadData(c);
  const HingeGrid grid(c.features);

  // Fast-BHM on the full training set.
  std::unique_ptr<HingeMap> map;
  const double fast_s = MedianSeconds(a.repeats, [&] {
    FastBhmLearner l(grid, c.fast_bhm);
    UpdateOnScans(&l, data.train, FirstScans(data.train));
    map = std::make_unique<HingeMap>(l.ToMap());
  });
  const double fast_auc = EvaluateMap(*map, data.test).auc;
  const std::int64_t fast_bytes = ArtifactBytes(*map, c);

  // Full BHM against Fast-BHM on the same coarser grid and the first bhm_scans training scans.
  HingeGridConfig coarse = c.features;
  const double ratio = a.bhm_spacing / c.features.spacing;
  coarse.spacing = a.bhm_spacing;
  coarse.gamma = c.features.gamma / (ratio * ratio);  // same overlap between neighbouring features
  coarse.cutoff_radius = c.features.cutoff_radius * ratio;
  const HingeGrid bhm_grid(coarse);
  const int scans = std::min(a.bhm_scans, data.train.num_scans());
  const double bhm_s = MedianSeconds(1, [&] {
    BhmLearner l(bhm_grid, c.fast_bhm);
    UpdateOnScans(&l, data.train, FirstScans(data.train, scans));
  });
  const double fast_same_s = MedianSeconds(a.repeats, [&] {
    FastBhmLearner l(bhm_grid, c.fast_bhm);
    UpdateOnScans(&l, data.train, FirstScans(data.train, scans));
  });

  // Query throughput: probability + gradient + variance over the test points, one thread.
  MapWorkspace ws = map->MakeWorkspace();
  double sink = 0;
  const std::int64_t n = data.test.size();
  const int passes = std::max<std::int64_t>(1, 2000000 / std::max<std::int64_t>(n, 1));
  const double query_s = MedianSeconds(a.repeats, [&] {
    for (int p = 0; p < passes; ++p)
      for (std::int64_t i = 0; i < n; ++i) {
        const QueryResult q = map->Query(data.test.xy(0, i), data.test.xy(1, i), &ws);
        sink += q.probability + q.dp_dx + q.variance;
      }
  });
  const double query_pps = static_cast<double>(n) * passes / query_s;

  const OctomapFigures octo =
      RunOctomapBaseline(data, c.data.points.max_range, a.octomap_resolution, a.repeats);

  std::ostringstream j;
  j << "{\"train_points\": " << data.train.size() << ", \"fast_bhm_train_s\": " << fast_s
    << ", \"fast_bhm_auc\": " << fast_auc << ", \"fast_bhm_bytes\": " << fast_bytes
    << ", \"bhm_train_s\": " << bhm_s << ", \"bhm_grid\": \"" << bhm_grid.Describe()
    << "\", \"bhm_scans\": " << scans << ", \"fast_bhm_same_grid_s\": " << fast_same_s
    << ", \"bhm_over_fast_bhm\": " << bhm_s / fast_same_s
    << ", \"query_points_per_s\": " << query_pps
    << ", \"octomap_resolution\": " << a.octomap_resolution
    << ", \"octomap_train_s\": " << octo.insert_s << ", \"octomap_auc\": " << octo.auc
    << ", \"octomap_bytes\": " << octo.bytes << ", \"octomap_memory_bytes\": " << octo.memory
    << ", \"repeats\": " << a.repeats << ", \"checksum\": " << (sink != 0 ? 1 : 0) << "}";
  if (req.json) {
    std::cout << j.str() << "\n";
    return;
  }
  std::cout << "Fast-BHM: trains " << data.train.size() << " points in " << fast_s << " s (AUC "
            << fast_auc << ", " << fast_bytes << " bytes)\n"
            << "full BHM: " << bhm_s << " s vs Fast-BHM " << fast_same_s << " s on " << scans
            << " scans, grid " << bhm_grid.Describe() << " (ratio " << bhm_s / fast_same_s << ")\n"
            << "query (p, gradient, variance): " << query_pps / 1e6 << " M points/s on one thread\n"
            << "OctoMap " << a.octomap_resolution << " m: inserts in " << octo.insert_s << " s, "
            << octo.bytes << " bytes serialized, " << octo.memory << " bytes in memory, AUC "
            << octo.auc << "\n";
}

}  // namespace

void SetBenchStep(ExperimentKind* kind) { SetBench<BenchOptions>(kind, RunBench); }

}  // namespace foresight::occupancy
