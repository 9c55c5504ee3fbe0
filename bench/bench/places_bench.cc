// lmd-bench places --maps N [--queries Q] [--seed S] [--threads T] [--json] [--cache-mb M]
//                  [--check-every K] [--csv FILE] [--max-bucket B] [--max-candidates C]
//
// Protocol:
//   1. Build. The simulator streams N local maps of the built-in world
//      (core/sim/simulate.h, building by building). Each map is taken as
//      lmdd takes an inserted map (points as float32, the wire format, then
//      MethodView's deduplication) and keeps only what lmdd keeps: its place
//      features (DescribePlace on its points at the entropy compass heading,
//      equal to PreparePlace(map).features: checked on every K-th map),
//      added to one PlaceIndex, and the map itself in a compact form
//      (float32 points, scan poses and float32 ranges: what lmdd's store
//      holds on disk) from which it is prepared again when a query needs it.
//      Maps are numbered 0..N-1 in route order (id = number, one robot,
//      sequence = number).
//   2. Queries. Q stored maps at evenly spaced numbers are observed again
//      (own frame moved by a random rigid motion, 2 cm point and range
//      noise, 10 % of the points dropped), taken as lmdd takes a query, run
//      through PrepareLocalQuery and Localize with default LocalizeOptions
//      against a MapSource that answers Search from the PlaceIndex and
//      Prepared() from lmdd's PreparedMapCache of M MiB (empty at the
//      start, as lmdd's after a restart), preparing a missing map on demand
//      as lmdd does (PrepareMap with free space, heading from the stored
//      features; a map the fit ranking reads alone is gridded alone,
//      SearchGrid). Each query is timed three times on its worker thread
//      (CLOCK_THREAD_CPUTIME_ID): the first-stage Search alone, the whole
//      Localize cold (as it runs: cache misses prepared inside it), and the
//      whole Localize again, warm (every map it verifies now cached).
//   3. Scoring (LocalMap::truth, global frame; nothing else reads it): top
//      hit = the source map; top hit shows the place (PlaceOverlap >= 0.5 at
//      0.3 m); sure (verdict.sure) and right (top hit shows the place and its
//      pose is within 0.2 m / 1 deg of the truth, as lmd-eval scores it).
//
// Output: a report on stdout (progress bars on stderr); with --json the last
// stdout line is one JSON object with the figures; --csv FILE writes one row
// per query (its answer, its scores, its costs). --max-bucket B and
// --max-candidates C (experiments, not the product) run the first stage with
// PlaceSearchOptions::max_bucket = B or max_candidates = C instead of its
// defaults.
#include "bench/bench/places_bench.h"

#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench/reobserve.h"
#include "bench/common/flags.h"
#include "core/align/prepared_map.h"
#include "core/eval/ground_truth.h"
#include "core/eval/retrieval_metrics.h"
#include "core/localize/localizer.h"
#include "core/localize/map_source.h"
#include "core/localize/prepared_map_cache.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"
#include "core/place/place_features.h"
#include "core/place/place_index.h"
#include "core/sim/simulate.h"
#include "core/util/progress_bar.h"
#include "core/viewpoint/orientation.h"

namespace lmd::bench {
namespace {

struct Args {
  size_t maps = 1000;
  size_t queries = 100;
  uint64_t seed = 1;
  int threads = 2;
  bool json = false;
  size_t cache_mb = 1024;   // as lmdd's prepared_map_cache_mb
  size_t check_every = 100; // maps whose features are compared with PreparePlace's (0 = none)
  std::string csv;          // per-query rows, if set
  long max_bucket = -1;     // PlaceSearchOptions::max_bucket override; -1 = the product's
  long max_candidates = -1; // PlaceSearchOptions::max_candidates override; -1 = the product's
};

void Usage() {
  std::fprintf(stderr,
               "usage: lmd-bench places --maps N [--queries Q] [--seed S] [--threads T] [--json]\n"
               "                        [--cache-mb M] [--check-every K] [--csv FILE] [--max-bucket B]\n"
               "                        [--max-candidates C]\n");
}

bool ParseArgs(int argc, char** argv, Args* args) {
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "-h") == 0 || std::strcmp(argv[i], "--help") == 0) {
      Usage();
      std::exit(0);
    }
  }
  Flags flags({"maps", "queries", "seed", "threads", "cache-mb", "check-every", "max-bucket", "max-candidates", "csv"},
              {"json"});
  uint64_t maps = 0, queries = 0, threads = 0, cache_mb = 0, check_every = 0, max_bucket = 0, max_candidates = 0;
  const bool ok = flags.Parse(argc, argv) && flags.Count("maps", 1, PlaceIndex::kMaxMaps, args->maps, &maps) &&
                  flags.Count("queries", 1, 100000, args->queries, &queries) &&
                  flags.Count("seed", 0, UINT64_MAX, args->seed, &args->seed) &&
                  flags.Count("threads", 1, 256, static_cast<uint64_t>(args->threads), &threads) &&
                  flags.Count("cache-mb", 0, 1 << 20, args->cache_mb, &cache_mb) &&
                  flags.Count("check-every", 0, 1000000000, args->check_every, &check_every) &&
                  flags.Count("max-bucket", 0, 1000000000, 0, &max_bucket) &&
                  flags.Count("max-candidates", 0, 1000000000000, 0, &max_candidates);
  if (!ok) {
    std::fprintf(stderr, "lmd-bench places: %s\n", flags.error().c_str());
    Usage();
    return false;
  }
  args->maps = maps, args->queries = queries, args->threads = static_cast<int>(threads);
  args->cache_mb = cache_mb, args->check_every = check_every;
  if (flags.Has("max-bucket")) args->max_bucket = static_cast<long>(max_bucket);
  if (flags.Has("max-candidates")) args->max_candidates = static_cast<long>(max_candidates);
  args->json = flags.Has("json");
  args->csv = flags.Get("csv");
  return true;
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// CPU time of the calling thread, ms (robust when other processes share the cores).
double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double ProcessCpuS() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

double MaxRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

// The map as lmdd takes it from the wire: points as float32 (v1::LocalMap
// has float x, y; poses and ranges keep their precision), then deduplicated
// on the local-map grid as server/indexing.cc's MethodView does (lmd-built
// maps keep every point). Written here because MethodView lives in server/.
LocalMap ServedView(LocalMap map) {
  for (Point2& p : map.points) p = {static_cast<float>(p.x), static_cast<float>(p.y)};
  map.points = DeduplicatePoints(map.points, LocalMapOptions().dedup_cell_m);
  return map;
}

// A stored map as the store holds it (lmdd: RocksDB, here memory): float32
// points, the scans (pose, beam geometry, float32 ranges, all beams of a map
// in one array), the trajectory only when it is not the scans' poses (the
// local-map builder makes it so), and the truth for scoring.
struct CompactMap {
  struct ScanHead {
    Pose2 pose;
    float first_angle = 0, angle_step = 0, max_range = 0;
    uint32_t beams = 0;
  };
  std::vector<float> xy;             // x0, y0, x1, y1, ...
  std::vector<ScanHead> scans;
  std::vector<float> ranges;
  std::vector<Pose2> trajectory;     // empty when it equals the scans' poses
  bool trajectory_is_scan_poses = false;
  EvalTruth truth;

  static CompactMap Of(const LocalMap& map) {
    CompactMap c;
    c.xy.reserve(2 * map.points.size());
    for (const Point2& p : map.points) c.xy.push_back(static_cast<float>(p.x)), c.xy.push_back(static_cast<float>(p.y));
    size_t beams = 0;
    for (const Scan& s : map.scans) beams += s.ranges.size();
    c.ranges.reserve(beams);
    c.scans.reserve(map.scans.size());
    for (const Scan& s : map.scans) {
      c.scans.push_back({s.pose, s.first_angle, s.angle_step, s.max_range, static_cast<uint32_t>(s.ranges.size())});
      c.ranges.insert(c.ranges.end(), s.ranges.begin(), s.ranges.end());
    }
    c.trajectory_is_scan_poses = !map.scans.empty() && map.trajectory.size() == map.scans.size();
    for (size_t i = 0; c.trajectory_is_scan_poses && i < map.scans.size(); ++i) {
      const Pose2 &a = map.trajectory[i], &b = map.scans[i].pose;
      c.trajectory_is_scan_poses = a.x == b.x && a.y == b.y && a.theta == b.theta;
    }
    if (!c.trajectory_is_scan_poses) c.trajectory = map.trajectory;
    c.truth = map.truth;
    return c;
  }

  LocalMap Expand() const {
    LocalMap m;
    m.points.reserve(xy.size() / 2);
    for (size_t i = 0; i + 1 < xy.size(); i += 2) m.points.push_back({xy[i], xy[i + 1]});
    m.scans.reserve(scans.size());
    size_t at = 0;
    for (const ScanHead& h : scans) {
      Scan s;
      s.pose = h.pose;
      s.first_angle = h.first_angle, s.angle_step = h.angle_step, s.max_range = h.max_range;
      s.ranges.assign(ranges.begin() + static_cast<long>(at), ranges.begin() + static_cast<long>(at + h.beams));
      at += h.beams;
      m.scans.push_back(std::move(s));
    }
    if (trajectory_is_scan_poses) {
      for (const ScanHead& h : scans) m.trajectory.push_back(h.pose);
    } else {
      m.trajectory = trajectory;
    }
    m.truth = truth;
    return m;
  }

  size_t MemoryBytes() const {
    return sizeof(CompactMap) + xy.capacity() * sizeof(float) + scans.capacity() * sizeof(ScanHead) +
           ranges.capacity() * sizeof(float) + trajectory.capacity() * sizeof(Pose2);
  }
};

// Preparations made by Prepared() and SearchGrid() on the calling thread (the query's).
struct PrepareTally {
  size_t count = 0;
  size_t grids = 0;  // of count: search grids alone (MapSource::SearchGrid)
  double cpu_ms = 0;
};
thread_local PrepareTally tally;

// The stored maps as a MapSource, as lmdd's StoreMapSource serves its store:
// Search from the place index; Prepared() and SearchGrid() from lmdd's
// PreparedMapCache, a miss prepared (or gridded) from the compact map with
// the stored features' heading; RouteOf = (0, map number).
// Search, Prepared and RouteOf may run concurrently once the maps are added;
// two queries that miss the same map both prepare it (as with lmdd's cache).
class SimulatedStore : public MapSource {
 public:
  explicit SimulatedStore(size_t cache_bytes, PreparedMapOptions prepare)
      : cache_(cache_bytes), prepare_(std::move(prepare)) {}

  // Not thread-safe; ids are 0, 1, 2, ... in order.
  Status Add(PlaceFeatures features, CompactMap map) {
    const uint64_t id = maps_.size();
    Status added = index_.Add(id, std::move(features));
    if (!added.ok()) return added;
    maps_.push_back(std::move(map));
    return Status::Ok();
  }

  std::vector<PlaceHypothesis> Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                      const std::function<bool(uint64_t)>& excluded,
                                      PlaceSearchStats* stats) const override {
    return index_.Search(query, options, excluded, stats);
  }

  std::shared_ptr<const PreparedMap> Prepared(uint64_t map_id) const override {
    if (map_id >= maps_.size()) return nullptr;
    return Tallied(false, [&](const PreparedMapCache::ReadSource& read) {
      return cache_.Prepared(kCollection, map_id, prepare_, read);
    }, map_id);
  }

  std::shared_ptr<const PreparedMap> SearchGrid(uint64_t map_id) const override {
    if (map_id >= maps_.size()) return nullptr;
    return Tallied(true, [&](const PreparedMapCache::ReadSource& read) {
      return cache_.SearchGrid(kCollection, map_id, prepare_, read);
    }, map_id);
  }

  bool RouteOf(uint64_t map_id, Route* route) const override {
    if (map_id >= maps_.size()) return false;
    *route = {0, map_id};
    return true;
  }

  const PlaceIndex& index() const { return index_; }
  const CompactMap& map(size_t id) const { return maps_[id]; }
  size_t size() const { return maps_.size(); }
  size_t preparations() const { return preparations_.load(); }
  const PreparedMapCache& cache() const { return cache_; }
  size_t MapBytes() const {
    size_t bytes = maps_.capacity() * sizeof(CompactMap);
    for (const CompactMap& m : maps_) bytes += m.MemoryBytes() - sizeof(CompactMap);
    return bytes;
  }

 private:
  static inline const std::string kCollection = "sim";

  // `lookup` (a cache call) given the reader of map_id; its CPU is tallied
  // when it missed (read the map and prepared it).
  template <typename Lookup>
  std::shared_ptr<const PreparedMap> Tallied(bool grid_only, const Lookup& lookup, uint64_t map_id) const {
    bool missed = false;
    const double c0 = ThreadCpuMs();
    std::shared_ptr<const PreparedMap> prepared = lookup([&]() -> std::optional<PreparedMapCache::Source> {
      missed = true;
      return PreparedMapCache::Source{maps_[map_id].Expand(), index_.Heading(map_id)};
    });
    if (missed) {
      tally.cpu_ms += ThreadCpuMs() - c0;
      ++tally.count;
      tally.grids += grid_only;
      preparations_.fetch_add(1);
    }
    return prepared;
  }

  PlaceIndex index_;
  std::vector<CompactMap> maps_;
  mutable PreparedMapCache cache_;
  const PreparedMapOptions prepare_;
  mutable std::atomic<size_t> preparations_{0};
};

bool SameFeatures(const PlaceFeatures& a, const PlaceFeatures& b) {
  if (a.heading != b.heading || a.features.size() != b.features.size()) return false;
  for (size_t i = 0; i < a.features.size(); ++i) {
    const PlaceFeature &x = a.features[i], &y = b.features[i];
    if (x.x != y.x || x.y != y.y || x.code != y.code) return false;
  }
  return true;
}

// One map of the build, as a worker leaves it for the index.
struct Described {
  PlaceFeatures features;
  CompactMap map;
  int check = -1;  // -1 not checked, 0 differs from PreparePlace, 1 equal
  double cpu_ms = 0;  // served view + compass + DescribePlace + compaction (not the check)
  double check_cpu_ms = 0;  // PreparePlace (lmdd's insert path: features and the prepared map)
};

Described DescribeStored(const LocalMap& raw, const LocalizeOptions& options, bool check) {
  Described d;
  const double c0 = ThreadCpuMs();
  LocalMap map = ServedView(raw);
  const double heading = EstimateDominantOrientation(map.points, options.match.map.orientation);
  d.features = DescribePlace(map.points, heading, options.features);
  d.map = CompactMap::Of(map);
  d.cpu_ms = ThreadCpuMs() - c0;
  if (check) {
    const double c1 = ThreadCpuMs();
    const PreparedPlace place = PreparePlace(map, options);
    d.check_cpu_ms = ThreadCpuMs() - c1;
    d.check = SameFeatures(d.features, place.features) ? 1 : 0;
  }
  return d;
}

struct QueryResult {
  size_t source = 0;
  double prepare_query_cpu_ms = 0;  // PrepareLocalQuery
  double search_cpu_ms = 0;         // the first stage alone
  double cold_cpu_ms = 0;           // Localize, misses prepared inside
  double warm_cpu_ms = 0;           // Localize again
  double cold_wall_ms = 0;
  size_t preparations = 0;          // in the cold Localize
  size_t grid_preparations = 0;     // of them search grids alone (for the fit ranking)
  double preparation_cpu_ms = 0;
  size_t warm_preparations = 0;
  PlaceSearchStats search;
  size_t hypotheses = 0, maps_matched = 0;
  bool source_in_hypotheses = false;
  bool top_is_source = false, top_shows_place = false, any_hit_shows_place = false;
  bool sure = false, right = false;
  double pose_err_m = -1, pose_err_deg = -1;
  bool same_answer_warm = true;     // the warm run gave the same top hit and verdict
  // Diagnostics (--csv).
  uint64_t top_id = 0;
  double top_overlap = 0;           // PlaceOverlap of the query with the top hit
  double best_score = 0, rival_score = 0;
  int source_hypothesis_rank = -1;  // first hypothesis of the source map
  int source_hit_rank = -1;         // among the verified hits
  double source_hit_score = 0;
};

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

template <typename F>
std::vector<double> Column(const std::vector<QueryResult>& results, F f) {
  std::vector<double> out;
  out.reserve(results.size());
  for (const QueryResult& r : results) out.push_back(static_cast<double>(f(r)));
  return out;
}

}  // namespace

int RunPlacesBench(int argc, char** argv) {
  Args args;
  if (!ParseArgs(argc, argv, &args)) return 2;
  LocalizeOptions options;  // the product's defaults, as lmdd serves them
  if (args.max_bucket >= 0) options.search.max_bucket = static_cast<size_t>(args.max_bucket);
  if (args.max_candidates >= 0) options.search.max_candidates = static_cast<size_t>(args.max_candidates);
  const int threads = std::max(1, args.threads);
  const auto run_start = std::chrono::steady_clock::now();
  const double run_cpu0 = ProcessCpuS();

  // 1. Build: simulate, describe (workers), index (this thread).
  SimulationOptions sim;
  sim.world.seed = args.seed;
  sim.route.seed = args.seed;
  sim.num_maps = args.maps;
  sim.local_map.id_prefix = "sim";
  std::vector<size_t> sources;  // query sources: evenly spaced map numbers
  for (size_t q = 0; q < args.queries; ++q)
    sources.push_back(std::min(args.maps - 1, (2 * q + 1) * args.maps / (2 * args.queries)));
  std::vector<LocalMap> query_maps;
  size_t next_source = 0;

  SimulatedStore store(args.cache_mb << 20, options.match.map);
  constexpr size_t kBatch = 256;
  std::vector<LocalMap> batch;
  std::vector<Described> described;
  size_t checked = 0, check_equal = 0, encoded_feature_bytes = 0, features_total = 0;
  double describe_wall_s = 0, describe_cpu_ms = 0, check_cpu_ms = 0, add_wall_s = 0, in_sink_s = 0;
  Status failed = Status::Ok();
  ProgressBar build_bar("simulate + describe + index maps", args.maps);
  auto flush = [&] {
    auto t = std::chrono::steady_clock::now();
    const size_t first = store.size();
    described.assign(batch.size(), Described());
    std::vector<std::thread> workers;
    for (int w = 0; w < threads; ++w) {
      workers.emplace_back([&, w] {
        for (size_t i = static_cast<size_t>(w); i < batch.size(); i += static_cast<size_t>(threads)) {
          const size_t n = first + i;
          described[i] = DescribeStored(batch[i], options, args.check_every > 0 && n % args.check_every == 0);
        }
      });
    }
    for (std::thread& w : workers) w.join();
    describe_wall_s += Seconds(t);
    t = std::chrono::steady_clock::now();
    for (Described& d : described) {
      describe_cpu_ms += d.cpu_ms;
      if (d.check >= 0) ++checked, check_equal += d.check, check_cpu_ms += d.check_cpu_ms;
      encoded_feature_bytes += EncodePlaceFeatures(d.features).size();
      features_total += d.features.features.size();
      Status added = store.Add(std::move(d.features), std::move(d.map));
      if (!added.ok() && failed.ok()) failed = added;
    }
    add_wall_s += Seconds(t);
    batch.clear();
    build_bar.Update(store.size());
  };
  const auto sim_start = std::chrono::steady_clock::now();
  SimulateLocalMapsStreaming(sim, [&](LocalMap&& map) {
    const auto t = std::chrono::steady_clock::now();
    const size_t n = store.size() + batch.size();
    while (next_source < sources.size() && sources[next_source] == n) {
      query_maps.push_back(Reobserve(map, args.seed * 1000003 + n, 0.02, 0.1));
      ++next_source;
    }
    batch.push_back(std::move(map));
    if (batch.size() == kBatch) flush();
    in_sink_s += Seconds(t);
    return failed.ok() && store.size() + batch.size() < args.maps;
  });
  if (!batch.empty()) flush();
  const double build_wall_s = Seconds(sim_start);
  const double simulate_s = build_wall_s - in_sink_s;
  if (!failed.ok()) {
    build_bar.Abandon();
    std::fprintf(stderr, "lmd-bench places: %s\n", failed.ToString().c_str());
    return 1;
  }
  build_bar.Done();
  const double build_cpu_s = ProcessCpuS() - run_cpu0;
  const size_t n_maps = store.size();
  if (n_maps < args.maps)
    std::fprintf(stderr, "lmd-bench places: the simulator gave %zu maps of %zu\n", n_maps, args.maps);
  sources.resize(query_maps.size());
  const double nm = static_cast<double>(std::max<size_t>(1, n_maps));
  const size_t index_bytes = store.index().MemoryBytes();
  const size_t map_bytes = store.MapBytes();

  // 2. Queries, on `threads` workers, each query on one thread from start to end.
  std::vector<QueryResult> results(query_maps.size());
  {
    ProgressBar bar("queries", query_maps.size());
    std::atomic<size_t> next{0}, done{0};
    std::mutex bar_mutex;
    std::vector<std::thread> workers;
    for (int w = 0; w < threads; ++w) {
      workers.emplace_back([&] {
        for (size_t q = next.fetch_add(1); q < query_maps.size(); q = next.fetch_add(1)) {
          QueryResult& r = results[q];
          r.source = sources[q];
          const LocalMap served = ServedView(query_maps[q]);
          double c = ThreadCpuMs();
          const LocalQuery query = PrepareLocalQuery(served, options);
          r.prepare_query_cpu_ms = ThreadCpuMs() - c;

          c = ThreadCpuMs();
          const std::vector<PlaceHypothesis> hypotheses = store.Search(query.features, options.search, {}, &r.search);
          r.search_cpu_ms = ThreadCpuMs() - c;
          for (size_t k = 0; k < hypotheses.size() && r.source_hypothesis_rank < 0; ++k)
            if (hypotheses[k].map_id == r.source) r.source_hypothesis_rank = static_cast<int>(k);
          r.source_in_hypotheses = r.source_hypothesis_rank >= 0;

          tally = PrepareTally();
          c = ThreadCpuMs();
          const auto t = std::chrono::steady_clock::now();
          const Localization cold = Localize(query, store, options);
          r.cold_wall_ms = Seconds(t) * 1e3;
          r.cold_cpu_ms = ThreadCpuMs() - c;
          r.preparations = tally.count;
          r.grid_preparations = tally.grids;
          r.preparation_cpu_ms = tally.cpu_ms;
          r.hypotheses = cold.stats.hypotheses;
          r.maps_matched = cold.stats.maps_matched;

          tally = PrepareTally();
          c = ThreadCpuMs();
          const Localization warm = Localize(query, store, options);
          r.warm_cpu_ms = ThreadCpuMs() - c;
          r.warm_preparations = tally.count;
          r.same_answer_warm = warm.verdict.sure == cold.verdict.sure && warm.hits.size() == cold.hits.size() &&
                               (cold.hits.empty() || warm.hits[0].map_id == cold.hits[0].map_id);

          r.sure = cold.verdict.sure;
          r.best_score = cold.verdict.best_score, r.rival_score = cold.verdict.rival_score;
          for (size_t k = 0; k < cold.hits.size() && r.source_hit_rank < 0; ++k) {
            if (cold.hits[k].map_id != r.source) continue;
            r.source_hit_rank = static_cast<int>(k);
            r.source_hit_score = cold.hits[k].score;
          }
          if (!cold.hits.empty()) {
            const LocalizedHit& top = cold.hits[0];
            r.top_id = top.map_id;
            r.top_is_source = top.map_id == r.source;
            const LocalMap db = store.map(top.map_id).Expand();
            r.top_overlap = PlaceOverlap(served, db);
            r.top_shows_place = r.top_overlap >= 0.5;
            PoseError(top.pose, Compose(Inverse(db.truth.global_frame), served.truth.global_frame), &r.pose_err_m,
                      &r.pose_err_deg);
            r.right = r.sure && r.top_shows_place && r.pose_err_m <= 0.2 && r.pose_err_deg <= 1.0;
            for (const LocalizedHit& h : cold.hits)
              r.any_hit_shows_place |= PlaceOverlap(served, store.map(h.map_id).Expand()) >= 0.5;
          }
          std::lock_guard<std::mutex> lock(bar_mutex);
          bar.Update(done.fetch_add(1) + 1);
        }
      });
    }
    for (std::thread& w : workers) w.join();
    bar.Done();
  }

  // 3. Report.
  if (!args.csv.empty()) {
    std::FILE* out = std::fopen(args.csv.c_str(), "w");
    if (out == nullptr) {
      std::fprintf(stderr, "lmd-bench places: cannot write %s\n", args.csv.c_str());
    } else {
      std::fprintf(out, "query,source,top,top_is_source,top_overlap,sure,right,best_score,rival_score,pose_err_m,"
                        "pose_err_deg,source_hypothesis_rank,source_hit_rank,source_hit_score,candidates,maps_voted,"
                        "maps_matched,search_cpu_ms,cold_cpu_ms,warm_cpu_ms,preparations,preparation_cpu_ms\n");
      for (size_t q = 0; q < results.size(); ++q) {
        const QueryResult& r = results[q];
        std::fprintf(out,
                     "%zu,%zu,%llu,%d,%.3f,%d,%d,%.4f,%.4f,%.4f,%.3f,%d,%d,%.4f,%zu,%zu,%zu,%.3f,%.3f,%.3f,%zu,%.3f\n",
                     q, r.source, static_cast<unsigned long long>(r.top_id), r.top_is_source, r.top_overlap, r.sure,
                     r.right, r.best_score, r.rival_score, r.pose_err_m, r.pose_err_deg, r.source_hypothesis_rank,
                     r.source_hit_rank, r.source_hit_score, r.search.candidates, r.search.maps_voted, r.maps_matched,
                     r.search_cpu_ms, r.cold_cpu_ms, r.warm_cpu_ms, r.preparations, r.preparation_cpu_ms);
      }
      std::fclose(out);
    }
  }
  const double nq = static_cast<double>(std::max<size_t>(1, results.size()));
  auto share = [&](bool QueryResult::*field) {
    size_t k = 0;
    for (const QueryResult& r : results) k += r.*field;
    return static_cast<double>(k) / nq;
  };
  size_t sure = 0, sure_right = 0, preparations = 0, grid_preparations = 0, warm_preparations = 0, warm_same = 0;
  for (const QueryResult& r : results) {
    sure += r.sure, sure_right += r.right, preparations += r.preparations, warm_preparations += r.warm_preparations;
    grid_preparations += r.grid_preparations;
    warm_same += r.same_answer_warm;
  }
  const std::vector<double> search_cpu = Column(results, [](const QueryResult& r) { return r.search_cpu_ms; });
  const std::vector<double> cold_cpu = Column(results, [](const QueryResult& r) { return r.cold_cpu_ms; });
  const std::vector<double> warm_cpu = Column(results, [](const QueryResult& r) { return r.warm_cpu_ms; });
  const std::vector<double> cold_wall = Column(results, [](const QueryResult& r) { return r.cold_wall_ms; });
  const std::vector<double> prep_cpu = Column(results, [](const QueryResult& r) { return r.preparation_cpu_ms; });
  const std::vector<double> prep_count = Column(results, [](const QueryResult& r) { return r.preparations; });
  const std::vector<double> query_cpu = Column(results, [](const QueryResult& r) { return r.prepare_query_cpu_ms; });
  const std::vector<double> candidates = Column(results, [](const QueryResult& r) { return r.search.candidates; });
  const std::vector<double> maps_voted = Column(results, [](const QueryResult& r) { return r.search.maps_voted; });
  const std::vector<double> matched = Column(results, [](const QueryResult& r) { return r.maps_matched; });
  std::vector<double> pose_m;
  for (const QueryResult& r : results)
    if (r.top_shows_place) pose_m.push_back(r.pose_err_m);
  const double per_prep_ms = preparations ? Mean(prep_cpu) * nq / static_cast<double>(preparations) : 0.0;
  const double sure_share = static_cast<double>(sure) / nq;
  const double right_share = sure ? static_cast<double>(sure_right) / static_cast<double>(sure) : 0.0;

  std::string overrides;
  if (args.max_bucket >= 0) overrides += ", max_bucket " + std::to_string(args.max_bucket) + " (not the default)";
  if (args.max_candidates >= 0) {
    overrides += ", max_candidates " + std::to_string(args.max_candidates) + " (not the default)";
  }
  std::printf("lmd-bench places: %zu maps (seed %llu), %zu queries, %d threads, prepared-map cache %zu MiB%s\n",
              n_maps, static_cast<unsigned long long>(args.seed), results.size(), threads, args.cache_mb,
              overrides.c_str());
  std::printf("  build                   %.1f s wall, %.1f s CPU: simulate %.1f s, describe %.1f s wall "
              "(%.2f ms CPU/map), index add %.2f s\n",
              build_wall_s, build_cpu_s, simulate_s, describe_wall_s, describe_cpu_ms / nm, add_wall_s);
  std::printf("  features check          %zu of %zu checked maps equal PreparePlace(map).features "
              "(PreparePlace %.2f ms CPU/map)\n",
              check_equal, checked, checked ? check_cpu_ms / static_cast<double>(checked) : 0.0);
  std::printf("  place features per map  %.1f features, %.0f bytes encoded (EncodePlaceFeatures)\n",
              static_cast<double>(features_total) / nm, static_cast<double>(encoded_feature_bytes) / nm);
  std::printf("  place index memory      %.1f MiB (%.0f bytes/map)\n", static_cast<double>(index_bytes) / (1 << 20),
              static_cast<double>(index_bytes) / nm);
  std::printf("  stored maps (compact)   %.1f MiB (%.0f bytes/map)\n", static_cast<double>(map_bytes) / (1 << 20),
              static_cast<double>(map_bytes) / nm);
  std::printf("  per query CPU ms        p50       p99      mean\n");
  std::printf("    PrepareLocalQuery  %8.2f  %8.2f  %8.2f\n", Quantile(query_cpu, 0.5), Quantile(query_cpu, 0.99),
              Mean(query_cpu));
  std::printf("    first-stage Search %8.2f  %8.2f  %8.2f\n", Quantile(search_cpu, 0.5), Quantile(search_cpu, 0.99),
              Mean(search_cpu));
  std::printf("    Localize, cold     %8.2f  %8.2f  %8.2f   (wall p50 %.2f ms)\n", Quantile(cold_cpu, 0.5),
              Quantile(cold_cpu, 0.99), Mean(cold_cpu), Quantile(cold_wall, 0.5));
  std::printf("      of it preparing  %8.2f  %8.2f  %8.2f   (%zu preparations, %zu of them search grids alone, "
              "%.1f per query p50, %.2f ms each)\n",
              Quantile(prep_cpu, 0.5), Quantile(prep_cpu, 0.99), Mean(prep_cpu), preparations, grid_preparations,
              Quantile(prep_count, 0.5), per_prep_ms);
  std::printf("    Localize, warm     %8.2f  %8.2f  %8.2f   (%zu preparations; same answer %zu of %zu)\n",
              Quantile(warm_cpu, 0.5), Quantile(warm_cpu, 0.99), Mean(warm_cpu), warm_preparations, warm_same,
              results.size());
  std::printf("  first stage (p50)       %.0f stored features compared, %.0f maps voted; %.0f maps matched\n",
              Quantile(candidates, 0.5), Quantile(maps_voted, 0.5), Quantile(matched, 0.5));
  std::printf("  prepared-map cache      %zu maps, %.1f MiB, %llu evictions\n", store.cache().size(),
              static_cast<double>(store.cache().bytes()) / (1 << 20),
              static_cast<unsigned long long>(store.cache().evictions()));
  std::printf("  answers                 source among hypotheses %.2f, top hit = source %.2f, "
              "top hit shows the place %.2f, a hit shows it %.2f\n",
              share(&QueryResult::source_in_hypotheses), share(&QueryResult::top_is_source),
              share(&QueryResult::top_shows_place), share(&QueryResult::any_hit_shows_place));
  std::printf("  verdict                 sure %.2f (%zu), right %.3f of them (%zu); pose error of place top hits "
              "p50 %.3f m\n",
              sure_share, sure, right_share, sure_right, Quantile(pose_m, 0.5));
  std::printf("  process                 %.1f s wall, %.1f s CPU, max RSS %.0f MiB\n", Seconds(run_start),
              ProcessCpuS() - run_cpu0, MaxRssMb());
  if (args.json) {
    std::printf(
        "{\"maps\": %zu, \"queries\": %zu, \"seed\": %llu, \"threads\": %d, \"cache_mb\": %zu, "
        "\"build_wall_s\": %.2f, \"build_cpu_s\": %.2f, \"simulate_s\": %.2f, \"describe_s\": %.2f, "
        "\"describe_cpu_ms_per_map\": %.3f, \"index_add_s\": %.3f, \"features_checked\": %zu, "
        "\"features_equal\": %zu, \"prepare_place_cpu_ms_per_map\": %.3f, \"features_per_map\": %.1f, "
        "\"feature_bytes_per_map\": %.1f, "
        "\"index_bytes\": %zu, \"index_bytes_per_map\": %.1f, \"map_bytes_per_map\": %.1f, "
        "\"prepare_query_cpu_ms_p50\": %.3f, \"search_cpu_ms_p50\": %.3f, \"search_cpu_ms_p99\": %.3f, "
        "\"localize_cold_cpu_ms_p50\": %.3f, \"localize_cold_cpu_ms_p99\": %.3f, "
        "\"localize_warm_cpu_ms_p50\": %.3f, \"localize_warm_cpu_ms_p99\": %.3f, "
        "\"preparation_cpu_ms_p50\": %.3f, \"preparations\": %zu, \"grid_preparations\": %zu, "
        "\"preparation_cpu_ms_each\": %.3f, "
        "\"candidates_p50\": %.0f, \"maps_matched_p50\": %.1f, \"cache_evictions\": %zu, "
        "\"source_in_hypotheses\": %.3f, \"top_is_source\": %.3f, \"top_shows_place\": %.3f, "
        "\"sure_share\": %.3f, \"sure_right\": %.4f, \"max_rss_mb\": %.0f}\n",
        n_maps, results.size(), static_cast<unsigned long long>(args.seed), threads, args.cache_mb, build_wall_s,
        build_cpu_s, simulate_s, describe_wall_s, describe_cpu_ms / nm, add_wall_s, checked, check_equal,
        checked ? check_cpu_ms / static_cast<double>(checked) : 0.0,
        static_cast<double>(features_total) / nm, static_cast<double>(encoded_feature_bytes) / nm, index_bytes,
        static_cast<double>(index_bytes) / nm, static_cast<double>(map_bytes) / nm, Quantile(query_cpu, 0.5),
        Quantile(search_cpu, 0.5), Quantile(search_cpu, 0.99), Quantile(cold_cpu, 0.5), Quantile(cold_cpu, 0.99),
        Quantile(warm_cpu, 0.5), Quantile(warm_cpu, 0.99), Quantile(prep_cpu, 0.5), preparations, grid_preparations,
        per_prep_ms, Quantile(candidates, 0.5), Quantile(matched, 0.5), static_cast<size_t>(store.cache().evictions()),
        share(&QueryResult::source_in_hypotheses), share(&QueryResult::top_is_source),
        share(&QueryResult::top_shows_place), sure_share, right_share, MaxRssMb());
  }
  return checked == check_equal ? 0 : 1;
}

}  // namespace lmd::bench
