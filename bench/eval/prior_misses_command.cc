// lmd-eval prior-misses: why loose prior queries miss the place. In process,
// with lmdd's defaults (core/localize/prior.h; --one-pose: without
// LocalizeOptions::prior_second_pose; --no-site: without
// LocalizeOptions::prior_site_maps): every map of each log is
// stored, anchored at its true pose with its trajectory; each map with a
// place (a stored map outside its 10 m of travel shows it) is asked with
// its true pose off by 1-3 m and 10-20 deg (lmd-eval served --mode prior's
// noise, seeded by the map's index; --tracking: --mode tracking's). A miss
// is a top hit that does not show the place. For each miss, every stored
// map that shows the place is scan matched where the prior puts it (the
// window lmdd searches) and the miss is put in one of three classes:
//   not verified  one of them matches within 0.5 m of the truth and scores
//                 at least the answer's top hit: lmdd did not pick it to verify;
//   out-scored    one matches near the truth, but below the answer's top hit
//                 (a map that does not show the place, or one at a wrong pose,
//                 fits the query better);
//   shifted       every one of them matches more than 0.5 m from the truth:
//                 within the prior's window the search prefers another pose
//                 (a corridor's shift, or the logs' corrected poses); split
//                 by whether one of them scores higher at the truth than
//                 where it matched (then a search that kept more poses could
//                 find it) or none does (the query cannot tell them apart).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <unordered_set>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/eval_dataset.h"
#include "bench/eval/stored_log.h"
#include "core/localize/prior.h"
#include "core/localize/verification.h"
#include "core/sim/pose_noise.h"
#include "core/util/progress_bar.h"

namespace lmd::eval {
namespace {

constexpr double kNearTruthM = 0.5;

struct PriorMissCounts {
  std::string name;
  size_t asked = 0, missed = 0, not_verified = 0, out_scored = 0, shifted = 0, shifted_truth_better = 0;
};

PriorMissCounts CountMisses(const Dataset& d, const LocalizeOptions& options, const PoseNoise& noise) {
  PriorMissCounts counts;
  counts.name = d.name;
  const std::unique_ptr<StoredLog> stored = StoreLog(d, options, /*anchored=*/true);
  const MemoryCollection& collection = stored->collection;
  ProgressBar bar(d.name + ": prior queries", d.queries.size());
  for (const EvalQuery& q : d.queries) {
    bar.Add();
    if (q.places.empty() || d.maps[q.map].points.empty()) continue;
    ++counts.asked;
    const std::unordered_set<size_t> candidates(q.candidates.begin(), q.candidates.end());
    auto excluded = [&](uint64_t id) { return candidates.count(id) == 0; };
    const LocalQuery query = PrepareLocalQuery(d.maps[q.map], options, &stored->places[q.map]);
    std::mt19937_64 rng(q.map + 1);
    Prior prior;
    prior.pose = PerturbedPose(d.maps[q.map].truth.global_frame, noise, rng);
    prior.radius_m = noise.radius_m;
    prior.heading_sigma_rad = noise.sigma_deg * M_PI / 180;
    const Localization answer = LocalizeNear(query, collection, options, prior, excluded);
    if (!answer.hits.empty() && d.ShowsPlace(q, answer.hits[0].map_id)) continue;
    ++counts.missed;
    const double top = answer.hits.empty() ? 0.0 : answer.hits[0].score;
    double best_near_truth = -1.0;  // the best score of a place map matched near the truth
    bool truth_better = false;      // a place map scores higher at the truth than where it matched
    for (size_t j : q.places) {
      const PreparedMap& db = *collection.Prepared(j);
      ScanMatchOptions match = PriorWindow(prior, options);
      const Pose2 guess =
          PriorGuess(query, db, d.maps[j].truth.global_frame, prior, match.window_deg, &match.window_deg);
      const LocalizedHit hit =
          localize_internal::Scored(query, db, MatchLocalMaps(query.match, db, {guess}, match), options);
      const Pose2 truth = d.TruePose(q.map, j);
      if (std::hypot(hit.pose.x - truth.x, hit.pose.y - truth.y) <= kNearTruthM) {
        best_near_truth = std::max(best_near_truth, hit.score);
      } else {
        truth_better |= localize_internal::ScoredAt(query, db, truth, options).score > hit.score;
      }
    }
    if (best_near_truth < 0) {
      ++counts.shifted;
      counts.shifted_truth_better += truth_better;
    } else if (best_near_truth >= top) {
      ++counts.not_verified;
    } else {
      ++counts.out_scored;
    }
  }
  bar.Done();
  return counts;
}

void Print(const PriorMissCounts& c) {
  std::printf("%-12s %6zu %6zu %8.3f %13zu %11zu %8zu %21zu\n", c.name.c_str(), c.asked, c.missed,
              1.0 - static_cast<double>(c.missed) / std::max<size_t>(1, c.asked), c.not_verified, c.out_scored,
              c.shifted, c.shifted_truth_better);
}

}  // namespace

int RunPriorMisses(int argc, char** argv) {
  Flags args(WithSensorFlags({"log"}), {"one-pose", "no-site", "tracking"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval prior-misses: %s\n", args.error().c_str());
    return 2;
  }
  LocalizeOptions options;
  options.prior_second_pose = !args.Has("one-pose");  // the ablation: each map's first pose only
  if (args.Has("no-site")) options.prior_site_maps = 0;  // the ablation: without the site grid
  std::vector<PriorMissCounts> all;
  const int read = ForEachServedLog(args, "prior-misses", [&](const Dataset& d) {
    all.push_back(CountMisses(d, options, args.Has("tracking") ? kTrackingPrior : kRoughPrior));
  });
  if (read != 0) return read;
  std::printf("%-12s %6s %6s %8s %13s %11s %8s %21s\n", "log", "asked", "missed", "place@1", "not verified",
              "out-scored", "shifted", "(truth scores higher)");
  PriorMissCounts total;
  total.name = "all";
  for (const PriorMissCounts& c : all) {
    Print(c);
    total.asked += c.asked, total.missed += c.missed, total.not_verified += c.not_verified;
    total.out_scored += c.out_scored, total.shifted += c.shifted, total.shifted_truth_better += c.shifted_truth_better;
  }
  Print(total);
  return 0;
}

}  // namespace lmd::eval
