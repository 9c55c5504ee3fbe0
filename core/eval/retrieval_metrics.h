// Metrics of the evaluation protocol (DESIGN.md §4) computed from ranked
// retrieval results: the paper's scoring (rank of the one relevant map: ANR,
// recall@1, top-X %), the product's place recall@k, pose errors against the
// logs' ground truth, and success-over-k curves for change detection.
// Pure functions over plain numbers; no method code.
#pragma once

#include <cstddef>
#include <vector>

#include "core/types.h"

namespace lmd {

// Rank (1-based) of the candidate `target` when candidates are ordered by
// score (descending). Candidates with a higher score rank before it; ties
// (including the unscored tail, score 0) count half: rank = 1 + higher +
// tied / 2, so a method that cannot tell tied maps apart gets the expected
// rank of a random order. `scores` holds one score per candidate.
double RankOfTarget(const std::vector<double>& scores, size_t target);

// True when a 1-based rank is within the top `percent` % of `candidates`
// maps: rank <= max(1, percent / 100 * candidates).
bool WithinTopPercent(double rank, size_t candidates, double percent);

// One query's outcome, as the metrics need it.
struct QueryOutcome {
  double rank = 0.0;          // 1-based rank of the relevant map among the candidates
  size_t candidates = 0;      // database size for this query (valid candidates)
  int first_place_hit = -1;   // 0-based position of the first hit showing the query's place; -1 = none in the list
  bool place_counted = true;  // false: no candidate shows the query's place (left out of place recall)
  bool has_pose = false;      // the top hit is right and carries a metric pose
  double pose_err_m = 0.0;    // translation error of that pose, m
  double pose_err_deg = 0.0;  // rotation error, deg
  double ms = 0.0;            // time spent on the query, ms
};

// Averages over the queries of one dataset and method. Rates are fractions
// in [0, 1]; anr is in %.
struct RetrievalSummary {
  size_t queries = 0;
  double candidates_mean = 0.0;
  double anr = 0.0;          // % mean of rank / candidates (paper's ANR)
  double recall_at_1 = 0.0;  // relevant map ranked first
  double top1 = 0.0, top5 = 0.0, top10 = 0.0;  // relevant map within the top X %
  size_t top1_count = 0, top5_count = 0, top10_count = 0;
  size_t place_queries = 0;  // queries with place_counted
  double place_at_1 = 0.0, place_at_5 = 0.0;
  size_t pose_count = 0;     // correct top hits with a pose
  double pose_err_m_median = 0.0, pose_err_m_p90 = 0.0;
  double pose_err_deg_median = 0.0, pose_err_deg_p90 = 0.0;
  double ms_per_query = 0.0;
};

RetrievalSummary Summarize(const std::vector<QueryOutcome>& outcomes);

// Mean of each field over datasets (each dataset weighs the same, as in the
// paper's "averaged over datasets"); counts are summed. Pose fields average
// only over datasets that have poses.
RetrievalSummary AverageOverDatasets(const std::vector<RetrievalSummary>& per_dataset);

// Quantile q in [0, 1] with linear interpolation between order statistics; 0
// for an empty vector.
double Quantile(std::vector<double> values, double q);

// Translation (m) and rotation (deg, absolute, wrapped) difference of two poses.
void PoseError(const Pose2& estimate, const Pose2& truth, double* err_m, double* err_deg);

// Success-rate curve: `first_success` holds, per task, the 1-based rank k at
// which the task first succeeds (0 = never). Returns, for each k in `ks`, the
// fraction of tasks with 0 < first_success <= k. Empty tasks give zeros.
std::vector<double> SuccessCurve(const std::vector<size_t>& first_success, const std::vector<size_t>& ks);

// True when some point of a change mask lies within radius_m of some truly
// changed point (both in the query map's own frame).
bool MaskHitsChange(const std::vector<Point2>& mask_points, const std::vector<Point2>& changed_points,
                    double radius_m = 0.5);

// 1, 2, 5, 10, 20, 50, ... up to and including the first value >= max_k.
std::vector<size_t> LogSteps(size_t max_k);

}  // namespace lmd
