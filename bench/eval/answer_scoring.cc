#include "bench/eval/answer_scoring.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Dense>

#include "core/align/icp.h"
#include "core/align/scan_match.h"
#include "core/eval/retrieval_metrics.h"
#include "core/localmap/pose_ops.h"

namespace lmd::eval {

namespace {

// Quantiles of the chi-square distribution with 3 degrees of freedom (x, y, theta).
constexpr double kChiSquare3Dof50 = 2.366, kChiSquare3Dof95 = 7.815;

// The part of verification's score (core/localize) that the query's points
// give: their overlap less their share in the map's free space.
double Fit(const std::vector<Point2>& query, const PreparedMap& db, const Pose2& pose) {
  const Overlap o = MeasureOverlap(query, db, pose, ScanMatchOptions().inlier_radius_m);
  return o.fraction - o.conflict_fraction;
}

bool FitsBetterThanTruth(const Dataset& d, const EvalQuery& q, const Answer::Hit& top) {
  const PreparedMap db = PrepareMap(d.maps[top.db], ScanMatchOptions().map);
  const std::vector<Point2>& points = d.maps[q.map].points;
  return Fit(points, db, top.pose) > Fit(points, db, d.TruePose(q.map, top.db));
}

RivalKind ClassifyRival(const Dataset& d, const EvalQuery& q, const Answer& answer) {
  if (answer.rival_score <= 0) return RivalKind::kNone;
  for (const Answer::Hit& h : answer.hits) {
    if (h.agrees_with_best || std::abs(h.score - answer.rival_score) > 1e-6) continue;
    double err_m = 0, err_deg = 0;
    PoseError(h.pose, d.TruePose(q.map, h.db), &err_m, &err_deg);
    if (err_m <= kSurePoseM && err_deg <= kSurePoseDeg) return RivalKind::kSamePlace;
    return d.ShowsPlace(q, h.db) ? RivalKind::kPlaceOff : RivalKind::kElsewhere;
  }
  return RivalKind::kSelf;
}

}  // namespace

const char* RivalName(RivalKind kind) {
  switch (kind) {
    case RivalKind::kNone: return "none";
    case RivalKind::kSelf: return "self";
    case RivalKind::kSamePlace: return "same_place";
    case RivalKind::kPlaceOff: return "place_off";
    case RivalKind::kElsewhere: return "elsewhere";
  }
  return "?";
}

bool MaskFindsChange(const Dataset& d, const EvalQuery& q, const std::vector<Point2>& points, size_t db,
                     const Pose2& pose) {
  if (!q.change_ok || !MaskHitsChange(points, q.changed_points, kMaskHitM)) return false;
  const Pose2 truth = d.TruePose(q.map, db);
  return std::all_of(points.begin(), points.end(), [&](const Point2& p) {
    const Point2 answered = TransformPoint(pose, p), true_place = TransformPoint(truth, p);
    return std::hypot(answered.x - true_place.x, answered.y - true_place.y) <= kMaskHitM;
  });
}

AnswerOutcome ScoreAnswer(const Dataset& d, const EvalQuery& q, const Answer& answer, bool changed) {
  AnswerOutcome o;
  o.place_counted = !q.places.empty();
  for (size_t i = 0; i < answer.hits.size(); ++i) {
    if (d.ShowsPlace(q, answer.hits[i].db)) {
      o.first_place_hit = static_cast<int>(i);
      break;
    }
  }
  if (o.first_place_hit == 0) {
    o.pose_known = true;
    const Pose2 truth = d.TruePose(q.map, answer.hits[0].db);
    PoseError(answer.hits[0].pose, truth, &o.pose_err_m, &o.pose_err_deg);
    if (answer.pose_covariance) {
      const Eigen::Vector3d e(answer.hits[0].pose.x - truth.x, answer.hits[0].pose.y - truth.y,
                              std::remainder(answer.hits[0].pose.theta - truth.theta, 2 * M_PI));
      o.pose_d2 = e.dot(answer.pose_covariance->ldlt().solve(e));
    }
    if (answer.site_pose) {
      o.site_known = true;
      PoseError(*answer.site_pose, d.maps[q.map].truth.global_frame, &o.site_err_m, &o.site_err_deg);
    }
  }
  if (answer.pose_covariance) {
    const PoseDeviations sd = PoseStandardDeviations(*answer.pose_covariance);
    o.position_sd_m = sd.position_m, o.heading_sd_deg = sd.heading_rad * 180 / M_PI;
  }
  o.top_right = o.pose_known && o.pose_err_m <= kSurePoseM && o.pose_err_deg <= kSurePoseDeg;
  o.localized = answer.localized;
  o.localized_right = o.localized && o.top_right;
  o.wrong_pose_fits_better = !changed && o.localized && o.pose_known && !o.localized_right &&
                             o.pose_err_m <= kNearMissM && o.pose_err_deg <= kNearMissDeg &&
                             FitsBetterThanTruth(d, q, answer.hits[0]);
  o.rival = ClassifyRival(d, q, answer);
  o.confidence = answer.confidence;
  o.change_task = changed && q.change_ok && o.place_counted;
  if (changed) {
    for (size_t r = 0; r < answer.masks.size(); ++r) {
      const Answer::Mask& m = answer.masks[r];
      const bool finds = MaskFindsChange(d, q, m.points, m.db, m.pose);
      if (finds && o.first_change_mask == 0) o.first_change_mask = r + 1;
      o.false_masks += !finds;
    }
    o.masks = answer.masks.size();
  }
  o.cpu_ms = answer.cpu_ms;
  o.wall_ms = answer.wall_ms;
  return o;
}

AnswerSummary SummarizeAnswers(const std::vector<AnswerOutcome>& outcomes) {
  AnswerSummary s;
  s.queries = outcomes.size();
  size_t at1 = 0, at5 = 0, change_ok = 0, within_50 = 0, within_95 = 0, sure_within_95 = 0;
  std::vector<double> err_m, err_deg, site_m, site_deg, cpu, wall;
  std::vector<StatedOutcome> stated;
  for (const AnswerOutcome& o : outcomes) {
    stated.push_back({o.confidence, o.top_right});
    if (o.place_counted) {
      ++s.place_queries;
      at1 += o.first_place_hit == 0;
      at5 += o.first_place_hit >= 0 && o.first_place_hit < 5;
    }
    if (o.pose_known) err_m.push_back(o.pose_err_m), err_deg.push_back(o.pose_err_deg);
    if (o.site_known) site_m.push_back(o.site_err_m), site_deg.push_back(o.site_err_deg);
    if (o.pose_d2 >= 0) {
      ++s.covariance_count;
      within_50 += o.pose_d2 <= kChiSquare3Dof50;
      within_95 += o.pose_d2 <= kChiSquare3Dof95;
      s.covariance_sure += o.localized;
      sure_within_95 += o.localized && o.pose_d2 <= kChiSquare3Dof95;
    }
    s.localized += o.localized;
    s.localized_wrong += o.localized && !o.localized_right;
    s.wrong_pose_fits_better += o.wrong_pose_fits_better;
    if (!o.localized && o.top_right) {
      ++s.unsure_right;
      ++s.unsure_right_rival[static_cast<int>(o.rival)];
    }
    if (o.change_task) {
      ++s.change_tasks;
      change_ok += o.first_change_mask == 1;
    }
    s.masks += o.masks, s.false_masks += o.false_masks;
    cpu.push_back(o.cpu_ms), wall.push_back(o.wall_ms);
  }
  auto rate = [](size_t n, size_t of) { return of ? static_cast<double>(n) / static_cast<double>(of) : 0.0; };
  s.place_at_1 = rate(at1, s.place_queries);
  s.place_at_5 = rate(at5, s.place_queries);
  s.pose_count = err_m.size();
  s.pose_err_m_median = Quantile(err_m, 0.5), s.pose_err_m_p90 = Quantile(err_m, 0.9);
  s.pose_err_deg_median = Quantile(err_deg, 0.5), s.pose_err_deg_p90 = Quantile(err_deg, 0.9);
  s.site_count = site_m.size();
  s.site_err_m_median = Quantile(site_m, 0.5), s.site_err_m_p90 = Quantile(site_m, 0.9);
  s.site_err_deg_median = Quantile(site_deg, 0.5);
  s.within_50 = rate(within_50, s.covariance_count), s.within_95 = rate(within_95, s.covariance_count);
  s.sure_within_95 = rate(sure_within_95, s.covariance_sure);
  s.reliability = MeasureReliability(stated);
  s.localized_share = rate(s.localized, s.queries);
  s.localized_precision = s.localized ? 1.0 - rate(s.localized_wrong, s.localized) : 1.0;
  s.change_success_at_1 = rate(change_ok, s.change_tasks);
  s.false_mask_share = rate(s.false_masks, s.masks);
  s.cpu_ms_p50 = Quantile(cpu, 0.5), s.cpu_ms_p99 = Quantile(cpu, 0.99);
  double total = 0;
  for (double c : cpu) total += c;
  s.cpu_ms_mean = cpu.empty() ? 0.0 : total / static_cast<double>(cpu.size());
  s.wall_ms_p50 = Quantile(wall, 0.5), s.wall_ms_p99 = Quantile(wall, 0.99);
  return s;
}

AnswerSummary MeanOverLogs(const std::vector<AnswerSummary>& logs) {
  AnswerSummary m;
  if (logs.empty()) return m;
  m.localized_precision = 0.0;
  const double n = static_cast<double>(logs.size());
  for (const AnswerSummary& s : logs) {
    m.queries += s.queries, m.place_queries += s.place_queries, m.pose_count += s.pose_count;
    m.localized += s.localized, m.localized_wrong += s.localized_wrong, m.change_tasks += s.change_tasks;
    m.wrong_pose_fits_better += s.wrong_pose_fits_better;
    m.unsure_right += s.unsure_right;
    for (int k = 0; k < kRivalKinds; ++k) m.unsure_right_rival[k] += s.unsure_right_rival[k];
    m.masks += s.masks, m.false_masks += s.false_masks;
    m.place_at_1 += s.place_at_1 / n, m.place_at_5 += s.place_at_5 / n;
    m.pose_err_m_median += s.pose_err_m_median / n, m.pose_err_m_p90 += s.pose_err_m_p90 / n;
    m.pose_err_deg_median += s.pose_err_deg_median / n, m.pose_err_deg_p90 += s.pose_err_deg_p90 / n;
    m.site_count += s.site_count;
    m.site_err_m_median += s.site_err_m_median / n, m.site_err_m_p90 += s.site_err_m_p90 / n;
    m.site_err_deg_median += s.site_err_deg_median / n;
    m.covariance_count += s.covariance_count, m.covariance_sure += s.covariance_sure;
    m.within_50 += s.within_50 / n, m.within_95 += s.within_95 / n, m.sure_within_95 += s.sure_within_95 / n;
    Reliability& r = m.reliability;
    r.calibration_error += s.reliability.calibration_error / n, r.brier += s.reliability.brier / n;
    r.answers += s.reliability.answers;
    for (int b = 0; b < kReliabilityBins; ++b) {
      const double count = static_cast<double>(s.reliability.count[b]);
      r.count[b] += s.reliability.count[b];
      r.mean_probability[b] += count * s.reliability.mean_probability[b];
      r.share_right[b] += count * s.reliability.share_right[b];
    }
    m.localized_share += s.localized_share / n, m.localized_precision += s.localized_precision / n;
    m.change_success_at_1 += s.change_success_at_1 / n, m.false_mask_share += s.false_mask_share / n;
    m.cpu_ms_p50 += s.cpu_ms_p50 / n, m.cpu_ms_p99 += s.cpu_ms_p99 / n, m.cpu_ms_mean += s.cpu_ms_mean / n;
    m.wall_ms_p50 += s.wall_ms_p50 / n, m.wall_ms_p99 += s.wall_ms_p99 / n;
  }
  for (int b = 0; b < kReliabilityBins; ++b) {
    const double count = static_cast<double>(m.reliability.count[b]);
    if (count > 0) m.reliability.mean_probability[b] /= count, m.reliability.share_right[b] /= count;
  }
  return m;
}

std::string SummaryJson(const AnswerSummary& s) {
  char buf[2000];
  std::snprintf(buf, sizeof buf,
                "{\"queries\": %zu, \"place_queries\": %zu, \"place_at_1\": %.4f, \"place_at_5\": %.4f, "
                "\"pose_count\": %zu, \"pose_err_m_median\": %.4f, \"pose_err_m_p90\": %.4f, "
                "\"pose_err_deg_median\": %.4f, \"pose_err_deg_p90\": %.4f, \"site_count\": %zu, "
                "\"site_err_m_median\": %.4f, \"site_err_m_p90\": %.4f, \"site_err_deg_median\": %.4f, "
                "\"covariance_count\": %zu, \"within_50\": %.4f, \"within_95\": %.4f, \"covariance_sure\": %zu, "
                "\"sure_within_95\": %.4f, \"calibration_error\": %.4f, \"brier\": %.4f, "
                "\"localized\": %zu, "
                "\"localized_share\": %.4f, \"localized_wrong\": %zu, \"localized_precision\": %.4f, "
                "\"wrong_pose_fits_better\": %zu, \"unsure_right\": %zu, \"unsure_right_rival\": "
                "{\"none\": %zu, \"self\": %zu, \"same_place\": %zu, \"place_off\": %zu, \"elsewhere\": %zu}, "
                "\"change_tasks\": %zu, \"change_success_at_1\": %.4f, \"masks\": %zu, \"false_masks\": %zu, "
                "\"false_mask_share\": %.4f, \"cpu_ms_p50\": %.3f, \"cpu_ms_p99\": %.3f, \"cpu_ms_mean\": %.3f, "
                "\"wall_ms_p50\": %.3f, \"wall_ms_p99\": %.3f}",
                s.queries, s.place_queries, s.place_at_1, s.place_at_5, s.pose_count, s.pose_err_m_median,
                s.pose_err_m_p90, s.pose_err_deg_median, s.pose_err_deg_p90, s.site_count, s.site_err_m_median,
                s.site_err_m_p90, s.site_err_deg_median, s.covariance_count, s.within_50, s.within_95,
                s.covariance_sure, s.sure_within_95, s.reliability.calibration_error, s.reliability.brier, s.localized,
                s.localized_share, s.localized_wrong, s.localized_precision, s.wrong_pose_fits_better, s.unsure_right,
                s.unsure_right_rival[0], s.unsure_right_rival[1], s.unsure_right_rival[2], s.unsure_right_rival[3],
                s.unsure_right_rival[4], s.change_tasks, s.change_success_at_1, s.masks, s.false_masks,
                s.false_mask_share, s.cpu_ms_p50, s.cpu_ms_p99, s.cpu_ms_mean, s.wall_ms_p50, s.wall_ms_p99);
  return buf;
}

}  // namespace lmd::eval
