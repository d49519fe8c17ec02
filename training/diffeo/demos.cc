#include "training/diffeo/demos.h"

#include <algorithm>
#include <string>

#include "core/error.h"
#include "datasets/data_root.h"
#include "datasets/lasa.h"
#include "datasets/synthetic_demos.h"

namespace foresight::imitation {
namespace {

bool Contains(const std::vector<int>& v, int i) {
  return std::find(v.begin(), v.end(), i) != v.end();
}

/// `all` without the demos of data.excluded (dropped before anything reads them); fills p's train,
/// held_out (indices into the kept demos) and original (each kept demo's index in `all`).
DemoSet WithoutExcluded(const ExperimentConfig& c, const DemoSet& all, PreparedDemos* p) {
  const int n = static_cast<int>(all.demos.size());
  for (const auto& [key, ids] :
       {std::pair{"data.held_out", &c.data.held_out}, std::pair{"data.excluded", &c.data.excluded}})
    for (int i : *ids)
      FS_THROW_UNLESS(i < n, all.name, ": ", key, ": demo ", i, " does not exist (", n, " demos)");
  DemoSet kept{all.name, all.dimension, {}};
  for (int i = 0; i < n; ++i) {
    if (Contains(c.data.excluded, i)) continue;
    const int k = static_cast<int>(kept.demos.size());
    (Contains(c.data.held_out, i) ? p->held_out : p->train).push_back(k);
    kept.demos.push_back(all.demos[static_cast<std::size_t>(i)]);
    p->original.push_back(i);
  }
  FS_THROW_UNLESS(!p->train.empty(), all.name,
                  ": no demo left to train on after data.excluded and data.held_out (", n,
                  " demos)");
  return kept;
}

PreparedDemos Prepare(const ExperimentConfig& c, const DemoSet& all) {
  PreparedDemos p;
  const DemoSet raw = WithoutExcluded(c, all, &p);
  p.name = raw.name;
  try {
    p.spread = CheckDemonstrations(raw, c.data.goal_tolerance);
  } catch (const Error& e) {
    if (c.data.excluded.empty()) throw;
    std::string kept;
    for (int i : p.original) kept += (kept.empty() ? "" : ", ") + std::to_string(i);
    Fail(e.what(), " (demo numbers count the demos kept after data.excluded: the data's [", kept,
         "])");
  }
  const auto [train_set, held_set] = SplitByDemo(raw, p.held_out);
  (void)held_set;
  p.norm = FitNormalisation(train_set, c.data.half_range);
  p.demos = ApplyNormalisation(Downsample(raw, c.data.downsample), p.norm);
  return p;
}

}  // namespace

std::vector<PreparedDemos> LoadDemos(const ExperimentConfig& c) {
  std::vector<DemoSet> sets;
  switch (c.data.source) {
    case DemoSource::kLasa: {
      const std::string dir = ResolveDataFile(c.data.root, "lasa_handwriting");
      std::vector<std::string> shapes = c.data.shapes;
      if (shapes.size() == 1 && shapes[0] == "all") shapes = ListLasaShapes(dir);
      for (const std::string& s : shapes) sets.push_back(ReadLasaShape(dir, s));
      break;
    }
    case DemoSource::kSynthetic: {
      SyntheticDemoConfig s;
      s.demos = c.data.synthetic_demos;
      s.points = c.data.synthetic_points;
      s.noise = c.data.synthetic_noise;
      s.seed = static_cast<std::uint64_t>(c.seed);
      s.shape = c.data.synthetic_shape;
      sets.push_back(SyntheticDemos2d(s));
      break;
    }
    case DemoSource::kTaskSpace:
      sets.push_back(
          TaskSpaceDemos(c.data.task, c.data.task_demos, static_cast<std::uint64_t>(c.seed)));
      break;
  }
  std::vector<PreparedDemos> out;
  for (const DemoSet& s : sets) out.push_back(Prepare(c, s));
  return out;
}

void StackDemos(const DemoSet& set, const std::vector<int>& ids, Eigen::MatrixXd* positions,
                Eigen::MatrixXd* velocities) {
  Eigen::Index n = 0;
  for (int i : ids) n += set.demos[static_cast<std::size_t>(i)].position.cols();
  positions->resize(set.dimension, n);
  velocities->resize(set.dimension, n);
  Eigen::Index at = 0;
  for (int i : ids) {
    const Demonstration& d = set.demos[static_cast<std::size_t>(i)];
    positions->middleCols(at, d.position.cols()) = d.position;
    velocities->middleCols(at, d.position.cols()) = d.velocity;
    at += d.position.cols();
  }
}

}  // namespace foresight::imitation
