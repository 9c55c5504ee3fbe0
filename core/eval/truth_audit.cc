#include "core/eval/truth_audit.h"

#include <algorithm>
#include <cmath>

#include "core/align/icp.h"
#include "core/eval/retrieval_metrics.h"
#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

// From the log's pose exactly instead: the same medians within 0.3 cm on the
// nine logs of ../shared/data.
const Pose2 kStartOffset{0.25, -0.2, 2 * M_PI / 180};
constexpr double kMoveWindowM = 3.0;  // each map of the place searches this far around the log's pose
constexpr size_t kMinAgreeing = 3;
constexpr double kAgreeM = 0.1, kAgreeDeg = 0.5;

}  // namespace

std::optional<Pose2> MatchNearLogPose(const LocalQuery& query, const PreparedMap& db, const Pose2& log_pose,
                                      const LocalizeOptions& options, double window_m) {
  if (query.match.points.empty()) return std::nullopt;
  ScanMatchOptions match = options.match;
  if (window_m > 0) match.window_m = window_m;
  const ScanMatch m = MatchLocalMaps(query.match, db, {Compose(log_pose, kStartOffset)}, match);
  const Pose2 refined = RefinePose(query.match.points, db, m.pose, options.refine);
  const LocalizedHit hit = localize_internal::ScoredAt(query, db, refined, options);
  if (std::max(hit.score, m.score) < options.confidence.min_score) return std::nullopt;
  return hit.score >= m.score ? refined : m.pose;
}

std::optional<PlaceMove> MoveByItsPlace(const LocalQuery& query, const std::vector<PlaceMap>& place,
                                        const LocalizeOptions& options) {
  std::vector<Pose2> moves;
  for (const PlaceMap& p : place) {
    const std::optional<Pose2> pose = MatchNearLogPose(query, *p.map, p.log_pose, options, kMoveWindowM);
    if (pose) moves.push_back(Compose(Inverse(p.log_pose), *pose));
  }
  if (moves.size() < kMinAgreeing) return std::nullopt;
  std::vector<double> xs, ys, thetas;
  for (const Pose2& m : moves) {
    xs.push_back(m.x), ys.push_back(m.y), thetas.push_back(std::remainder(m.theta, 2 * M_PI));
  }
  PlaceMove out;
  out.move = {Quantile(xs, 0.5), Quantile(ys, 0.5), Quantile(thetas, 0.5)};
  out.matched = moves.size();
  out.agreeing = std::count_if(moves.begin(), moves.end(), [&](const Pose2& m) {
    double err_m = 0, err_deg = 0;
    PoseError(m, out.move, &err_m, &err_deg);
    return err_m <= kAgreeM && err_deg <= kAgreeDeg;
  });
  if (out.agreeing < kMinAgreeing) return std::nullopt;
  return out;
}

}  // namespace lmd
