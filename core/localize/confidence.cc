#include "core/localize/confidence.h"

#include <algorithm>
#include <cmath>

#include "core/align/icp.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

// Of `points` (frame B) moved by `pose` into frame A, those A observed
// (near one of A's points, or in its free space): the share in its free space.
double FreeSpaceShare(const std::vector<Point2>& points, const PreparedMap& a, const Pose2& pose) {
  const Overlap o = MeasureOverlap(points, a, pose, 0.3);
  const size_t observed = o.inliers + o.conflicts;
  return observed == 0 ? 0.0 : static_cast<double>(o.conflicts) / static_cast<double>(observed);
}

}  // namespace

double Disagreement(const PreparedMap& a, const PreparedMap& b, const Pose2& b_in_a) {
  return std::max(FreeSpaceShare(b.sparse_points, a, b_in_a), FreeSpaceShare(a.sparse_points, b, Inverse(b_in_a)));
}

bool OnePlace(const Pose2& a, const Pose2& b, const ConfidenceOptions& options) {
  return std::hypot(a.x - b.x, a.y - b.y) <= options.same_place_m &&
         std::abs(std::remainder(a.theta - b.theta, 2 * M_PI)) <= options.same_place_deg * M_PI / 180;
}

double LogisticFit::Probability(double best_score, double margin, bool sure) const {
  const double z = bias + score_weight * best_score + margin_weight * margin + (sure ? sure_weight : 0.0);
  return 1.0 / (1.0 + std::exp(-z));
}

void SetConfidence(Verdict* v, bool has_hits, const ConfidenceOptions& options) {
  const double margin = v->best_score - v->rival_score;
  v->confidence = has_hits ? options.calibration.Probability(v->best_score, margin, v->sure) : 0.0;
}

bool PoseKnownToPromise(const Eigen::Matrix3d& covariance, const ConfidenceOptions& options) {
  if (options.promise_sigmas <= 0) return true;
  const PoseDeviations sd = PoseStandardDeviations(covariance);
  return options.promise_sigmas * sd.position_m <= options.max_pose_spread_m &&
         options.promise_sigmas * sd.heading_rad * 180 / M_PI <= options.max_pose_spread_deg;
}

double HighestHarmlessRival(double best_score, const ConfidenceOptions& options) {
  double margin = options.min_margin;
  const double p = options.min_global_probability;
  if (p >= 1.0) return -1.0;
  if (p > 0.0) {  // the margin at which the global line's probability reaches p
    const LogisticFit& line = options.global_fit;
    const double logit = std::log(p / (1.0 - p));
    margin = std::max(margin, (logit - line.bias - line.score_weight * best_score) / line.margin_weight);
  }
  return best_score - margin;
}

int SiteNamingHit(const std::vector<JudgedHit>& hits) {
  for (size_t i = 0; i < hits.size(); ++i) {
    if (hits[i].agrees_with_best && hits[i].collection_pose) return static_cast<int>(i);
  }
  return -1;
}

bool SitePlaceClear(const std::vector<JudgedHit>& hits, int named, double named_other_pose,
                    const ConfidenceOptions& options) {
  if (named < 0) return false;
  const JudgedHit& naming = hits[static_cast<size_t>(named)];
  double elsewhere = named_other_pose;
  for (const JudgedHit& h : hits) {
    // As Judge compares: hits further below than agreement_window are no rivals.
    if (!h.collection_pose || h.score < naming.score - options.agreement_window) continue;
    if (!OnePlace(*naming.collection_pose, *h.collection_pose, options)) elsewhere = std::max(elsewhere, h.score);
  }
  return ClearLead(naming.score, elsewhere, options);
}

bool ClearLead(double best_score, double rival_score, const ConfidenceOptions& options) {
  const double margin = best_score - rival_score;
  return best_score >= options.min_score && margin >= options.min_margin &&
         options.global_fit.Probability(best_score, margin, false) >= options.min_global_probability;
}

Verdict Judge(std::vector<JudgedHit>* hits, const ConfidenceOptions& options, double self_rival) {
  Verdict v;
  v.rival_score = self_rival;
  if (hits->empty() || (*hits)[0].map == nullptr) return v;
  JudgedHit& best = (*hits)[0];
  best.agrees_with_best = true;
  v.best_score = best.score;
  for (size_t i = 1; i < hits->size(); ++i) {
    JudgedHit& h = (*hits)[i];
    h.agrees_with_best = false;
    if (h.map == nullptr || h.score < best.score - options.agreement_window) continue;
    if (best.collection_pose && h.collection_pose) {
      h.agrees_with_best = OnePlace(*best.collection_pose, *h.collection_pose, options);
    } else {
      // The query's pose in A and in B give B's frame in A's: A <- query <- B.
      const Pose2 b_in_a = Compose(best.pose, Inverse(h.pose));
      h.agrees_with_best = Disagreement(*best.map, *h.map, b_in_a) <= options.max_disagreement;
    }
    if (h.agrees_with_best) {
      ++v.agreeing;
    } else {
      v.rival_score = std::max(v.rival_score, h.score);
    }
  }
  // Anchored maps of the place that fit the query put it somewhere: where
  // they agree, but not on the best hit's pose within what a sure answer
  // promises, the pose is not known that well.
  if (best.collection_pose && options.max_pose_spread_m > 0) {
    std::vector<Pose2> offsets;  // in the best hit's site frame
    for (size_t i = 1; i < hits->size(); ++i) {
      const JudgedHit& h = (*hits)[i];
      if (!h.agrees_with_best || !h.collection_pose || h.score < options.min_score) continue;
      offsets.push_back(Compose(Inverse(*best.collection_pose), *h.collection_pose));
    }
    if (offsets.size() >= 2) {
      const Pose2 median = ComponentMedian(offsets);
      v.pose_spread_m = std::hypot(median.x, median.y);
      v.pose_spread_deg = std::abs(median.theta) * 180 / M_PI;
    }
  }
  // Maps that agree with the best by what they saw may still show two
  // places: identical rooms of one building put no wall in each other's
  // free space. Where anchored maps among them name places apart in the
  // site, the best hit's place is not known (lmd-bench load, simulated
  // building, global queries: the top hit a twin room 6-39 m away, sure).
  bool places_apart = false;
  if (const int named = SiteNamingHit(*hits); named >= 0) {
    const Pose2& place = *(*hits)[static_cast<size_t>(named)].collection_pose;
    places_apart = std::any_of(hits->begin(), hits->end(), [&](const JudgedHit& h) {
      return h.agrees_with_best && h.collection_pose && !OnePlace(place, *h.collection_pose, options);
    });
  }
  v.sure = !places_apart && ClearLead(v.best_score, v.rival_score, options);
  if (options.max_pose_spread_m > 0 &&
      (v.pose_spread_m > options.max_pose_spread_m || v.pose_spread_deg > options.max_pose_spread_deg)) {
    v.sure = false;
  }
  SetConfidence(&v, true, options);
  return v;
}

}  // namespace lmd
