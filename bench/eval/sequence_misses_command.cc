// lmd-eval sequence-misses: why sequence queries miss the place. In process,
// with lmdd's defaults (core/localize/sequence.h): every map of each log is
// stored, anchored at its true pose with its trajectory; each map whose
// place is stored is asked with its two earlier maps and drifting odometry
// to them, the maps around all three left out, as lmd-eval served --mode
// sequence asks it (sequence_context.h, the same seed). A miss is a top hit
// that does not show the place. Each is checked at the truth: every map of
// the sequence localised where the newest map's true pose puts it
// (CheckSequenceAt, as lmdd checks a hypothesis), and put in one class:
//   not proposed     the sequence fits better at the truth than the answer's
//                    score: no map's own search proposed the true pose (or
//                    it was not among the sequence_hypotheses best);
//   context unseen   the truth fits no better, and no earlier map fits there
//                    (score < confidence.min_score): what the robot saw
//                    before is not stored, so only the newest map speaks for
//                    the truth, while a look-alike's context may fit a little;
//   truth loses      the truth fits no better though its context fits.
// --list prints each miss with every map's score at the truth and at the
// answer's pose.
#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <unordered_set>
#include <vector>

#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/eval_dataset.h"
#include "bench/eval/sequence_context.h"
#include "bench/eval/stored_log.h"
#include "core/localize/sequence.h"
#include "core/util/progress_bar.h"

namespace lmd::eval {
namespace {

constexpr uint64_t kSeed = 1;              // lmd-eval served's default --seed

enum MissClass { kNotProposed, kContextUnseen, kTruthLoses, kClasses };
const std::vector<const char*> kClassNames = {"not proposed", "context unseen", "truth loses"};

double Mean(const SequenceCheck& check) {
  double total = 0.0;
  for (const LocalizedHit& h : check.best) total += h.db ? h.score : 0.0;
  return check.best.empty() ? 0.0 : total / static_cast<double>(check.best.size());
}

std::string Scores(const SequenceCheck& check) {
  std::string s;
  for (const LocalizedHit& h : check.best) s += " " + std::to_string(h.db ? h.score : 0.0).substr(0, 4);
  return s;
}

MissCounts CountMisses(const Dataset& d, const LocalizeOptions& options, size_t every, bool list) {
  MissCounts counts;
  counts.name = d.name;
  counts.by_class.assign(kClasses, 0);
  const std::unique_ptr<StoredLog> stored = StoreLog(d, options, /*anchored=*/true);
  const SequenceShape shape;
  std::vector<const EvalQuery*> query_of_map(d.maps.size(), nullptr);
  for (const EvalQuery& q : d.queries) query_of_map[q.map] = &q;
  ProgressBar bar(d.name + ": sequence queries", d.queries.size());
  for (size_t k = 0; k < d.queries.size(); ++k) {
    bar.Add();
    if (k % every != 0) continue;
    const EvalQuery q = WithoutSequenceNeighbours(d, d.queries[k], shape);
    if (q.places.empty() || d.maps[q.map].points.empty()) continue;
    ++counts.asked;
    const std::unordered_set<size_t> candidates(q.candidates.begin(), q.candidates.end());
    auto excluded = [&](uint64_t id) { return candidates.count(id) == 0; };
    std::mt19937_64 rng(kSeed ^ (0x9E3779B97F4A7C15ULL * (q.map + 1)));  // as lmd-eval served draws it
    std::vector<SequenceStep> steps;
    std::string places_stored = " " + std::to_string(q.places.size());  // each map's, for --list
    for (const EarlierMap& e : EarlierMaps(d, q, shape, &rng)) {
      steps.push_back({PrepareLocalQuery(d.maps[e.map], options, &stored->places[e.map]), e.in_newest, e.travel_m});
      const EvalQuery* own = query_of_map[e.map];
      const auto stored_places = own == nullptr ? 0 : std::count_if(own->places.begin(), own->places.end(), [&](size_t j) {
        return candidates.count(j) > 0;
      });
      places_stored += " " + std::to_string(stored_places);
    }
    const LocalQuery newest = PrepareLocalQuery(d.maps[q.map], options, &stored->places[q.map]);
    const Localization answer = LocalizeSequence(newest, steps, stored->collection, options, excluded);
    counts.matched += answer.stats.maps_matched;
    if (!answer.hits.empty() && d.ShowsPlace(q, answer.hits[0].map_id)) continue;
    ++counts.missed;
    const SequenceCheck at_truth =
        CheckSequenceAt(newest, steps, stored->collection, options, d.maps[q.map].truth.global_frame, excluded);
    const double top = answer.hits.empty() ? 0.0 : answer.hits[0].score;
    bool context_fits = false;
    for (size_t s = 1; s < at_truth.best.size(); ++s) {
      context_fits |= at_truth.best[s].db && at_truth.best[s].score >= options.confidence.min_score;
    }
    const MissClass c = Mean(at_truth) > top ? kNotProposed : context_fits ? kTruthLoses : kContextUnseen;
    ++counts.by_class[c];
    if (!list) continue;
    std::string at_answer = " (no hit)";
    if (!answer.hits.empty() && answer.hits[0].collection_pose) {
      at_answer = Scores(CheckSequenceAt(newest, steps, stored->collection, options,
                                         *answer.hits[0].collection_pose, excluded));
    }
    std::fprintf(stderr,
                 "%s map %zu: %s; answer %.2f (%s); maps of each map's place stored:%s; its fit at the truth:%s; "
                 "at the answer:%s\n",
                 d.name.c_str(), q.map, kClassNames[c], top, answer.verdict.sure ? "sure" : "unsure",
                 places_stored.c_str(), Scores(at_truth).c_str(), at_answer.c_str());
  }
  bar.Done();
  return counts;
}

}  // namespace

int RunSequenceMisses(int argc, char** argv) {
  Flags args(WithSensorFlags({"log", "every"}), {"list"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval sequence-misses: %s\n", args.error().c_str());
    return 2;
  }
  size_t every = 0;
  if (!ParseEvery(args, "sequence-misses", &every)) return 2;
  const LocalizeOptions options;  // lmdd's defaults
  std::vector<MissCounts> all;
  const int read = ForEachServedLog(args, "sequence-misses", [&](const Dataset& d) {
    all.push_back(CountMisses(d, options, every, args.Has("list")));
  });
  if (read != 0) return read;
  PrintMissTable(all, kClassNames);
  return 0;
}

}  // namespace lmd::eval
