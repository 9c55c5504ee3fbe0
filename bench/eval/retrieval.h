// lmd-eval retrieval: the methods compared, their per-dataset results, and
// the writers of results.json, report.md and the SVG plots.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "bench/eval/answer_scoring.h"
#include "core/eval/retrieval_metrics.h"
#include "core/localize/localizer.h"
#include "core/index/retrieve_options.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd::eval {

// One method: either a paper method (a descriptor configuration and the
// first-stage similarity, every candidate scored exhaustively), or the
// product's localisation pipeline (core/localize, the code lmdd serves) with
// some LocalizeOptions: `best` with the served defaults, each ablation row
// with one option changed.
struct MethodSpec {
  std::string key;    // results.json key
  std::string label;  // report label
  std::string group;  // "paper", "descriptor", "best", "ablation"
  // Paper methods: descriptor.
  Planner planner = Planner::kCoG;
  int setting = 1;             // paper descriptor setting #1..#8
  int word_bits = 10;          // appearance word bits B (paper: 10)
  // First stage.
  Method method = Method::kLmd;
  double max_offset_m = 0.5;     // RetrieveOptions::max_offset_m (its default)
  bool stationary = false;       // queries without simulated change
  // The paper's change detector (LOF + NN-d) evaluated on this method's hits.
  bool change_eval = false;
  // The pipeline instead (groups best and ablation).
  bool pipeline = false;
  LocalizeOptions localize;
  std::string note;              // one line for the ablation table: what differs from best
};

// Thresholds T_NN-d of the change-detection curves; kDefaultThreshold is the
// detector's default (1.5), evaluated in addition to the integer curve.
inline const std::vector<double>& ChangeThresholds() {
  static const std::vector<double> t = {0, 1, 1.5, 2, 3, 4, 5, 6, 7, 8};
  return t;
}
inline constexpr double kDefaultChangeThreshold = 1.5;

// Change detection results of one dataset (one method).
struct ChangeResult {
  size_t tasks = 0;  // queries with a simulated change
  std::vector<size_t> ks;                   // k of the curves
  std::map<double, std::vector<double>> curves;  // threshold -> success rate at each k
  double success_at_1 = 0, success_at_10 = 0;  // default threshold
  double false_alarm_rate = 0;  // default threshold: top-10 masks not on a true change of a right place
  double masks_mean = 0;        // default threshold: masks per task
};

struct DatasetResults {
  std::string name;
  size_t maps = 0;
  size_t queries = 0;
  std::map<std::string, RetrievalSummary> methods;
  std::map<std::string, AnswerSummary> pipeline;  // pipeline methods: verdicts, change masks, CPU
  ChangeResult change;            // change_method's
  std::string change_method;      // the first method with change_eval (the paper's detector)
  std::map<std::string, ChangeResult> method_change;  // every method with change_eval
};

struct RunInfo {
  std::string command;
  std::string date;
  std::string machine;
  uint64_t seed = 1;
  int threads = 2;
  double seconds = 0;
};

// DIR/results.json, DIR/report.md and DIR/*.svg. False if a file cannot be written.
bool WriteResults(const std::string& dir, const std::vector<MethodSpec>& specs,
                  const std::vector<DatasetResults>& datasets, const RunInfo& info);

}  // namespace lmd::eval
