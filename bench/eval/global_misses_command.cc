// lmd-eval global-misses: why global queries (no prior) miss the place. In
// process, with lmdd's defaults: every map of each log is stored (--anchored:
// anchored at its true pose, a site map) and each map with a place (a stored
// map outside its 10 m of travel shows it) is queried with the maps within
// 10 m of its travel excluded, as lmd-eval served does. A miss is a top hit
// that does not show the place; each is put in the first class that holds:
//   truth loses      no map of the place scores higher at its true pose than
//                    the top hit: the query cannot tell the look-alike (or it
//                    shows too little of the place) by one map's fit;
//   verified near    a map of the place was verified with a guess within 1 m
//                    and 10 deg of its true pose, yet its search did not win;
//   unverified near  a map of the place had such a hypothesis but was not
//                    verified (passed over for a route neighbour, or beyond
//                    verify_maps);
//   guesses far      maps of the place were verified, none with a guess near
//                    its true pose (the votes named another stretch);
//   unverified       maps of the place among the first stage's hypotheses,
//                    none verified;
//   no hypothesis    no map of the place among them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <unordered_set>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/eval_dataset.h"
#include "bench/eval/stored_log.h"
#include "core/localize/verification.h"
#include "core/util/progress_bar.h"

namespace lmd::eval {
namespace {

using localize_internal::Candidate;

enum MissClass { kTruthLoses, kVerifiedNear, kUnverifiedNear, kGuessesFar, kUnverified, kNoHypothesis, kClasses };
const std::vector<const char*> kClassNames = {"truth loses", "verified near", "unverified near",
                                               "guesses far", "unverified",  "no hypothesis"};

// A guess within 1 m and 10 deg of the truth: the +-1 m search around it
// covers the true pose, up to the compass's error.
bool NearTruth(const Pose2& guess, const Pose2& truth) {
  return std::hypot(guess.x - truth.x, guess.y - truth.y) <= 1.0 &&
         std::abs(std::remainder(guess.theta - truth.theta, 2 * M_PI)) <= 10 * M_PI / 180;
}

MissClass Classify(const Dataset& d, const EvalQuery& q, const LocalQuery& query, const MapSource& source,
                   const std::vector<PlaceHypothesis>& hypotheses, const std::vector<Candidate>& verified,
                   double top, const LocalizeOptions& options) {
  bool truth_wins = false;
  for (size_t j : q.places) {
    truth_wins |= localize_internal::ScoredAt(query, *source.Prepared(j), d.TruePose(q.map, j), options).score > top;
  }
  if (!truth_wins) return kTruthLoses;
  const std::unordered_set<size_t> places(q.places.begin(), q.places.end());
  std::unordered_set<uint64_t> verified_ids;
  bool place_verified = false;
  for (const Candidate& c : verified) {
    verified_ids.insert(c.map_id);
    if (places.count(c.map_id) == 0) continue;
    place_verified = true;
    for (const Pose2& g : c.guesses) {
      if (NearTruth(g, d.TruePose(q.map, c.map_id))) return kVerifiedNear;
    }
  }
  bool place_hypothesis = false;
  for (const PlaceHypothesis& h : hypotheses) {
    if (places.count(h.map_id) == 0) continue;
    place_hypothesis = true;
    if (verified_ids.count(h.map_id) == 0 &&
        NearTruth(HypothesisPose(h, query.map->heading), d.TruePose(q.map, h.map_id))) {
      return kUnverifiedNear;
    }
  }
  if (place_verified) return kGuessesFar;
  return place_hypothesis ? kUnverified : kNoHypothesis;
}

MissCounts CountMisses(const Dataset& d, const LocalizeOptions& options, bool anchored, size_t every) {
  MissCounts counts;
  counts.name = d.name;
  counts.by_class.assign(kClasses, 0);
  const std::unique_ptr<StoredLog> stored = StoreLog(d, options, anchored);
  const MemoryCollection& collection = stored->collection;
  ProgressBar bar(d.name + ": global queries", d.queries.size());
  for (size_t k = 0; k < d.queries.size(); ++k) {
    bar.Add();
    const EvalQuery& q = d.queries[k];
    if (k % every != 0 || q.places.empty() || d.maps[q.map].points.empty()) continue;
    ++counts.asked;
    const std::unordered_set<size_t> candidates(q.candidates.begin(), q.candidates.end());
    auto excluded = [&](uint64_t id) { return candidates.count(id) == 0; };
    const LocalQuery query = PrepareLocalQuery(d.maps[q.map], options, &stored->places[q.map]);
    LocalizeStats stats;
    localize_internal::SearchTrace trace;
    const std::vector<LocalizedHit> hits =
        localize_internal::SearchAndVerify(query, collection, options, excluded, &stats, &trace);
    counts.matched += stats.maps_matched;
    if (!hits.empty() && d.ShowsPlace(q, hits[0].map_id)) continue;
    ++counts.missed;
    ++counts.by_class[Classify(d, q, query, collection, trace.hypotheses, trace.verified,
                               hits.empty() ? 0.0 : hits[0].score, options)];
  }
  bar.Done();
  return counts;
}

}  // namespace

int RunGlobalMisses(int argc, char** argv) {
  Flags args(WithSensorFlags({"log", "every"}), {"anchored"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval global-misses: %s\n", args.error().c_str());
    return 2;
  }
  size_t every = 0;
  if (!ParseEvery(args, "global-misses", &every)) return 2;
  const LocalizeOptions options;  // lmdd's defaults
  std::vector<MissCounts> all;
  const int read = ForEachServedLog(args, "global-misses", [&](const Dataset& d) {
    all.push_back(CountMisses(d, options, args.Has("anchored"), every));
  });
  if (read != 0) return read;
  PrintMissTable(all, kClassNames);
  return 0;
}

}  // namespace lmd::eval
