// lmd-microbench: CPU cost of each stage of one DetectChanges call as lmdd
// runs it (describe, retrieve, prepare a db map, verify the top hits, change
// detection), on the demo world's local maps. Google Benchmark; run
// `build/bench/lmd-microbench` (add --benchmark_filter=Verify to pick stages).
// Each query is a demo map, searched in an index of all other demo maps; one
// iteration runs every query once, and `per_query` is the mean time of one.
#include <algorithm>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "core/align/prepared_map.h"
#include "core/align/relative_pose.h"
#include "core/align/scan_match.h"
#include "core/align/verify_hits.h"
#include "core/change/change_detector.h"
#include "core/describe/describer.h"
#include "core/index/index.h"
#include "core/sim/simulate.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd {
namespace {

constexpr size_t kQueries = 40;        // every (maps / kQueries)-th demo map is a query
constexpr size_t kVerified = 10;       // lmdd's verify_candidates default
constexpr double kMaxOffsetM = 3.0;    // lmdd's default_max_offset_m

// The demo world described, indexed and prepared once, as lmdd stores it.
struct World {
  std::vector<LocalMap> maps;
  std::vector<Lmd> lmds;
  std::vector<std::shared_ptr<const PreparedMap>> prepared;
  Index index = std::move(Index::Create()).value();
  std::vector<size_t> queries;

  World() {
    maps = SimulateLocalMaps(DefaultDemoOptions());
    for (size_t i = 0; i < maps.size(); ++i) {
      lmds.push_back(Describe(maps[i], PlanViewpoint(maps[i]), ProductDescriberOptions()));
      prepared.push_back(std::make_shared<const PreparedMap>(PrepareMap(maps[i], {}, lmds[i].frame.heading)));
    }
    for (size_t i = 0; i < maps.size(); i += std::max<size_t>(1, maps.size() / kQueries)) queries.push_back(i);
    for (size_t i = 0; i < maps.size(); ++i) (void)index.Add(i, lmds[i]);
  }

  // The query's top hits, itself excluded (lmdd's query is not yet stored).
  std::vector<MapHit> Hits(size_t q, RetrieveStats* total = nullptr) const {
    RetrieveOptions options;
    options.top_k = kVerified + 1;
    options.max_offset_m = kMaxOffsetM;
    RetrieveStats stats;
    std::vector<MapHit> hits = std::move(index.Retrieve(lmds[q], options, &stats)).value();
    if (total) total->maps_scored += stats.maps_scored;
    hits.erase(std::remove_if(hits.begin(), hits.end(), [&](const MapHit& h) { return h.map_id == q; }),
               hits.end());
    hits.resize(std::min(hits.size(), kVerified));
    return hits;
  }

  std::vector<HitCandidate> Candidates(size_t q, const std::vector<MapHit>& hits) const {
    std::vector<HitCandidate> out;
    for (const MapHit& h : hits) {
      HitCandidate c;
      c.map_id = h.map_id;
      c.db = prepared[h.map_id];
      c.retrieval_score = h.score;
      c.guesses = {RelativePose(lmds[q].frame, lmds[h.map_id].frame, h.orientation, h.offset)};
      out.push_back(std::move(c));
    }
    return out;
  }
};

const World& TheWorld() {
  static const World* world = new World();  // built once, never torn down
  return *world;
}

// Seconds per query, for an iteration that runs `queries` queries.
benchmark::Counter PerQuery(size_t queries) {
  return benchmark::Counter(static_cast<double>(queries),
                            benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

VerifyOptions LmddVerifyOptions() {
  VerifyOptions options;
  options.match.quarter_turns = false;  // as lmdd (hit_verifier.cc)
  return options;
}

void BM_PlanAndDescribe(benchmark::State& state) {
  const World& w = TheWorld();
  for (auto _ : state) {
    for (size_t q : w.queries) {
      benchmark::DoNotOptimize(Describe(w.maps[q], PlanViewpoint(w.maps[q]), ProductDescriberOptions()));
    }
  }
  state.counters["per_query"] = PerQuery(w.queries.size());
}
BENCHMARK(BM_PlanAndDescribe)->Unit(benchmark::kMillisecond);

void BM_Retrieve(benchmark::State& state) {
  const World& w = TheWorld();
  RetrieveStats stats;
  for (auto _ : state) {
    for (size_t q : w.queries) benchmark::DoNotOptimize(w.Hits(q, &stats));
  }
  state.counters["per_query"] = PerQuery(w.queries.size());
  // Maps scored exactly per query, of the maps in the index.
  state.counters["maps_scored"] = benchmark::Counter(static_cast<double>(stats.maps_scored) / w.queries.size(),
                                                     benchmark::Counter::kAvgIterations);
  state.counters["maps"] = static_cast<double>(w.maps.size());
}
BENCHMARK(BM_Retrieve)->Unit(benchmark::kMillisecond);

void BM_PrepareMap(benchmark::State& state) {
  const World& w = TheWorld();
  for (auto _ : state) {
    for (size_t q : w.queries) benchmark::DoNotOptimize(PrepareMap(w.maps[q], {}, w.lmds[q].frame.heading));
  }
  state.counters["per_query"] = PerQuery(w.queries.size());
}
BENCHMARK(BM_PrepareMap)->Unit(benchmark::kMillisecond);

// lmdd's verification of one query: its top hits, db maps already prepared.
void BM_VerifyTopHits(benchmark::State& state) {
  const World& w = TheWorld();
  const VerifyOptions options = LmddVerifyOptions();
  std::vector<PreparedQuery> queries;
  std::vector<std::vector<HitCandidate>> candidates;
  for (size_t q : w.queries) {
    queries.push_back(PrepareQuery(w.maps[q], options.match, w.lmds[q].frame.heading));
    candidates.push_back(w.Candidates(q, w.Hits(q)));
  }
  size_t low = 0, verified = 0, evaluations = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < queries.size(); ++i) {
      const std::vector<VerifiedHit> hits = VerifyHits(queries[i], candidates[i], options);
      for (const VerifiedHit& h : hits) {
        low += h.verified && h.score < options.global_below_score;
        evaluations += h.match.search_evaluations;
      }
      verified += hits.size();
    }
  }
  state.counters["per_query"] = PerQuery(queries.size());
  // Share of verified hits scoring below global_below_score (the guess-free
  // search ran for them when no other hit of the query matched).
  state.counters["low_score_share"] = verified ? static_cast<double>(low) / verified : 0.0;
  // Correlative block scores per verified hit (the search's cost).
  state.counters["evaluations"] = verified ? static_cast<double>(evaluations) / verified : 0.0;
  size_t points = 0;
  for (const PreparedQuery& q : queries) points += q.search_points.size();
  state.counters["search_points"] = static_cast<double>(points) / queries.size();
}
BENCHMARK(BM_VerifyTopHits)->Unit(benchmark::kMillisecond);

// The guess-free search alone, against each query's first hit.
void BM_MatchGlobal(benchmark::State& state) {
  const World& w = TheWorld();
  const ScanMatchOptions options = LmddVerifyOptions().match;
  std::vector<PreparedQuery> queries;
  std::vector<size_t> dbs;
  for (size_t q : w.queries) {
    queries.push_back(PrepareQuery(w.maps[q], options, w.lmds[q].frame.heading));
    dbs.push_back(w.Hits(q).front().map_id);
  }
  for (auto _ : state) {
    for (size_t i = 0; i < queries.size(); ++i) {
      benchmark::DoNotOptimize(MatchLocalMapsGlobal(queries[i], *w.prepared[dbs[i]], options));
    }
  }
  state.counters["per_query"] = PerQuery(queries.size());
}
BENCHMARK(BM_MatchGlobal)->Unit(benchmark::kMillisecond);

void BM_DetectChanges(benchmark::State& state) {
  const World& w = TheWorld();
  std::vector<std::vector<ChangeCandidate>> candidates;
  for (size_t q : w.queries) {
    candidates.emplace_back();
    for (const MapHit& h : w.Hits(q)) candidates.back().push_back({h, &w.lmds[h.map_id]});
  }
  for (auto _ : state) {
    for (size_t i = 0; i < candidates.size(); ++i) {
      benchmark::DoNotOptimize(DetectChanges(w.lmds[w.queries[i]], candidates[i]));
    }
  }
  state.counters["per_query"] = PerQuery(candidates.size());
}
BENCHMARK(BM_DetectChanges)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lmd

BENCHMARK_MAIN();
