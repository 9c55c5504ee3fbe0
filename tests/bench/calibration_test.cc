#include "bench/common/calibration.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace lmd {
namespace {

TEST(ReliabilityTest, BinsTheAnswersAndSumsTheGaps) {
  std::vector<StatedOutcome> outcomes;
  for (int i = 0; i < 10; ++i) outcomes.push_back({0.05, i == 0});  // said 0.05, right 0.1
  for (int i = 0; i < 10; ++i) outcomes.push_back({0.95, i < 5});   // said 0.95, right 0.5
  const Reliability r = MeasureReliability(outcomes);
  EXPECT_EQ(r.answers, 20u);
  EXPECT_EQ(r.count[0], 10u);
  EXPECT_EQ(r.count[9], 10u);
  EXPECT_NEAR(r.mean_probability[9], 0.95, 1e-12);
  EXPECT_NEAR(r.share_right[0], 0.1, 1e-12);
  EXPECT_NEAR(r.calibration_error, 0.5 * 0.05 + 0.5 * 0.45, 1e-12);
  const double brier = (9 * 0.05 * 0.05 + 0.95 * 0.95 + 5 * 0.05 * 0.05 + 5 * 0.95 * 0.95) / 20;
  EXPECT_NEAR(r.brier, brier, 1e-12);
  EXPECT_EQ(MeasureReliability({}).answers, 0u);
}

// Probabilities outside [0, 1] count at the nearest end, NaN as 0: every
// answer lands in a bin.
TEST(ReliabilityTest, ProbabilitiesOutOfRangeCountAtTheEnds) {
  const Reliability r = MeasureReliability({{1.5, true}, {-0.2, false}, {std::nan(""), false}});
  EXPECT_EQ(r.count[kReliabilityBins - 1], 1u);
  EXPECT_EQ(r.count[0], 2u);
  EXPECT_NEAR(r.brier, 0.0, 1e-12);
  EXPECT_NEAR(r.calibration_error, 0.0, 1e-12);
}

// Answers drawn from a known logistic: the fit finds its weights, and the
// probabilities it states are calibrated.
TEST(FitLogisticTest, RecoversTheWeightsItWasDrawnFrom) {
  const LogisticFit truth{-6.0, 9.0, 5.0, 1.5};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<CalibrationSample> samples;
  for (int i = 0; i < 20000; ++i) {
    CalibrationSample s;
    s.best_score = unit(rng);
    s.margin = s.best_score * unit(rng);
    s.sure = s.best_score > 0.6 && s.margin > 0.2 && unit(rng) < 0.7;
    s.right = unit(rng) < truth.Probability(s.best_score, s.margin, s.sure);
    samples.push_back(s);
  }
  const LogisticFit fit = FitLogistic(samples);
  EXPECT_NEAR(fit.bias, truth.bias, 0.5);
  EXPECT_NEAR(fit.score_weight, truth.score_weight, 0.8);
  EXPECT_NEAR(fit.margin_weight, truth.margin_weight, 0.8);
  EXPECT_NEAR(fit.sure_weight, truth.sure_weight, 0.5);
  std::vector<StatedOutcome> stated;
  for (const CalibrationSample& s : samples) {
    stated.push_back({fit.Probability(s.best_score, s.margin, s.sure), s.right});
  }
  EXPECT_LT(MeasureReliability(stated).calibration_error, 0.02);
}

// Outcomes a feature separates perfectly: the ridge keeps the weights finite.
TEST(FitLogisticTest, SeparableOutcomesKeepFiniteWeights) {
  std::vector<CalibrationSample> samples;
  for (int i = 0; i < 100; ++i) samples.push_back({i / 100.0, 0.1, i >= 50, i >= 50});
  const LogisticFit fit = FitLogistic(samples);
  EXPECT_TRUE(std::isfinite(fit.bias) && std::isfinite(fit.sure_weight));
  EXPECT_GT(fit.Probability(0.9, 0.1, true), 0.9);
  EXPECT_LT(fit.Probability(0.1, 0.1, false), 0.1);
}

}  // namespace
}  // namespace lmd
