// How well a stated probability of being right matches how often answers
// are right (lmd-eval served's report, lmd-eval calibrate), and the fit of
// the logistic that states it (ConfidenceOptions::calibration).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/localize/confidence.h"

namespace lmd {

// One answer: the probability it was given, and whether it was right.
struct StatedOutcome {
  double probability = 0.0;
  bool right = false;
};

inline constexpr int kReliabilityBins = 10;  // [0, 0.1), ..., [0.9, 1]

struct Reliability {
  size_t answers = 0;
  // Expected calibration error: over the bins, the answers' share times the
  // gap between their mean probability and their share right.
  double calibration_error = 0.0;
  double brier = 0.0;  // mean squared gap between probability and outcome
  size_t count[kReliabilityBins] = {};
  double mean_probability[kReliabilityBins] = {}, share_right[kReliabilityBins] = {};
};

Reliability MeasureReliability(const std::vector<StatedOutcome>& outcomes);

// A reliability diagram (SVG): each tenth of stated probability at its
// answers' mean probability (x) and their share right (y), one line per
// series; a calibrated probability lies on the diagonal.
struct ReliabilitySeries {
  std::string name;
  Reliability reliability;
};
std::string ReliabilitySvg(const std::vector<ReliabilitySeries>& series, const std::string& title);

// An answer's features and outcome, to fit a LogisticFit on.
struct CalibrationSample {
  double best_score = 0.0, margin = 0.0;
  bool sure = false, right = false;
};

// Maximum-likelihood logistic regression (Newton's method, a small ridge so
// that a feature that separates the outcomes cannot run off to infinity).
LogisticFit FitLogistic(const std::vector<CalibrationSample>& samples);

}  // namespace lmd
