// Scoring of the localisation pipeline's answers (core/localize), the same
// whether they come from lmd-eval's own run (`retrieval`, method best) or
// from a live lmdd (`served`): place recall, the metric pose, whether lmdd
// was sure and right, change masks, and cost.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bench/common/calibration.h"
#include "bench/eval/eval_dataset.h"
#include "core/types.h"

namespace lmd::eval {

// A "sure" answer counts as right when the top hit shows the query's place
// and its pose is this close to the truth.
inline constexpr double kSurePoseM = 0.2;
inline constexpr double kSurePoseDeg = 1.0;
// A change mask finds the change when one of its points is this close to a
// changed point and its hit's pose puts every one of its points this close to
// where the truth puts them in the hit's map (MaskFindsChange).
inline constexpr double kMaskHitM = 0.5;

// A sure answer's pose this close to the truth, the place right, is a near
// miss (AnswerOutcome::wrong_pose_fits_better).
inline constexpr double kNearMissM = 0.5;
inline constexpr double kNearMissDeg = 3.0;

// Who the verdict's best rival is (AnswerOutcome::rival).
enum class RivalKind {
  kNone,       // no rival
  kSelf,       // no returned hit scores rival_score: the best map at another pose (or a hit past top_k)
  kSamePlace,  // a hit at the query's true pose in it (to kSurePose*): the maps were taken to disagree
  kPlaceOff,   // a hit of the query's place at a wrong pose
  kElsewhere,  // a hit that does not show the place, at a wrong pose: a look-alike
};
inline constexpr int kRivalKinds = 5;
const char* RivalName(RivalKind kind);

// One answer, in the dataset's map indices.
struct Answer {
  struct Hit {
    size_t db = 0;
    Pose2 pose;  // query own frame in the db map's own frame
    double score = 0.0;
    bool agrees_with_best = true;
  };
  struct Mask {
    size_t db = 0;  // the hit it is credited to
    Pose2 pose;     // that hit's pose: query own frame in the db map's own frame
    std::vector<Point2> points;  // query own frame
  };
  std::vector<Hit> hits;    // best first
  bool localized = false;   // the verdict
  double confidence = 0.0;
  double rival_score = 0.0;  // the verdict's best rival (0: none)
  std::optional<Pose2> site_pose;  // the query's own frame in the collection's (anchored collections)
  std::optional<Eigen::Matrix3d> pose_covariance;  // of hits[0].pose (Localization.pose_covariance)
  std::vector<Mask> masks;  // best first
  double cpu_ms = 0.0;      // lmdd's (or the pipeline's) CPU on this query
  double wall_ms = 0.0;
};

struct AnswerOutcome {
  bool place_counted = false;  // a candidate shows the query's place
  int first_place_hit = -1;    // position of the first hit showing it; -1 = none
  bool pose_known = false;     // the top hit shows the place
  double pose_err_m = 0.0, pose_err_deg = 0.0;
  // The answer's site pose against the query's log pose, where the top hit
  // shows the place and the answer has one (maps stored at their log poses).
  bool site_known = false;
  double site_err_m = 0.0, site_err_deg = 0.0;
  bool top_right = false;        // the top hit shows the place, its pose within kSurePose*
  // Where the top hit shows the place and the answer has a pose covariance:
  // the squared Mahalanobis distance of its pose error (x, y, theta) under
  // it; -1 elsewhere. A calibrated covariance puts it below the chi-square
  // (3 dof) quantile q for a share q of the answers.
  double pose_d2 = -1.0;
  // The answer's pose covariance as standard deviations: the position's
  // along its least known direction (m) and the heading's (deg); -1 where
  // the answer has none.
  double position_sd_m = -1.0, heading_sd_deg = -1.0;
  bool localized = false;
  bool localized_right = false;  // localized and top_right
  // Sure and wrong by a near miss (the right place, the pose beyond
  // kSurePose* but within kNearMiss*), yet the answered pose explains the
  // query better than the logs' truth does (more of its points on the hit's,
  // fewer in its free space): the truth's own error may be the cause.
  // Unchanged queries only.
  bool wrong_pose_fits_better = false;
  // What kept the verdict's margin down: the best hit that disagrees with the
  // best one, or none of the returned hits (the best map at another pose).
  RivalKind rival = RivalKind::kNone;
  double confidence = 0.0;
  bool change_task = false;      // the query carried a simulated change (and has a place)
  size_t first_change_mask = 0;  // 1-based rank of the first mask that finds it; 0 = none
  size_t masks = 0, false_masks = 0;  // masks returned; of them, those that find no change of a right hit
  double cpu_ms = 0.0, wall_ms = 0.0;
};

// Whether a change mask (`points`, query own frame) credited to stored map
// `db` at `pose` finds the query's simulated change: it touches the change
// (kMaskHitM), and `pose` places it in the map where the truth does (each of
// its points within kMaskHitM). A mask claims its points are new where the
// stored map saw free space; that claim is right whether or not the map
// shows the rest of the query (the place rule of place recall), and a hit at
// a wrong place cannot place it right.
bool MaskFindsChange(const Dataset& d, const EvalQuery& q, const std::vector<Point2>& points, size_t db,
                     const Pose2& pose);

// `changed`: the answer is to the query's changed copy (q.changed).
AnswerOutcome ScoreAnswer(const Dataset& d, const EvalQuery& q, const Answer& answer, bool changed);

struct AnswerSummary {
  size_t queries = 0, place_queries = 0;
  double place_at_1 = 0.0, place_at_5 = 0.0;
  size_t pose_count = 0;
  double pose_err_m_median = 0.0, pose_err_m_p90 = 0.0, pose_err_deg_median = 0.0, pose_err_deg_p90 = 0.0;
  size_t site_count = 0;  // AnswerOutcome::site_known
  double site_err_m_median = 0.0, site_err_m_p90 = 0.0, site_err_deg_median = 0.0;
  // Of the answers with a pose_d2, the shares within the pose covariance's
  // 50 % and 95 % ellipsoids; of the sure ones among them, within 95 %.
  size_t covariance_count = 0, covariance_sure = 0;
  double within_50 = 0.0, within_95 = 0.0, sure_within_95 = 0.0;
  // How well `confidence` states how often the top hit is right (top_right),
  // over all answers (calibration.h). Of a mean over logs: the calibration
  // error and Brier score are means, the bins the answers pooled.
  Reliability reliability;
  double localized_share = 0.0;      // of all queries
  double localized_precision = 1.0;  // right among localized answers (1 when none)
  size_t localized = 0, localized_wrong = 0;
  size_t wrong_pose_fits_better = 0;  // of localized_wrong (AnswerOutcome::wrong_pose_fits_better)
  // Answers top_right but not localized, by their rival.
  size_t unsure_right = 0, unsure_right_rival[kRivalKinds] = {};
  size_t change_tasks = 0;
  double change_success_at_1 = 0.0;  // of change tasks: the top mask finds the change
  size_t masks = 0, false_masks = 0;
  double false_mask_share = 0.0;     // of all masks returned
  double cpu_ms_p50 = 0.0, cpu_ms_p99 = 0.0, cpu_ms_mean = 0.0;
  double wall_ms_p50 = 0.0, wall_ms_p99 = 0.0;
};

AnswerSummary SummarizeAnswers(const std::vector<AnswerOutcome>& outcomes);
// Each field's mean over the summaries (each log weighs the same); counts summed.
AnswerSummary MeanOverLogs(const std::vector<AnswerSummary>& logs);

// JSON object of a summary (no trailing newline).
std::string SummaryJson(const AnswerSummary& s);

}  // namespace lmd::eval
