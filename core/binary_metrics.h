#pragma once
/// Scores of a binary classifier (occupancy maps): area under the ROC curve, precision and recall
/// at a threshold, and the ROC curve itself.

#include <cstdint>
#include <vector>

namespace foresight {

struct BinaryMetrics {
  double auc = 0;        ///< area under the ROC curve; ties count one half (Mann-Whitney U)
  double precision = 0;  ///< TP / (TP + FP) at the threshold (0 when nothing is predicted positive)
  double recall = 0;     ///< TP / (TP + FN) at the threshold
  std::int64_t positives = 0, negatives = 0;
};

/// @param scores [n] classifier outputs (higher = more likely positive); NaN is an Error.
/// @param labels [n] 1 = positive, 0 = negative. Both classes must be present (else Error).
/// @param threshold predicted positive when score >= threshold.
BinaryMetrics EvaluateBinary(const std::vector<double>& scores,
                             const std::vector<std::uint8_t>& labels, double threshold = 0.5);

/// ROC curve as (false positive rate, true positive rate) points, at most `max_points` of them
/// (evenly thinned; max_points >= 2, else Error), from (0, 0) to (1, 1).
std::vector<std::pair<double, double>> RocCurve(const std::vector<double>& scores,
                                                const std::vector<std::uint8_t>& labels,
                                                int max_points = 200);

}  // namespace foresight
