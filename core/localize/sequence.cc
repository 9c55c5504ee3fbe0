#include "core/localize/sequence.h"

#include <algorithm>
#include <cmath>

#include "core/localize/prior.h"
#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"

namespace lmd {

using namespace localize_internal;

namespace {

// A pose hypothesis for the newest map, and the evidence for it.
struct Hypothesis {
  Pose2 newest;             // the newest map's own frame: in the collection's frame, or in `db`'s
  double single = 0.0;      // the verification score of the map that proposed it
  LocalizedHit hit;         // the newest map's best hit at it (once scored)
  double score = 0.0;       // the sequence's mean
  // ... of its maps' fits as hits are ranked (RankFit): hypotheses are
  // ranked by it, as hits are, and scored by the mean of the scores.
  double rank = 0.0;
  size_t agreeing = 0;      // earlier maps that fit
};

bool Near(const Pose2& a, const Pose2& b, double metres, double radians) {
  return std::hypot(a.x - b.x, a.y - b.y) <= metres && std::abs(std::remainder(a.theta - b.theta, 2 * M_PI)) <= radians;
}

// The newest map's own hits and its fit at each hypothesis (of two fits of
// one map within a match window of each other, the better), best first:
// every pose at which the sequence's search saw the newest map fit.
std::vector<LocalizedHit> NewestFits(std::vector<LocalizedHit> hits, const std::vector<Hypothesis>& hypotheses,
                                     const LocalizeOptions& options) {
  const double window_rad = options.match.window_deg * M_PI / 180;
  for (const Hypothesis& h : hypotheses) {
    if (!h.hit.db) continue;
    auto same = std::find_if(hits.begin(), hits.end(), [&](const LocalizedHit& o) {
      return o.map_id == h.hit.map_id && Near(o.pose, h.hit.pose, options.match.window_m, window_rad);
    });
    if (same == hits.end()) {
      hits.push_back(h.hit);
    } else if (h.hit.score > same->score) {
      *same = h.hit;
    }
  }
  SortHits(&hits, options);
  return hits;
}

}  // namespace

SequenceCheck CheckSequenceAt(const LocalQuery& newest, const std::vector<SequenceStep>& earlier,
                              const MapSource& source, const LocalizeOptions& options, const Pose2& newest_pose,
                              const std::function<bool(uint64_t)>& excluded, const std::function<bool()>& stop) {
  // Every map of the sequence localised where the pose puts it (the window
  // grown by the odometry's drift over its travel: a heading error turns the
  // map about its own origin, which moves its centroid, the search's pivot,
  // too).
  LocalizeOptions near_options = options;
  // A map's fit is asked here, not whether it is sure: no rival pose, no slide.
  near_options.self_rival_radius_m = 0;
  near_options.confidence.min_slide_margin = 0;
  near_options.prior_first_stage = false;  // the hypotheses came from it
  near_options.prior_second_pose = false;  // a hypothesis names the pose; its window is the drift's
  near_options.prior_weak_fits = false;
  near_options.prior_any_near_maps = false;
  SequenceCheck check;
  for (size_t k = 0; k <= earlier.size(); ++k) {
    if (stop && stop()) break;
    const LocalQuery& query = k == 0 ? newest : earlier[k - 1].query;
    Prior prior;
    prior.pose = newest_pose;
    prior.radius_m = options.match.window_m;
    prior.heading_sigma_rad = options.match.window_deg * M_PI / 180;
    if (k > 0) {
      const SequenceStep& step = earlier[k - 1];
      const double heading_error = options.sequence_drift_rad_per_m * step.travel_m;
      prior.pose = Compose(newest_pose, step.in_newest);
      prior.radius_m += options.sequence_drift * step.travel_m +
                        std::hypot(step.query.match.centroid.x, step.query.match.centroid.y) * heading_error;
      prior.heading_sigma_rad += heading_error;
    }
    near_options.prior_maps = k == 0 ? options.sequence_newest_maps : options.sequence_prior_maps;
    const Localization l = LocalizeNear(query, source, near_options, prior, excluded, stop);
    check.maps_matched += l.stats.maps_matched;
    check.windows.push_back(prior);
    check.best.push_back(l.hits.empty() ? LocalizedHit{} : l.hits[0]);
  }
  return check;
}

Localization LocalizeSequence(const LocalQuery& newest, const std::vector<SequenceStep>& earlier,
                              const MapSource& source, const LocalizeOptions& given,
                              const std::function<bool(uint64_t)>& excluded, const std::function<bool()>& stop,
                              bool with_changes) {
  const LocalizeOptions options = WithStop(given, stop);
  Localization out;
  // Every map of the sequence proposes poses for the newest: its own hits,
  // carried to the newest through the odometry. A look-alike that fools the
  // newest map rarely fools the maps before it too. Only anchored maps can
  // propose one, so in a site map only they are searched: where lost robots
  // stored maps without anchors, those would otherwise fill every verified
  // slot (lmd-bench load --mode fleet: the robots' answers then had no site
  // pose and they stayed lost).
  LocalizeOptions site = options;
  site.search.anchored_only = source.HasAnchors();
  // Each map's hypotheses are checked through the others: a second round
  // where one map fits nowhere found no more places (lmd-eval served --mode
  // sequence, 2026-12-05: place@1 .922 -> .921) for +35 % CPU.
  site.second_round_hypotheses = 0;
  std::vector<LocalizedHit> newest_hits = SearchAndVerify(newest, source, site, excluded, &out.stats);
  SetCollectionPoses(source, &newest_hits);
  const double newest_unexamined_votes = out.stats.unexamined_votes;
  const bool anchored = std::any_of(newest_hits.begin(), newest_hits.end(),
                                    [](const LocalizedHit& h) { return h.collection_pose.has_value(); });
  // What each map of the sequence showed already: its verified hits, with
  // its own frame in the collection's frame (0: the newest, s + 1: earlier[s]).
  std::vector<std::vector<LocalizedHit>> shown(earlier.size() + 1);
  std::vector<Hypothesis> hypotheses;
  auto propose = [&](const Pose2& pose, double single) {
    for (Hypothesis& h : hypotheses) {
      if (Near(h.newest, pose, options.match.window_m, options.match.window_deg * M_PI / 180)) {
        h.single = std::max(h.single, single);
        return;
      }
    }
    hypotheses.push_back({pose, single, {}, 0.0, 0});
  };
  for (const LocalizedHit& h : newest_hits) {
    if (h.collection_pose) propose(*h.collection_pose, h.score), shown[0].push_back(h);
  }
  if (anchored) {
    for (size_t s = 0; s < earlier.size(); ++s) {
      if (StopAsked(options)) break;
      std::vector<LocalizedHit> hits = SearchAndVerify(earlier[s].query, source, site, excluded, &out.stats);
      SetCollectionPoses(source, &hits);
      for (const LocalizedHit& h : hits) {
        if (!h.collection_pose) continue;
        propose(Compose(*h.collection_pose, Inverse(earlier[s].in_newest)), h.score);
        shown[s + 1].push_back(h);
      }
    }
  }
  // A map's best verified hit within `prior` of where a hypothesis puts it:
  // evidence already in hand. The search near the hypothesis matches the
  // maps whose robots drove nearest, which need not be the ones that show
  // this map's view best (a map matched at 0.95 by its own search scored
  // 0.11 there: fr079's map 105 in process, 3-map sequence).
  auto best_shown = [&](size_t k, const Prior& prior) -> const LocalizedHit* {
    const LocalizedHit* best = nullptr;
    for (const LocalizedHit& h : shown[k]) {
      if (Near(*h.collection_pose, prior.pose, prior.radius_m, prior.heading_sigma_rad) && (!best || h.score > best->score)) {
        best = &h;
      }
    }
    return best;
  };
  if (!anchored) {
    // Without a site map, the newest map's hits are judged alone.
    if (site.search.anchored_only) newest_hits = SearchAndVerify(newest, source, options, excluded, &out.stats);
    Conclude(newest, options, std::move(newest_hits), nullptr, with_changes, &out, /*prior_place=*/false,
             SiteMaps{&source, &excluded});
    out.verdict.sequence_maps = earlier.size();
    return out;
  }
  std::stable_sort(hypotheses.begin(), hypotheses.end(),
                   [](const Hypothesis& a, const Hypothesis& b) { return a.single > b.single; });
  if (hypotheses.size() > options.sequence_hypotheses) hypotheses.resize(options.sequence_hypotheses);

  for (Hypothesis& h : hypotheses) {
    if (StopAsked(options)) break;
    const SequenceCheck check = CheckSequenceAt(newest, earlier, source, options, h.newest, excluded, stop);
    out.stats.maps_matched += check.maps_matched;
    // Each map's better fit: where the check found it, or already shown.
    double total = 0.0, total_rank = 0.0;
    for (size_t k = 0; k < check.best.size(); ++k) {
      const LocalizedHit* shown_here = best_shown(k, check.windows[k]);
      const LocalizedHit& found = check.best[k];
      const LocalizedHit* better = shown_here && (!found.db || shown_here->score > found.score) ? shown_here : &found;
      if (k == 0) h.hit = *better;
      const double score = better->db ? better->score : 0.0;
      total += score;
      total_rank += better->db ? RankFit(*better, options) : 0.0;
      if (k > 0) h.agreeing += score >= options.confidence.min_score;
    }
    if (!h.hit.db) continue;
    h.score = total / static_cast<double>(earlier.size() + 1);
    h.rank = total_rank / static_cast<double>(earlier.size() + 1);
  }
  // The hits: the newest map's best hit at each hypothesis, by the
  // sequence's rank; the verdict over them (two hypotheses at one place
  // agree, at two places one is the other's rival).
  std::stable_sort(hypotheses.begin(), hypotheses.end(),
                   [](const Hypothesis& a, const Hypothesis& b) { return a.rank > b.rank; });
  std::vector<LocalizedHit> hits;
  for (const Hypothesis& h : hypotheses) {
    if (!h.hit.db) continue;
    LocalizedHit hit = h.hit;
    hit.score = h.score;
    hit.sequence_agreeing = h.agreeing;
    hits.push_back(std::move(hit));
  }
  LocalizeOptions judged = options;
  judged.refine_best = false;  // a refinement would score the newest map alone
  judged.fuse_site_pose = false;  // its hits are hypotheses, each the newest map's best at one
  judged.changes_place_fit_of_union = false;  // ... so their union is no place either
  judged.changes_place_fit_before_conflicts = false;  // a hit's overlap is the newest map's, its score the sequence's
  judged.confidence.min_score = std::max(options.confidence.min_score, options.confidence.sequence_min_score);
  judged.confidence.min_global_probability = 0.0;  // fitted to single maps' scores, not a sequence's mean
  // Its hypotheses come from every map's search and are checked through all
  // of them: no one search's votes speak for the places it left out.
  out.stats.unexamined_votes = 0;
  // The newest map's best fit elsewhere in the best hit's map is a rival: in
  // a corridor every map of the sequence may fit as well shifted along it
  // (the odometry moves them together), and only that shift tells.
  Conclude(newest, judged, std::move(hits), OtherPoseRival(newest, options, judged.confidence), with_changes, &out,
           /*prior_place=*/false, SiteMaps{&source, &excluded});
  out.verdict.sequence_maps = earlier.size();
  if (!out.hits.empty()) out.verdict.sequence_agreeing = out.hits[0].sequence_agreeing;
  if (!options.sequence_newest_alone || out.verdict.sure || out.verdict.sequence_agreeing == 0 ||
      StopAsked(options)) {
    return out;
  }
  // Not sure by the sequence, though an earlier map fits where its odometry
  // puts it: the newest map judged alone, as a global answer is (its
  // search's vote lead included), with every pose at which the sequence saw
  // it fit as a possible rival. Where that is sure at the place of the
  // sequence's best hypothesis, the answer is the newest map's: the mean fit
  // of the maps (sequence_min_score) falls short where another earlier map
  // shows a place no stored map shows.
  Localization alone;
  alone.stats = out.stats;
  alone.stats.unexamined_votes = newest_unexamined_votes;
  Conclude(newest, options, NewestFits(std::move(newest_hits), hypotheses, options),
           OtherPoseRival(newest, options, options.confidence), with_changes, &alone, /*prior_place=*/false,
           SiteMaps{&source, &excluded});
  const LocalizedHit& sequence_best = out.hits[0];
  if (!alone.verdict.sure || !alone.hits[0].collection_pose || !sequence_best.collection_pose ||
      !OnePlace(*alone.hits[0].collection_pose, *sequence_best.collection_pose, options.confidence)) {
    out.stats = alone.stats;  // the work done, whichever answer is given
    out.stats.unexamined_votes = 0;
    return out;
  }
  alone.verdict.sequence_maps = out.verdict.sequence_maps;
  alone.verdict.sequence_agreeing = out.verdict.sequence_agreeing;
  alone.verdict.sequence_by_newest = true;
  return alone;
}

}  // namespace lmd
