// What `lmd-eval served` writes: results.json (per log and means over all,
// held-out and tuning logs), report.md (the same as tables), queries.csv
// (one line per query, for lmd-eval calibrate), served.svg (a picture) and
// calibration.svg (the confidence's reliability diagram).
#pragma once

#include <string>
#include <vector>

#include "bench/eval/answer_scoring.h"
#include "core/status.h"

namespace lmd::eval {

struct ServedLog {
  std::string name;
  size_t maps = 0;
  AnswerSummary still;    // Retrieve of each map as stored
  AnswerSummary changed;  // DetectChanges of its copy with a simulated change
  std::string query_lines;  // queries.csv rows
};

struct ServedRun {
  std::string command, date;
  std::vector<std::string> tuned_on;  // logs the configuration was tuned on
  std::vector<ServedLog> logs;
  double seconds = 0.0;
  double lmdd_cpu_seconds = 0.0;  // lmdd's own CPU over the whole run (Stats)
};

// IoError if a file cannot be written.
Status WriteServedReport(const std::string& dir, const ServedRun& run, bool with_changes);

}  // namespace lmd::eval
