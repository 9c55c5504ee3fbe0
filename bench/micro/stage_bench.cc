// lmd-microbench: CPU cost of each stage of one DetectChanges call as lmdd
// runs it (core/localize: prepare the query, first-stage search, scan
// matching of the chosen maps, the verdict, change masks) and of the whole
// call, on the demo world's local maps. Google Benchmark; run
// `build/bench/lmd-microbench` (--benchmark_filter=Search picks a stage).
// Each query is a demo map, localised against all other demo maps; one
// iteration runs every query once, and `per_query` is the mean time of one.
#include <algorithm>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "core/localize/localizer.h"
#include "core/localize/memory_collection.h"
#include "core/sim/simulate.h"

namespace lmd {
namespace {

constexpr size_t kQueries = 40;  // every (maps / kQueries)-th demo map is a query

// The demo world prepared and stored once, as lmdd stores it.
struct World {
  LocalizeOptions options;
  std::vector<LocalMap> maps;
  std::vector<PreparedPlace> places;
  MemoryCollection collection;
  std::vector<size_t> queries;

  World() {
    maps = SimulateLocalMaps(DefaultDemoOptions());
    for (size_t i = 0; i < maps.size(); ++i) {
      places.push_back(PreparePlace(maps[i], options));
      (void)collection.Add(i, places.back(), MapSource::Route{1, i + 1});
    }
    for (size_t i = 0; i < maps.size(); i += std::max<size_t>(1, maps.size() / kQueries)) queries.push_back(i);
  }
  // The query's own map is left out (lmdd's query is not yet stored).
  std::function<bool(uint64_t)> Excluding(size_t q) const {
    return [q](uint64_t id) { return id == q; };
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

// A query map as lmdd receives it: prepared for scan matching (free space
// ray-cast) and described (place features). lmdd does this once per map:
// the insert and the query of one robot tick share it.
void BM_PrepareQuery(benchmark::State& state) {
  const World& w = TheWorld();
  for (auto _ : state) {
    for (size_t q : w.queries) benchmark::DoNotOptimize(PrepareLocalQuery(w.maps[q], w.options));
  }
  state.counters["per_query"] = PerQuery(w.queries.size());
}
BENCHMARK(BM_PrepareQuery)->Unit(benchmark::kMillisecond);

void BM_Search(benchmark::State& state) {
  const World& w = TheWorld();
  std::vector<LocalQuery> queries;
  for (size_t q : w.queries) queries.push_back(PrepareLocalQuery(w.maps[q], w.options, &w.places[q]));
  PlaceSearchStats stats, total;
  for (auto _ : state) {
    for (size_t i = 0; i < queries.size(); ++i) {
      benchmark::DoNotOptimize(w.collection.Search(queries[i].features, w.options.search, w.Excluding(w.queries[i]), &stats));
      total.candidates += stats.candidates;
    }
  }
  state.counters["per_query"] = PerQuery(queries.size());
  state.counters["features_compared"] =
      benchmark::Counter(static_cast<double>(total.candidates) / queries.size(), benchmark::Counter::kAvgIterations);
  state.counters["maps"] = static_cast<double>(w.maps.size());
}
BENCHMARK(BM_Search)->Unit(benchmark::kMillisecond);

// The whole default-method query (first stage, scan matching, verdict), with
// and without change masks, the query prepared already.
void RunLocalize(benchmark::State& state, bool with_changes) {
  const World& w = TheWorld();
  std::vector<LocalQuery> queries;
  for (size_t q : w.queries) queries.push_back(PrepareLocalQuery(w.maps[q], w.options, &w.places[q]));
  double search = 0, verify = 0, verdict = 0, changes = 0, matched = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < queries.size(); ++i) {
      const Localization l = Localize(queries[i], w.collection, w.options, w.Excluding(w.queries[i]), {}, with_changes);
      search += l.stats.search_ms, verify += l.stats.verify_ms, verdict += l.stats.verdict_ms;
      changes += l.stats.changes_ms, matched += static_cast<double>(l.stats.maps_matched);
    }
  }
  state.counters["per_query"] = PerQuery(queries.size());
  const double n = static_cast<double>(queries.size());
  for (const auto& [name, value] : {std::pair<const char*, double>{"search_ms", search}, {"verify_ms", verify},
                                    {"verdict_ms", verdict}, {"changes_ms", changes}, {"maps_matched", matched}}) {
    state.counters[name] = benchmark::Counter(value / n, benchmark::Counter::kAvgIterations);
  }
}
void BM_Localize(benchmark::State& state) { RunLocalize(state, false); }
void BM_LocalizeWithChanges(benchmark::State& state) { RunLocalize(state, true); }
BENCHMARK(BM_Localize)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LocalizeWithChanges)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lmd

BENCHMARK_MAIN();
