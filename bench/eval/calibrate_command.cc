// lmd-eval calibrate: fits the answer's confidence (ConfidenceOptions::
// calibration) to served runs' answers and shows how well it holds. Reads
// the queries.csv of each `lmd-eval served` run named, fits the logistic on
// the tuning logs' answers of all runs pooled, and prints, per run, the
// calibration error and Brier score of the confidence the run's lmdd stated
// and of the fitted one, on the tuning logs and on the others; --svg FILE
// draws the fitted one's reliability on the others, a line per run.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/answer_scoring.h"
#include "bench/common/calibration.h"
#include "bench/eval/commands.h"
#include "bench/eval/data_paths.h"
#include "core/util/split.h"

namespace lmd::eval {
namespace {

struct Row {
  std::string log;
  CalibrationSample sample;
  double stated = 0.0;  // the confidence the run's lmdd gave
};

std::vector<std::string> SplitLine(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (size_t comma = line.find(','); comma != std::string::npos; comma = line.find(',', start)) {
    fields.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
  fields.push_back(line.substr(start));
  return fields;
}

// The rows of `dir`/queries.csv; false with `error` set when it cannot be read.
bool ReadRun(const std::string& dir, std::vector<Row>* rows, std::string* error) {
  const std::string path = dir + "/queries.csv";
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line)) {
    *error = "cannot read " + path;
    return false;
  }
  const std::vector<std::string> header = SplitLine(line);
  std::map<std::string, size_t> column;
  for (size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  const char* needed[] = {"log", "first_place_hit", "pose_err_m", "pose_err_deg", "localized", "best_score",
                          "rival_score", "confidence"};
  for (const char* name : needed) {
    if (!column.count(name)) {
      *error = path + " has no column " + name + " (not an lmd-eval served run?)";
      return false;
    }
  }
  size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    const std::vector<std::string> f = SplitLine(line);
    if (f.size() != header.size()) {
      *error = path + ":" + std::to_string(number) + ": " + std::to_string(f.size()) + " fields, the header has " +
               std::to_string(header.size());
      return false;
    }
    try {
      Row r;
      r.log = f[column["log"]];
      const bool top_is_place = std::stoi(f[column["first_place_hit"]]) == 0;
      r.sample.right = top_is_place && std::stod(f[column["pose_err_m"]]) <= kSurePoseM &&
                       std::stod(f[column["pose_err_deg"]]) <= kSurePoseDeg;
      r.sample.sure = std::stoi(f[column["localized"]]) != 0;
      r.sample.best_score = std::stod(f[column["best_score"]]);
      r.sample.margin = r.sample.best_score - std::stod(f[column["rival_score"]]);
      r.stated = std::stod(f[column["confidence"]]);
      const bool finite = std::isfinite(r.sample.best_score) && std::isfinite(r.sample.margin);
      if (!finite || !(r.stated >= 0.0 && r.stated <= 1.0)) {
        *error = path + ":" + std::to_string(number) + ": a score is not finite or the confidence is not in [0, 1]";
        return false;
      }
      rows->push_back(std::move(r));
    } catch (const std::exception&) {
      *error = path + ":" + std::to_string(number) + ": a field is not a number";
      return false;
    }
  }
  return true;
}

std::string Cell(const Reliability& r) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3f / %.3f", r.calibration_error, r.brier);
  return buf;
}

}  // namespace

int RunCalibrate(int argc, char** argv) {
  Flags args({"run", "tuned-on", "svg"});
  if (!args.Parse(argc, argv) || !args.Has("run")) {
    std::fprintf(stderr, "lmd-eval calibrate: %s\n", args.Has("run") ? args.error().c_str() : "--run DIR is required");
    return 2;
  }
  const std::vector<std::string> tuned_list =
      args.Has("tuned-on") ? SplitCommas(args.Get("tuned-on")) : DefaultTunedOn();
  const std::set<std::string> tuned(tuned_list.begin(), tuned_list.end());
  const std::vector<std::string> dirs = args.GetAll("run");
  std::vector<std::vector<Row>> runs(dirs.size());
  std::vector<CalibrationSample> training;
  for (size_t i = 0; i < dirs.size(); ++i) {
    std::string error;
    if (!ReadRun(dirs[i], &runs[i], &error)) {
      std::fprintf(stderr, "lmd-eval calibrate: %s\n", error.c_str());
      return 1;
    }
    for (const Row& r : runs[i]) {
      if (tuned.count(r.log)) training.push_back(r.sample);
    }
  }
  if (training.empty()) {
    std::string names;
    for (const std::string& log : tuned_list) names += (names.empty() ? "" : ",") + log;
    std::fprintf(stderr, "lmd-eval calibrate: no answer of the tuning logs (%s) in the runs\n", names.c_str());
    return 1;
  }
  const LogisticFit fit = FitLogistic(training);
  std::printf("Fitted on %zu answers of the tuning logs: bias %.2f, score_weight %.2f, margin_weight %.2f, "
              "sure_weight %.2f\n\n",
              training.size(), fit.bias, fit.score_weight, fit.margin_weight, fit.sure_weight);
  std::printf("Calibration error / Brier score (lower is better), of the confidence each run's lmdd stated and of "
              "the fitted one:\n\n");
  std::printf("| run | answers held out | held out: stated | fitted | tuning logs: stated | fitted |\n"
              "|---|---|---|---|---|---|\n");
  std::vector<StatedOutcome> pooled_held_out;
  std::vector<ReliabilitySeries> series;
  for (size_t i = 0; i < dirs.size(); ++i) {
    std::vector<StatedOutcome> stated[2], fitted[2];  // [held out, tuned on]
    for (const Row& r : runs[i]) {
      const int split = tuned.count(r.log) ? 1 : 0;
      const CalibrationSample& s = r.sample;
      stated[split].push_back({r.stated, s.right});
      fitted[split].push_back({fit.Probability(s.best_score, s.margin, s.sure), s.right});
      if (split == 0) pooled_held_out.push_back(fitted[0].back());
    }
    std::printf("| %s | %zu | %s | %s | %s | %s |\n", dirs[i].c_str(), stated[0].size(),
                Cell(MeasureReliability(stated[0])).c_str(), Cell(MeasureReliability(fitted[0])).c_str(),
                Cell(MeasureReliability(stated[1])).c_str(), Cell(MeasureReliability(fitted[1])).c_str());
    series.push_back({dirs[i] + ", held out", MeasureReliability(fitted[0])});
  }
  const Reliability held_out = MeasureReliability(pooled_held_out);
  std::printf("\nThe fitted confidence on the held-out logs of all runs (%zu answers):\n\n", held_out.answers);
  std::printf("| confidence | answers | mean confidence | right |\n|---|---|---|---|\n");
  for (int b = 0; b < kReliabilityBins; ++b) {
    if (held_out.count[b] == 0) continue;
    std::printf("| %.1f-%.1f | %zu | %.3f | %.3f |\n", b / 10.0, (b + 1) / 10.0, held_out.count[b],
                held_out.mean_probability[b], held_out.share_right[b]);
  }
  if (args.Has("svg")) {
    std::ofstream svg(args.Get("svg"));
    svg << ReliabilitySvg(series, "the fitted confidence on logs it was not fitted on");
    if (!svg) {
      std::fprintf(stderr, "lmd-eval calibrate: cannot write %s\n", args.Get("svg").c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace lmd::eval
