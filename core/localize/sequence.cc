#include "core/localize/sequence.h"

#include <algorithm>
#include <cmath>

#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"

namespace lmd {

using namespace localize_internal;

Localization LocalizeSequence(const LocalQuery& newest, const std::vector<SequenceStep>& earlier,
                              const MapSource& source, const LocalizeOptions& options,
                              const std::function<bool(uint64_t)>& excluded, const std::function<bool()>& stop,
                              bool with_changes) {
  Localization out;
  std::vector<LocalizedHit> hits = SearchAndVerify(newest, source, options, excluded, stop, &out.stats);
  const size_t checked = std::min(hits.size(), options.sequence_hypotheses);
  const double n = static_cast<double>(earlier.size() + 1);
  for (size_t i = 0; i < checked; ++i) {
    if (stop && stop()) break;
    LocalizedHit& hit = hits[i];
    double total = hit.score;
    for (const SequenceStep& step : earlier) {
      // Where the odometry puts the earlier map in this hypothesis's stored
      // map, and how far off it may be after that much travel.
      ScanMatchOptions match = options.match;
      match.window_m += options.sequence_drift * step.travel_m;
      match.window_deg += options.sequence_drift_rad_per_m * step.travel_m * 180 / M_PI;
      const ScanMatch m = MatchLocalMaps(step.query.match, *hit.db, {Compose(hit.pose, step.in_newest)}, match);
      ++out.stats.maps_matched;
      const double score = Scored(step.query, *hit.db, m, options).score;
      total += score;
      hit.sequence_agreeing += score >= options.confidence.min_score;
    }
    hit.score = total / n;  // the whole sequence's mean
  }
  // Hypotheses the sequence did not check keep only the newest map's score:
  // ranked after those it did.
  for (size_t i = checked; i < hits.size(); ++i) hits[i].score = std::min(hits[i].score, 0.0);
  std::stable_sort(hits.begin(), hits.end(), [](const LocalizedHit& a, const LocalizedHit& b) {
    if (a.score != b.score) return a.score > b.score;
    return a.map_id < b.map_id;
  });
  LocalizeOptions judged = options;
  judged.refine_best = false;  // a refinement would score the newest map alone
  Conclude(newest, judged, std::move(hits), nullptr, with_changes, &out);
  out.verdict.sequence_maps = earlier.size();
  if (!out.hits.empty()) out.verdict.sequence_agreeing = out.hits[0].sequence_agreeing;
  SetCollectionPoses(source, &out.hits);
  return out;
}

}  // namespace lmd
