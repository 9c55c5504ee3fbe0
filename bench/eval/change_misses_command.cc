// lmd-eval change-misses: why the simulated change is not in a query's top
// change mask. In process, with lmdd's defaults: every map of each log is
// stored anchored at its true pose; each map with a place and a simulated
// change is asked, changed, with a tracking robot's prior (lmd-eval served
// --mode tracking's noise; --global: without a prior), maps within 10 m of
// its travel excluded. Each task is put in the first class that holds:
//   top            the first mask hits the change (as lmd-eval served counts);
//   lower          a later mask does;
//   no masks       lmdd computed none: the answer was neither sure nor its
//                  place clear (its place fits and, without a prior, no
//                  disagreeing hit comes within the margin);
//   wrong place    no masks, and the top hit does not show the place;
//   misplaced      a mask hits the change but the pose of the hit it is
//                  credited to puts it elsewhere in that map (MaskFindsChange);
// and otherwise, by what most of the change's points were to the maps of the
// answer's place (those agreeing with its best hit, as change masks use):
//   explained      a map has a point within explained_radius_m of them;
//   unseen         no map saw them as free space;
//   moving         the query's own scans saw through them (seen_through_share);
//   few            none of those, but too few of them were kept to form a mask.
// Before those, "weak": the masks against the same maps without the
// evidence floor (GeometricChangeOptions::min_evidence) hit the change. The
// masks lmdd returned (those of the hits it returns), and those of them that
// do not find the change (false), are counted too, also for changed queries
// whose place no stored map shows (no task).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <unordered_set>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/answer_scoring.h"
#include "bench/eval/commands.h"
#include "bench/eval/eval_dataset.h"
#include "bench/eval/stored_log.h"
#include "core/change/sightings.h"
#include "core/eval/retrieval_metrics.h"
#include "core/localize/prior.h"
#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/pose_noise.h"
#include "core/util/progress_bar.h"

namespace lmd::eval {
namespace {

enum ChangeClass { kTop, kLower, kNoMasks, kWrongPlace, kMisplaced, kWeak, kExplained, kUnseen, kMoving, kFew, kClasses };
const char* const kClassNames[kClasses] = {"top",  "lower",     "no masks", "wrong place", "misplaced",
                                           "weak", "explained", "unseen",   "moving",      "few"};

struct ChangeCounts {
  std::string name;
  size_t tasks = 0, masks = 0, false_masks = 0;
  size_t classes[kClasses] = {};
};

// What most of the change's points were to the maps the answer's masks are
// made against (its place's and, with a site pose, the site maps near it).
ChangeClass WhyNotFound(const LocalQuery& query, const EvalQuery& q, const Localization& answer,
                        const localize_internal::SiteMaps& site, const LocalizeOptions& options) {
  std::vector<std::shared_ptr<const PreparedMap>> kept;
  const std::vector<AlignedMap> maps = localize_internal::WithSiteMaps(
      query, answer.hits[0], localize_internal::PlaceMaps(answer.hits, answer.verdict.best_score, options), site,
      options, &kept);
  const GeometricChangeOptions& change = options.changes;
  GeometricChangeOptions no_floor = change;
  no_floor.min_evidence = 0.0;
  for (const ChangeMask& m : GeometricChanges(q.changed.points, q.changed.trajectory, q.changed.scans, maps, no_floor)) {
    if (MaskHitsChange(m.points, q.changed_points, kMaskHitM)) return kWeak;
  }
  const std::vector<Sightings> sightings = CountSightings(q.changed_points, q.changed.scans);
  size_t explained = 0, unseen = 0, moving = 0;
  for (size_t i = 0; i < q.changed_points.size(); ++i) {
    bool is_explained = false, seen_free = false;
    for (const AlignedMap& m : maps) {
      const Point2 p = TransformPoint(m.pose, q.changed_points[i]);
      is_explained |= NearestPoint(*m.db, p, change.explained_radius_m) >= 0;
      seen_free |= InFreeSpace(*m.db, p);
    }
    const double seen = sightings[i].returns + sightings[i].through;
    if (is_explained) {
      ++explained;
    } else if (!seen_free) {
      ++unseen;
    } else if (seen > 0 && sightings[i].through > change.seen_through_share * seen) {
      ++moving;
    }
  }
  const size_t half = q.changed_points.size() / 2;
  if (explained > half) return kExplained;
  if (unseen > half) return kUnseen;
  if (moving > half) return kMoving;
  return kFew;
}

ChangeCounts CountChanges(const Dataset& d, const LocalizeOptions& options, bool global) {
  ChangeCounts counts;
  counts.name = d.name;
  const std::unique_ptr<StoredLog> stored = StoreLog(d, options, /*anchored=*/true);
  const MemoryCollection& collection = stored->collection;
  ProgressBar bar(d.name + ": changed queries", d.queries.size());
  for (const EvalQuery& q : d.queries) {
    bar.Add();
    if (!q.change_ok || q.changed.points.empty()) continue;
    // A query whose place no stored map shows is no task, but its masks are
    // counted (as lmd-eval served counts them).
    const bool task = !q.places.empty();
    counts.tasks += task;
    const std::unordered_set<size_t> candidates(q.candidates.begin(), q.candidates.end());
    const std::function<bool(uint64_t)> excluded = [&](uint64_t id) { return candidates.count(id) == 0; };
    const LocalQuery query = PrepareLocalQuery(q.changed, options);
    Localization answer;
    if (global) {
      answer = Localize(query, collection, options, excluded, {}, /*with_changes=*/true);
    } else {
      std::mt19937_64 rng(q.map + 1);
      Prior prior;
      prior.pose = PerturbedPose(d.maps[q.map].truth.global_frame, kTrackingPrior, rng);
      prior.radius_m = kTrackingPrior.radius_m;
      prior.heading_sigma_rad = kTrackingPrior.sigma_deg * M_PI / 180;
      answer = LocalizeNear(query, collection, options, prior, excluded, {}, /*with_changes=*/true);
    }
    std::optional<ChangeClass> c;
    bool hits_change = false;
    size_t rank = 0;  // of the masks lmdd would send: those of returned hits
    for (const ChangeMask& m : answer.changes) {
      const auto hit = std::find_if(answer.hits.begin(), answer.hits.end(),
                                    [&](const LocalizedHit& h) { return h.map_id == m.db_map_id; });
      if (hit == answer.hits.end()) continue;
      hits_change |= MaskHitsChange(m.points, q.changed_points, kMaskHitM);
      const bool finds = MaskFindsChange(d, q, m.points, m.db_map_id, hit->pose);
      if (finds && !c) c = rank == 0 ? kTop : kLower;
      ++rank;
      ++counts.masks;
      counts.false_masks += !finds;
    }
    if (!task) continue;
    if (!c) {
      const bool right_place = !answer.hits.empty() && d.ShowsPlace(q, answer.hits[0].map_id);
      if (answer.changes.empty() && !right_place) {
        c = kWrongPlace;
      } else if (hits_change) {
        c = kMisplaced;
      } else if (answer.changes.empty() && !answer.verdict.sure &&
                 !localize_internal::PlaceClear(
                     query, answer.hits, answer.verdict,
                     localize_internal::PlaceMaps(answer.hits, answer.verdict.best_score, options), options, !global)) {
        c = kNoMasks;
      } else {
        c = WhyNotFound(query, q, answer, localize_internal::SiteMaps{&collection, &excluded}, options);
      }
    }
    ++counts.classes[*c];
  }
  bar.Done();
  return counts;
}

void Print(const ChangeCounts& c) {
  std::printf("%-10s %6zu %6.3f %6.1f %%", c.name.c_str(), c.tasks,
              static_cast<double>(c.classes[kTop]) / std::max<size_t>(1, c.tasks),
              100.0 * static_cast<double>(c.false_masks) / std::max<size_t>(1, c.masks));
  for (size_t k = 0; k < kClasses; ++k) std::printf(" %11zu", c.classes[k]);
  std::printf("\n");
}

}  // namespace

int RunChangeMisses(int argc, char** argv) {
  Flags args(WithSensorFlags({"log"}), {"global"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval change-misses: %s\n", args.error().c_str());
    return 2;
  }
  const LocalizeOptions options;
  std::vector<ChangeCounts> all;
  const int read = ForEachServedLog(args, "change-misses", [&](const Dataset& d) {
    all.push_back(CountChanges(d, options, args.Has("global")));
  });
  if (read != 0) return read;
  std::printf("%-10s %6s %6s %8s", "log", "tasks", "top", "false");
  for (const char* name : kClassNames) std::printf(" %11s", name);
  std::printf("\n");
  ChangeCounts total;
  total.name = "all";
  for (const ChangeCounts& c : all) {
    Print(c);
    total.tasks += c.tasks, total.masks += c.masks, total.false_masks += c.false_masks;
    for (size_t k = 0; k < kClasses; ++k) total.classes[k] += c.classes[k];
  }
  Print(total);
  return 0;
}

}  // namespace lmd::eval
