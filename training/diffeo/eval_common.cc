#include "training/diffeo/eval_common.h"

#include <iomanip>
#include <map>
#include <sstream>

namespace foresight::imitation {

void AddPathScores(const std::string& prefix, const PathSet& paths, const PreparedDemos& demos,
                   int resample, Scores* s, const std::vector<int>& ids, double scale) {
  double sum = 0, held_sum = 0, reached = 0;
  int held = 0;
  const int n = static_cast<int>(paths.paths.size());
  for (int k = 0; k < n; ++k) {
    const int demo = ids.empty() ? k : ids[static_cast<std::size_t>(k)];
    const Eigen::MatrixXd& ref = demos.demos.demos[static_cast<std::size_t>(demo)].position;
    const double f =
        DiscreteFrechet(ResampleByArcLength(paths.paths[static_cast<std::size_t>(k)], resample),
                        ResampleByArcLength(ref, resample)) *
        scale;
    sum += f;
    if (std::find(demos.held_out.begin(), demos.held_out.end(), demo) != demos.held_out.end()) {
      held_sum += f;
      ++held;
    }
    reached += paths.reached[static_cast<std::size_t>(k)];
  }
  s->push_back({prefix + "frechet", n > 0 ? sum / n : 0.0});
  if (held > 0) s->push_back({prefix + "frechet_heldout", held_sum / held});
  s->push_back({prefix + "reach_rate", n > 0 ? reached / n : 0.0});
}

namespace {
void WriteNumber(std::ostringstream& o, double v) {
  if (std::isfinite(v))
    o << v;
  else
    o << "null";
}
}  // namespace

std::string EvalJson(const std::vector<std::pair<std::string, Scores>>& shapes) {
  std::ostringstream o;
  o << std::setprecision(6);
  o << "{\n  \"shapes\": {";
  // Means over the shapes that have each figure, in first-seen order.
  std::vector<std::string> order;
  std::map<std::string, std::pair<double, int>> mean;
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    o << (i ? ",\n" : "\n") << "    \"" << shapes[i].first << "\": {";
    for (std::size_t k = 0; k < shapes[i].second.size(); ++k) {
      const auto& [key, v] = shapes[i].second[k];
      o << (k ? ", " : "") << "\"" << key << "\": ";
      WriteNumber(o, v);
      if (!mean.count(key)) order.push_back(key);
      auto& m = mean[key];
      m.first += v;
      m.second += 1;
    }
    o << "}";
  }
  o << "\n  },\n  \"mean\": {";
  for (std::size_t k = 0; k < order.size(); ++k) {
    const auto& m = mean[order[k]];
    o << (k ? ", " : "") << "\"" << order[k] << "\": ";
    WriteNumber(o, m.first / m.second);
  }
  o << "},\n  \"shape_count\": " << shapes.size() << "\n}\n";
  return o.str();
}

}  // namespace foresight::imitation
