// AUC, precision, recall and the ROC curve against brute-force definitions.

#include "core/binary_metrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "tests/test_util.h"

namespace foresight {
namespace {

/// P(score of a positive > score of a negative) + P(tie) / 2 over all pairs.
double PairwiseAuc(const std::vector<double>& s, const std::vector<std::uint8_t>& l) {
  double wins = 0, pairs = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!l[i]) continue;
    for (std::size_t j = 0; j < s.size(); ++j) {
      if (l[j]) continue;
      pairs += 1;
      wins += s[i] > s[j] ? 1.0 : (s[i] == s[j] ? 0.5 : 0.0);
    }
  }
  return wins / pairs;
}

/// Random labelled scores, positives shifted up, scores rounded to `step` (ties).
void RandomData(int n, double step, std::uint64_t seed, std::vector<double>* s,
                std::vector<std::uint8_t>* l) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  std::bernoulli_distribution b(0.35);
  s->clear();
  l->clear();
  for (int i = 0; i < n; ++i) {
    const bool pos = b(rng);
    const double v = n01(rng) + (pos ? 0.8 : 0.0);
    s->push_back(step > 0 ? std::round(v / step) * step : v);
    l->push_back(pos ? 1 : 0);
  }
}

TEST(BinaryMetrics, AucEqualsPairwiseProbabilityWithTiesCountingHalf) {
  for (const double step : {0.0, 0.05, 0.5, 2.0}) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      std::vector<double> s;
      std::vector<std::uint8_t> l;
      RandomData(400, step, seed, &s, &l);
      const BinaryMetrics m = EvaluateBinary(s, l);
      EXPECT_NEAR(m.auc, PairwiseAuc(s, l), 1e-12) << "step " << step << " seed " << seed;
      EXPECT_EQ(m.positives + m.negatives, 400);
      EXPECT_EQ(m.positives, std::count(l.begin(), l.end(), 1));
    }
  }
}

TEST(BinaryMetrics, PerfectInvertedAndConstantClassifiers) {
  const std::vector<std::uint8_t> l = {1, 0, 1, 0, 0, 1};
  const std::vector<double> perfect = {0.9, 0.1, 0.8, 0.2, 0.3, 0.7};
  std::vector<double> inverted;
  for (const double v : perfect) inverted.push_back(1 - v);
  EXPECT_DOUBLE_EQ(EvaluateBinary(perfect, l).auc, 1.0);
  EXPECT_DOUBLE_EQ(EvaluateBinary(inverted, l).auc, 0.0);
  EXPECT_DOUBLE_EQ(EvaluateBinary(std::vector<double>(6, 0.4), l).auc, 0.5);
  // Infinite scores are ordinary scores.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_DOUBLE_EQ(EvaluateBinary({inf, -inf, inf, 0, -inf, 1}, l).auc, 1.0);
}

TEST(BinaryMetrics, PrecisionAndRecallByHand) {
  // threshold 0.5: predicted positive = scores >= 0.5 -> items 0, 1, 3, 5 (item 3 exactly at it).
  const std::vector<double> s = {0.9, 0.6, 0.4, 0.5, 0.1, 0.7, 0.2};
  const std::vector<std::uint8_t> l = {1, 0, 1, 1, 0, 0, 1};
  const BinaryMetrics m = EvaluateBinary(s, l, 0.5);
  // TP = {0, 3} = 2, FP = {1, 5} = 2, FN = {2, 6} = 2.
  EXPECT_DOUBLE_EQ(m.precision, 2.0 / 4.0);
  EXPECT_DOUBLE_EQ(m.recall, 2.0 / 4.0);
  EXPECT_EQ(m.positives, 4);
  EXPECT_EQ(m.negatives, 3);
  const BinaryMetrics hi = EvaluateBinary(s, l, 0.8);  // only item 0
  EXPECT_DOUBLE_EQ(hi.precision, 1.0);
  EXPECT_DOUBLE_EQ(hi.recall, 0.25);
  const BinaryMetrics none = EvaluateBinary(s, l, 2.0);  // nothing predicted positive
  EXPECT_DOUBLE_EQ(none.precision, 0.0);
  EXPECT_DOUBLE_EQ(none.recall, 0.0);
  const BinaryMetrics all = EvaluateBinary(s, l, -1.0);
  EXPECT_DOUBLE_EQ(all.precision, 4.0 / 7.0);
  EXPECT_DOUBLE_EQ(all.recall, 1.0);
}

TEST(BinaryMetrics, BadInputThrows) {
  using testing::ExpectErrorContains;
  ExpectErrorContains(
      [] {
        EvaluateBinary({0.1, 0.2}, {1, 1});
      },
      {"both classes", "2 positives and 0 negatives"});
  ExpectErrorContains([] { EvaluateBinary({0.1, 0.2}, {0, 0}); }, {"both classes"});
  ExpectErrorContains([] { EvaluateBinary({}, {}); }, {"both classes"});
  ExpectErrorContains(
      [] {
        EvaluateBinary({0.1, std::nan(""), 0.3}, {1, 0, 1});
      },
      {"score 1 is NaN"});
  ExpectErrorContains([] { EvaluateBinary({0.1, 0.2}, {1, 0, 1}); }, {"2 scores for 3 labels"});
  ExpectErrorContains([] { RocCurve({0.1, 0.2}, {1, 1}); }, {"both classes"});
  ExpectErrorContains([] { RocCurve({std::nan(""), 0.2}, {1, 0}); }, {"NaN"});
  ExpectErrorContains([] { RocCurve({0.1, 0.2}, {1, 0}, 1); }, {"max_points"});
}

TEST(RocCurve, RunsFromOriginToOneMonotonicallyAndItsAreaIsTheAuc) {
  std::vector<double> s;
  std::vector<std::uint8_t> l;
  RandomData(500, 0.1, 9, &s, &l);  // many ties: tied groups are diagonal steps
  const auto roc = RocCurve(s, l, 100000);
  ASSERT_GE(roc.size(), 3u);
  EXPECT_EQ(roc.front(), std::make_pair(0.0, 0.0));
  EXPECT_EQ(roc.back(), std::make_pair(1.0, 1.0));
  double area = 0;
  for (std::size_t i = 1; i < roc.size(); ++i) {
    EXPECT_GE(roc[i].first, roc[i - 1].first);
    EXPECT_GE(roc[i].second, roc[i - 1].second);
    EXPECT_TRUE(roc[i] != roc[i - 1]) << "repeated point " << i;
    area += (roc[i].first - roc[i - 1].first) * (roc[i].second + roc[i - 1].second) / 2;
  }
  EXPECT_NEAR(area, PairwiseAuc(s, l), 1e-12);

  // Thinned: at most max_points, endpoints kept, still monotone, points of the full curve.
  for (const int max_points : {2, 3, 10, 57}) {
    const auto thin = RocCurve(s, l, max_points);
    EXPECT_EQ(thin.size(), std::min<std::size_t>(max_points, roc.size()));
    EXPECT_EQ(thin.front(), std::make_pair(0.0, 0.0));
    EXPECT_EQ(thin.back(), std::make_pair(1.0, 1.0));
    for (std::size_t i = 1; i < thin.size(); ++i) {
      EXPECT_GE(thin[i].first, thin[i - 1].first);
      EXPECT_GE(thin[i].second, thin[i - 1].second);
    }
    for (const auto& p : thin) EXPECT_NE(std::find(roc.begin(), roc.end(), p), roc.end());
  }
}

TEST(RocCurve, PerfectClassifierGoesThroughZeroOne) {
  const auto roc = RocCurve({0.9, 0.8, 0.3, 0.1}, {1, 1, 0, 0});
  const std::vector<std::pair<double, double>> want = {{0, 0}, {0, 0.5}, {0, 1}, {0.5, 1}, {1, 1}};
  EXPECT_EQ(roc, want);
}

}  // namespace
}  // namespace foresight
