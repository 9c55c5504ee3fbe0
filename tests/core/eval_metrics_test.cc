#include <gtest/gtest.h>

#include <cmath>

#include "core/eval/retrieval_metrics.h"

namespace lmd {
namespace {

TEST(RetrievalMetricsTest, RankCountsHigherScoresAndHalfTheTies) {
  EXPECT_DOUBLE_EQ(RankOfTarget({0.9, 0.5, 0.1}, 0), 1.0);
  EXPECT_DOUBLE_EQ(RankOfTarget({0.9, 0.5, 0.1}, 2), 3.0);
  // Two other maps tie with the target: expected rank of a random order.
  EXPECT_DOUBLE_EQ(RankOfTarget({0.9, 0.5, 0.5, 0.5}, 1), 3.0);
  // Unscored relevant map in an unscored tail of 4 maps after one scored map.
  EXPECT_DOUBLE_EQ(RankOfTarget({0.7, 0, 0, 0, 0}, 3), 3.5);
}

TEST(RetrievalMetricsTest, TopPercentAllowsAtLeastRankOne) {
  EXPECT_TRUE(WithinTopPercent(1.0, 50, 1));    // 1 % of 50 = 0.5 -> rank 1 still counts
  EXPECT_FALSE(WithinTopPercent(2.0, 50, 1));
  EXPECT_TRUE(WithinTopPercent(10.0, 100, 10));
  EXPECT_FALSE(WithinTopPercent(10.5, 100, 10));
  EXPECT_TRUE(WithinTopPercent(5.0, 100, 5));
}

TEST(RetrievalMetricsTest, SummaryComputesAnrTopRatesAndPlaceRecall) {
  std::vector<QueryOutcome> q(4);
  q[0].rank = 1, q[0].candidates = 100, q[0].first_place_hit = 0;
  q[1].rank = 4, q[1].candidates = 100, q[1].first_place_hit = 3;
  q[2].rank = 50, q[2].candidates = 100, q[2].first_place_hit = -1;
  q[3].rank = 8, q[3].candidates = 100, q[3].place_counted = false;
  const RetrievalSummary s = Summarize(q);
  EXPECT_EQ(s.queries, 4u);
  EXPECT_NEAR(s.anr, 100.0 * (0.01 + 0.04 + 0.5 + 0.08) / 4, 1e-9);
  EXPECT_DOUBLE_EQ(s.recall_at_1, 0.25);
  EXPECT_DOUBLE_EQ(s.top1, 0.25);
  EXPECT_DOUBLE_EQ(s.top5, 0.5);
  EXPECT_DOUBLE_EQ(s.top10, 0.75);
  EXPECT_EQ(s.top10_count, 3u);
  EXPECT_EQ(s.place_queries, 3u);
  EXPECT_NEAR(s.place_at_1, 1.0 / 3, 1e-12);
  EXPECT_NEAR(s.place_at_5, 2.0 / 3, 1e-12);
}

TEST(RetrievalMetricsTest, OverallAveragesDatasetsEqually) {
  RetrievalSummary a, b;
  a.queries = 10, a.anr = 10, a.place_at_1 = 1.0;
  b.queries = 1000, b.anr = 30, b.place_at_1 = 0.5;
  b.pose_count = 3, b.pose_err_m_median = 0.2;
  const RetrievalSummary o = AverageOverDatasets({a, b});
  EXPECT_EQ(o.queries, 1010u);
  EXPECT_DOUBLE_EQ(o.anr, 20.0);
  EXPECT_DOUBLE_EQ(o.place_at_1, 0.75);
  EXPECT_DOUBLE_EQ(o.pose_err_m_median, 0.2);  // only datasets with poses
}

TEST(RetrievalMetricsTest, PoseErrorWrapsAngles) {
  double m = 0, deg = 0;
  PoseError({1, 1, M_PI - 0.01}, {1, 4, -M_PI + 0.01}, &m, &deg);
  EXPECT_NEAR(m, 3.0, 1e-12);
  EXPECT_NEAR(deg, 0.02 * 180 / M_PI, 1e-9);
}

TEST(RetrievalMetricsTest, QuantileInterpolates) {
  EXPECT_DOUBLE_EQ(Quantile({3, 1, 2}, 0.5), 2.0);
  EXPECT_DOUBLE_EQ(Quantile({0, 10}, 0.9), 9.0);
  EXPECT_DOUBLE_EQ(Quantile({}, 0.5), 0.0);
}

TEST(RetrievalMetricsTest, SuccessCurveIsCumulativeOverK) {
  const std::vector<size_t> first = {1, 3, 0, 12};
  const std::vector<size_t> ks = LogSteps(10);
  ASSERT_EQ(ks, (std::vector<size_t>{1, 2, 5, 10}));
  EXPECT_EQ(SuccessCurve(first, ks), (std::vector<double>{0.25, 0.25, 0.5, 0.5}));
  EXPECT_EQ(SuccessCurve({}, ks), (std::vector<double>{0, 0, 0, 0}));
}

TEST(RetrievalMetricsTest, MaskHitsChangeWithinRadius) {
  EXPECT_TRUE(MaskHitsChange({{0, 0}, {5, 5}}, {{5.3, 5.3}}, 0.5));
  EXPECT_FALSE(MaskHitsChange({{0, 0}}, {{0.4, 0.4}}, 0.5));
}

}  // namespace
}  // namespace lmd
