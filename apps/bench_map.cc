// `foresight bench map --config CONFIG [--json]`: occupancy-map figures measured side by side in
// one run on one thread: Fast-BHM training time on the full training set, the full BHM on a
// coarser grid against Fast-BHM on that same grid and data, engine query throughput (probability,
// gradient and variance), and OctoMap (insertion time, serialized size, memory, AUC).

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "apps/commands.h"
#include "core/error.h"
#include "core/log.h"
#include "inference/mapping/hinge_map.h"
#include "models/occupancy/bhm.h"
#include "models/occupancy/fast_bhm.h"
#include "models/occupancy/scan_training.h"
#include "training/experiment.h"
#include "training/occupancy/octomap_baseline.h"
#include "training/occupancy/pipeline.h"

namespace foresight::app {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct BenchMapArgs {
  std::string config;
  std::vector<std::string> overrides;
  bool json = false;
  int repeats = 5;
  double bhm_spacing = 1.0;
  int bhm_scans = 40;
  double octomap_resolution = 0.1;
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double TimeMedian(int repeats, F&& f) {
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto s = Clock::now();
    f();
    t.push_back(std::chrono::duration<double>(Clock::now() - s).count());
  }
  return Median(t);
}

void RunMapBench(const BenchMapArgs& a) {
  FS_THROW_UNLESS(ModelTagOfFile(a.config).rfind("occupancy.", 0) == 0, a.config,
                  ": not an occupancy config (model: occupancy.*)");
  OccupancyExperimentConfig c =
      config::LoadExperimentConfig<OccupancyExperimentConfig>(a.config, a.overrides);
  const OccupancyData data = LoadOccupancyData(c);
  const HingeGrid grid(c.features);

  // Fast-BHM on the full training set.
  std::unique_ptr<HingeMap> map;
  const double fast_s = TimeMedian(a.repeats, [&] {
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
  const double bhm_s = TimeMedian(1, [&] {
    BhmLearner l(bhm_grid, c.fast_bhm);
    UpdateOnScans(&l, data.train, FirstScans(data.train, scans));
  });
  const double fast_same_s = TimeMedian(a.repeats, [&] {
    FastBhmLearner l(bhm_grid, c.fast_bhm);
    UpdateOnScans(&l, data.train, FirstScans(data.train, scans));
  });

  // Query throughput: probability + gradient + variance over the test points, one thread.
  MapWorkspace ws = map->MakeWorkspace();
  double sink = 0;
  const std::int64_t n = data.test.size();
  const int passes = std::max<std::int64_t>(1, 2000000 / std::max<std::int64_t>(n, 1));
  const double query_s = TimeMedian(a.repeats, [&] {
    for (int p = 0; p < passes; ++p)
      for (std::int64_t i = 0; i < n; ++i) {
        const OccupancyQuery q = map->Query(data.test.xy(0, i), data.test.xy(1, i), &ws);
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
  if (a.json) {
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

void AddBenchMapCommand(CLI::App* bench) {
  auto a = std::make_shared<BenchMapArgs>();
  auto* cmd = bench->add_subcommand(
      "map", "occupancy maps: Fast-BHM vs full BHM vs OctoMap, query throughput");
  cmd->add_option("--config", a->config, "occupancy config (e.g. configs/occupancy/intel.yaml)")
      ->required();
  cmd->add_option("overrides", a->overrides, "key.path=value overrides of the config");
  cmd->add_flag("--json", a->json, "print one JSON object");
  cmd->add_option("--repeats", a->repeats, "timed repetitions (median reported)")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--bhm-spacing", a->bhm_spacing, "feature spacing of the full-BHM comparison (m)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--bhm-scans", a->bhm_scans, "training scans of the full-BHM comparison")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--octomap-resolution", a->octomap_resolution, "OctoMap voxel size (m)")
      ->check(CLI::PositiveNumber);
  cmd->callback([a] { RunMapBench(*a); });
}

}  // namespace foresight::app
