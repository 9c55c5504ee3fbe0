// lmd-eval retrieval: the methods compared, their per-dataset results, and
// the writers of results.json, report.md and the SVG plots.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/change/geometric_changes.h"
#include "core/eval/retrieval_metrics.h"
#include "core/index/retrieve_options.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd::eval {

// How the top hits of the first stage are re-ranked after verification.
enum class Rerank {
  kOverlap,   // fraction of query points within 0.3 m of the db map after alignment
  kMeanDist,  // maps with consistency >= 0.5 first, then the smallest mean distance after alignment
  kConsistency,  // overlap - 2 * (query points in db free space) - 4 * (db points in query free space)
  kConsistencyDist,  // kConsistency - 0.5 * min(mean distance after alignment, 3 m)
};

// One method: a descriptor configuration, a first-stage similarity and an
// optional geometric verification of its top hits.
struct MethodSpec {
  std::string key;    // results.json key
  std::string label;  // report label
  std::string group;  // "paper", "descriptor", "best", "ablation"
  // Descriptor.
  Planner planner = Planner::kCoG;
  bool both_planners = false;  // first stage = max of the CoG and CoR kernel scores
  int setting = 1;             // paper descriptor setting #1..#8
  int word_bits = 10;          // appearance word bits B (paper: 10)
  double interest_cell_m = 0.5;  // describer interest grid (DescriberOptions default)
  int max_features = 80;         // describer cap (DescriberOptions default)
  double inner_radius_m = 0.0;   // m, inner words (DescriberOptions; 0 = none, the paper's)
  // First stage.
  Method method = Method::kLmd;
  double max_offset_m = 0.5;     // RetrieveOptions::max_offset_m (its default)
  bool stationary = false;       // queries without simulated change
  // Verification of the first stage's top hits (0 = none).
  size_t verify_top_n = 0;
  // When none of those matched (a hit showing the place), verify this many
  // more, the next of the first stage's ranking (0 = never).
  size_t verify_more_if_unmatched = 0;
  Rerank rerank = Rerank::kOverlap;
  bool global_fallback = true;   // guess-free scan matching when the guided match is poor
  bool lazy_global = true;       // ... only if no candidate matched near its guess (VerifyConfig)
  bool always_global = false;    // ... for every verified candidate, keeping the better (VerifyConfig)
  double verify_window_m = 1.0;  // m, scan-matching window around each guess (VerifyConfig)
  // Unverified maps up to this many positions before or after a matched map
  // in its log (the same robot's route: they overlap it) rank just after it,
  // lower by kNeighbourStep per position (0 = off).
  size_t neighbour_window = 0;
  // Route neighbours also lift verified maps that did not match (false:
  // unverified maps only).
  bool lift_unmatched_neighbours = false;
  // Runs of matched maps that are consecutive in their log are ordered
  // among themselves by aligned mean distance (the relevant map's
  // criterion) instead of the re-ranking key.
  bool order_runs_by_distance = false;
  // Query expansion: the best matched hit's own descriptors score every
  // candidate that did not match, and an unverified map adds those scores
  // to the query's (other passes of the place resemble the stored map more
  // than the changed query). false = off.
  bool expand_from_matched = false;
  // With the expansion: this many unverified maps it ranks first are then
  // verified, guessed through the best matched map's pose (0 = none).
  size_t verify_expanded = 0;
  // Those maps may also be verified maps that did not match (their first
  // guess was poor); each keeps the better of its two alignments.
  bool reverify_unmatched = false;
  // Change detection evaluated on this method's hits.
  bool change_eval = false;
  // Masks whose points the verified db map explains (a db point within 0.3 m
  // under the verified pose) are ranked after the unexplained ones.
  bool change_geometric = false;
  // Geometric change masks (core/change/geometric_changes.h) against the
  // hits verification matched, ranked before the descriptor's masks.
  bool geometric_masks = false;
  // Geometric masks ranked by evidence (free-space margin, range); false: by point count.
  bool masks_by_evidence = true;
  double mask_explained_radius_m = GeometricChangeOptions().explained_radius_m;
  double mask_seen_through_share = GeometricChangeOptions().seen_through_share;
  // Geometric masks against the matched hits whose re-ranking key is within
  // this of the best matched hit's (PlaceHits).
  double mask_key_window = kPlaceHitsWindow;
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
  ChangeResult change;            // change_method's
  std::string change_method;      // the first method with change_eval
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
