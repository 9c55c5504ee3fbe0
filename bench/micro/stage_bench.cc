// lmd-microbench: CPU cost of each stage of one DetectChanges call as lmdd
// runs it (core/localize: prepare the query, first-stage search, scan
// matching of the chosen maps, the verdict, change masks) and of the whole
// call, and of prior queries, on the demo world's local maps or, with
// LMD_BENCH_LOG=FILE, on a CARMEN log's; and of indexing a stored map's
// place features. Google Benchmark; run
// `build/bench/lmd-microbench` (--benchmark_filter=Search picks a stage).
// Each query is a stored map, localised against the others with the maps
// within 10 m of its travel left out (lmd-eval served's protocol); one
// iteration runs every query once, and `per_query` is the mean time of one.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "core/io/carmen_reader.h"
#include "core/localize/localizer.h"
#include "core/localize/memory_collection.h"
#include "core/localize/prior.h"
#include "core/localmap/local_map_builder.h"
#include "core/place/place_index.h"
#include "core/sim/pose_noise.h"
#include "core/sim/simulate.h"

namespace lmd {
namespace {

constexpr size_t kQueries = 40;         // every (maps / kQueries)-th map is a query
constexpr double kExcludedTravelM = 10.0;  // m of travel around a query whose maps are left out

std::vector<LocalMap> BenchMaps() {
  const char* log_path = std::getenv("LMD_BENCH_LOG");
  if (log_path == nullptr) return SimulateLocalMaps(DefaultDemoOptions());
  Result<LaserLog> log = ReadCarmenLog(log_path);
  if (!log.ok()) {
    std::fprintf(stderr, "lmd-microbench: %s\n", log.status().message().c_str());
    std::exit(2);
  }
  return BuildLocalMaps(*log);
}

// The maps prepared and stored once, as lmdd stores them: anchored at their
// true poses (as maps inserted with a pose_hint) with their trajectories.
struct World {
  LocalizeOptions options;
  std::vector<LocalMap> maps;
  std::vector<PreparedPlace> places;
  MemoryCollection collection;
  std::vector<size_t> queries;

  World() {
    maps = BenchMaps();
    for (size_t i = 0; i < maps.size(); ++i) {
      places.push_back(PreparePlace(maps[i], options));
      (void)collection.Add(i, places.back(), MapSource::Route{1, i + 1}, maps[i].trajectory);
      (void)collection.SetAnchor(i, maps[i].truth.global_frame);
    }
    for (size_t i = 0; i < maps.size(); i += std::max<size_t>(1, maps.size() / kQueries)) {
      if (!maps[i].points.empty()) queries.push_back(i);  // as lmd-eval served, which never asks an empty map
    }
  }
  std::function<bool(uint64_t)> Excluding(size_t q) const {
    return [this, q](uint64_t id) {
      return std::abs(maps[id].truth.travel_start - maps[q].truth.travel_start) <= kExcludedTravelM;
    };
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

// Indexing every stored map's place features in a fresh index, as lmdd
// does at each insert (the index's own allocation not timed).
void BM_IndexPlaceFeatures(benchmark::State& state) {
  const World& w = TheWorld();
  for (auto _ : state) {
    state.PauseTiming();
    auto index = std::make_unique<PlaceIndex>();
    state.ResumeTiming();
    for (size_t i = 0; i < w.places.size(); ++i) benchmark::DoNotOptimize(index->Add(i, w.places[i].features));
    state.PauseTiming();
    index.reset();
    state.ResumeTiming();
  }
  state.counters["per_map"] = PerQuery(w.places.size());
}
BENCHMARK(BM_IndexPlaceFeatures)->Unit(benchmark::kMillisecond);

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

// Prior queries as lmd-eval served sends them: --mode prior (the true pose
// off by 1-3 m and 10-20 deg, radius 3.5 m, sigma 20 deg) and --mode
// tracking (0-0.3 m, 0-2 deg; 0.4 m, 3 deg: a tight prior), seeded per query.
void RunLocalizeNear(benchmark::State& state, const PoseNoise& noise) {
  const World& w = TheWorld();
  std::vector<LocalQuery> queries;
  std::vector<Prior> priors;
  for (size_t q : w.queries) {
    queries.push_back(PrepareLocalQuery(w.maps[q], w.options, &w.places[q]));
    std::mt19937_64 rng(q + 1);
    Prior prior;
    prior.pose = PerturbedPose(w.maps[q].truth.global_frame, noise, rng);
    prior.radius_m = noise.radius_m;
    prior.heading_sigma_rad = noise.sigma_deg * M_PI / 180.0;
    priors.push_back(prior);
  }
  // right: the site pose within 0.2 m and 1 deg of the truth.
  double search = 0, verify = 0, verdict = 0, matched = 0, right = 0, sure = 0, sure_wrong = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < queries.size(); ++i) {
      const Localization l = LocalizeNear(queries[i], w.collection, w.options, priors[i], w.Excluding(w.queries[i]));
      search += l.stats.search_ms, verify += l.stats.verify_ms, verdict += l.stats.verdict_ms;
      matched += static_cast<double>(l.stats.maps_matched);
      const Pose2 truth = w.maps[w.queries[i]].truth.global_frame;
      const std::optional<Pose2>& p = l.verdict.collection_pose;
      const bool is_right = p && std::hypot(p->x - truth.x, p->y - truth.y) <= 0.2 &&
                            std::abs(std::remainder(p->theta - truth.theta, 2 * M_PI)) <= M_PI / 180;
      right += is_right, sure += l.verdict.sure, sure_wrong += l.verdict.sure && !is_right;
    }
  }
  state.counters["per_query"] = PerQuery(queries.size());
  const double n = static_cast<double>(queries.size());
  for (const auto& [name, value] : {std::pair<const char*, double>{"search_ms", search}, {"verify_ms", verify},
                                    {"verdict_ms", verdict}, {"maps_matched", matched}, {"right", right},
                                    {"sure", sure}, {"sure_wrong", sure_wrong}}) {
    state.counters[name] = benchmark::Counter(value / n, benchmark::Counter::kAvgIterations);
  }
}
void BM_LocalizeNear(benchmark::State& state) { RunLocalizeNear(state, kRoughPrior); }
void BM_LocalizeNearTracking(benchmark::State& state) { RunLocalizeNear(state, kTrackingPrior); }
BENCHMARK(BM_LocalizeNear)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LocalizeNearTracking)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lmd

BENCHMARK_MAIN();
