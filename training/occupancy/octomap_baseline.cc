#include "training/occupancy/octomap_baseline.h"

#include <octomap/octomap.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

namespace foresight::occupancy {

OctomapFigures RunOctomapBaseline(const Data& data, double max_range, double resolution,
                                  int repeats) {
  OctomapFigures f;
  std::unique_ptr<octomap::OcTree> tree;
  std::vector<double> times;
  for (int r = 0; r < std::max(1, repeats); ++r) {
    const auto start = std::chrono::steady_clock::now();
    tree = std::make_unique<octomap::OcTree>(resolution);
    for (const int s : data.train_scans) {
      const LaserScan& scan = data.scans[s];
      octomap::Pointcloud cloud;
      for (int b = 0; b < scan.num_beams(); ++b) {
        const double range = scan.ranges[b];
        if (!(range > 0 && range < max_range)) continue;
        const double a = scan.BeamAngle(b);
        cloud.push_back(static_cast<float>(scan.x + range * std::cos(a)),
                        static_cast<float>(scan.y + range * std::sin(a)), 0.0f);
      }
      tree->insertPointCloud(
          cloud, octomap::point3d(static_cast<float>(scan.x), static_cast<float>(scan.y), 0.0f));
    }
    times.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  f.insert_s = times[times.size() / 2];
  std::ostringstream bin;
  tree->writeBinaryConst(bin);
  f.bytes = static_cast<std::int64_t>(bin.str().size());
  f.memory = static_cast<std::int64_t>(tree->memoryUsage());
  std::vector<double> scores(data.test.size());
  for (std::int64_t i = 0; i < data.test.size(); ++i) {
    const octomap::OcTreeNode* n = tree->search(data.test.xy(0, i), data.test.xy(1, i), 0.0);
    scores[i] = n ? n->getOccupancy() : 0.5;
  }
  const BinaryMetrics m = EvaluateBinary(scores, data.test.occupied);
  f.auc = m.auc;
  f.precision = m.precision;
  f.recall = m.recall;
  return f;
}

}  // namespace foresight::occupancy
