#include "core/binary_metrics.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace foresight {
namespace {

std::vector<std::size_t> SortedByScoreDescending(const std::vector<double>& scores,
                                                 const std::vector<std::uint8_t>& labels) {
  FS_THROW_UNLESS(scores.size() == labels.size(), "binary metrics: ", scores.size(), " scores for ",
                  labels.size(), " labels");
  for (std::size_t i = 0; i < scores.size(); ++i)
    FS_THROW_UNLESS(!std::isnan(scores[i]), "binary metrics: score ", i, " is NaN");
  std::vector<std::size_t> order(scores.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return scores[a] > scores[b]; });
  return order;
}

}  // namespace

BinaryMetrics EvaluateBinary(const std::vector<double>& scores,
                             const std::vector<std::uint8_t>& labels, double threshold) {
  const std::vector<std::size_t> order = SortedByScoreDescending(scores, labels);
  BinaryMetrics m;
  for (const auto l : labels) (l ? m.positives : m.negatives) += 1;
  FS_THROW_UNLESS(m.positives > 0 && m.negatives > 0, "binary metrics: need both classes, got ",
                  m.positives, " positives and ", m.negatives, " negatives");
  // AUC = P(score+ > score-) + P(tie) / 2: walk groups of equal scores from the top.
  double pairs = 0;
  std::int64_t tp = 0;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    std::int64_t group_pos = 0, group_neg = 0;
    while (j < order.size() && scores[order[j]] == scores[order[i]]) {
      (labels[order[j]] ? group_pos : group_neg) += 1;
      ++j;
    }
    pairs += static_cast<double>(group_neg) * (static_cast<double>(tp) + 0.5 * group_pos);
    tp += group_pos;
    i = j;
  }
  m.auc = pairs / (static_cast<double>(m.positives) * static_cast<double>(m.negatives));
  std::int64_t pred_pos = 0, true_pos = 0;
  for (std::size_t i = 0; i < scores.size(); ++i) {
    if (scores[i] >= threshold) {
      ++pred_pos;
      true_pos += labels[i] ? 1 : 0;
    }
  }
  m.precision = pred_pos > 0 ? static_cast<double>(true_pos) / pred_pos : 0.0;
  m.recall = static_cast<double>(true_pos) / m.positives;
  return m;
}

std::vector<std::pair<double, double>> RocCurve(const std::vector<double>& scores,
                                                const std::vector<std::uint8_t>& labels,
                                                int max_points) {
  FS_THROW_UNLESS(max_points >= 2, "ROC curve: max_points ", max_points,
                  " must be at least 2 (both endpoints)");
  const std::vector<std::size_t> order = SortedByScoreDescending(scores, labels);
  std::int64_t pos = 0, neg = 0;
  for (const auto l : labels) (l ? pos : neg) += 1;
  FS_THROW_UNLESS(pos > 0 && neg > 0, "ROC curve: need both classes");
  std::vector<std::pair<double, double>> all{{0.0, 0.0}};
  std::int64_t tp = 0, fp = 0;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j < order.size() && scores[order[j]] == scores[order[i]]) {
      (labels[order[j]] ? tp : fp) += 1;
      ++j;
    }
    all.emplace_back(static_cast<double>(fp) / neg, static_cast<double>(tp) / pos);
    i = j;
  }
  if (static_cast<int>(all.size()) <= max_points) return all;
  std::vector<std::pair<double, double>> thin;
  for (int k = 0; k < max_points; ++k) {
    thin.push_back(all[static_cast<std::size_t>(k) * (all.size() - 1) / (max_points - 1)]);
  }
  return thin;
}

}  // namespace foresight
