// lmdd's configuration: one plain struct, filled from defaults, then an
// optional config file, then command-line flags (later wins).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace lmd::server {

struct ServerConfig {
  // Address to serve gRPC on, HOST:PORT. Port 0 picks a free port.
  std::string listen = "127.0.0.1:50051";
  // Directory of the RocksDB store; created if absent.
  std::string data_dir = "./lmd-data";
  // spdlog level: trace, debug, info, warn, error, critical, off.
  std::string log_level = "info";

  // Limits. A request over a limit is refused with a message naming it.
  // Largest gRPC message accepted, bytes (RESOURCE_EXHAUSTED above it).
  int max_message_bytes = 64 << 20;
  // Points in one local map.
  uint32_t max_points_per_map = 200000;
  // Scans in one local map, and beams in one scan.
  uint32_t max_scans_per_map = 2000;
  uint32_t max_beams_per_scan = 4096;
  // Maps in one InsertMaps call.
  uint32_t max_maps_per_batch = 1000;
  // Largest top_k of Retrieve / DetectChanges.
  uint32_t max_top_k = 1000;
  // Largest verify_candidates a Retrieve / DetectChanges request may ask for
  // (each verified hit costs a scan match).
  uint32_t max_verify_candidates = 100;
  // Number of collections.
  uint32_t max_collections = 1000;
  // Maps a collection keeps: an insert beyond it deletes the collection's
  // oldest maps (insertion order) in the same write and lists them in the
  // response (evicted). 0: keep every map. A fleet that stores a map per
  // robot-second grows without bound and every query's first pass reads more
  // postings as it grows (docs/capacity.md); a cap bounds both.
  uint32_t retain_maps_per_collection = 0;
  // Largest absolute coordinate of a point or pose, m. Catches unit mistakes
  // (mm sent as m) and garbage before it reaches the method.
  double max_abs_coordinate_m = 100000.0;
  // Largest width or height of a map's bounding box (points, trajectory,
  // scan poses) and largest scan max_range, m. A local map spans tens of
  // metres (at most 61 m on the nine real logs); a map's scan-matching grids
  // grow with its area (a 1 km map took GBs); the index's pose words reach
  // 1638 m from the planned origin, hence at most 1150.
  double max_map_extent_m = 200.0;

  // fsync the write-ahead log before acknowledging an insert. Off: an
  // acknowledged insert survives a crash of lmdd (the WAL is written before the
  // ack) but not a power loss or kernel crash. On: it survives those too, at
  // the cost of one fsync per insert call: single-map inserts (lmd-bench
  // fill --maps 3000 --batch 1, 2-core VM) 577 and 571 per second off, 447
  // and 428 on (-24 %).
  bool sync_writes = false;
  // Serve on a non-loopback address without TLS and tokens. Off by default:
  // lmdd then refuses to listen anywhere but loopback.
  bool allow_insecure_remote = false;

  // Security. TLS is on when both the certificate and key files are set
  // (PEM). With a client CA file, clients must present a certificate it signed.
  std::string tls_cert_file;
  std::string tls_key_file;
  std::string tls_client_ca_file;
  // Bearer tokens per collection (format in auth.h). Empty: no token checks.
  std::string tokens_file;

  // Concurrency. Threads that run calls (0: one per hardware thread), and
  // calls that may wait for one; a call beyond that is refused at once with
  // RESOURCE_EXHAUSTED, which bounds memory under overload.
  uint32_t worker_threads = 0;
  uint32_t max_queued_calls = 1024;
  // Descriptors of recently seen maps kept to skip describing a map sent
  // twice (query, then insert); about 1.5 KB each. 0: off.
  uint32_t descriptor_cache_entries = 4096;

  // The default method verifies the index's best `verify_candidates` hits
  // geometrically (scan matching; 1-8 ms each) and re-ranks them by aligned
  // overlap. 0: the default method is the index alone (LMD kernel). With 10,
  // lmd-bench load at 60 robots cost lmdd 13.8 ms of CPU per robot-second;
  // 20, lmd-eval's best, gains about 0.07 place recall@1 on the real logs
  // (docs/results.md) and cost 20.5 ms in the same test. A request may ask
  // for another depth (verify_candidates, up to max_verify_candidates).
  uint32_t verify_candidates = 10;
  // Verification stops once this many candidates matched well (verification
  // score >= 0.8); the rest are returned unverified, in index order. 0:
  // verify all verify_candidates. Off by default: the first matches are
  // mostly maps just before the query on its own route, so stopping there
  // left loop closures unverified: on intel, aces, mit and fr079 (every
  // 15th map queried with lmdctl, 204 queries) the first hit from another
  // pass showed the query's place for 63 of 117 queries with 3 vs 67 of 110
  // with 0. It saves CPU when many robots share a place (README).
  uint32_t verify_enough_matches = 0;
  // Weight of reverse conflicts in the verification score: the fraction of
  // a candidate's points that the query map saw as free space (lmd-eval's
  // best uses 4). 0: not measured. Off by default for CPU: with 4, on the
  // 204 real-log queries above the first hit from another pass showed the
  // place for 71 of 114 vs 66 of 110 queries, top-5 precision 0.713 vs 0.721;
  // the demo localised 4 vs 3 of 8. The query's free space is ray-cast once
  // per call, and that preparation is reused once the map is stored and hit
  // (HitVerifier): lmd-bench load at 150 robots, lmdd CPU per robot-second
  // 9.0-9.1 vs 8.6-8.8 ms with 0 (9.7-10.1 ms before the reuse).
  double reverse_conflict_weight = 0.0;
  // Largest offset (m, per axis) between the planned viewpoints of two maps
  // of one place that the default method's kernel accepts. The planners are
  // metres off on real logs: 3 m gave +0.05 place recall@1 over 0.5 m
  // (lmd-eval retrieval ablation). The paper methods keep the index default.
  double default_max_offset_m = 3.0;
  // Once it has the top k, the default method's index stops after this many
  // maps scored exactly, best bounds first (RetrieveOptions::max_maps_scored); 0: exact. In a
  // store with many maps of each place the bound prunes little (lmd-bench
  // load: 20-60 % of all maps scored). 200: on intel, aces, mit and fr079
  // (every 15th map queried with lmdctl, 204 queries) the best hit other than
  // the query's own map was exact scoring's for 202 queries, and it showed
  // the query's place as often (0.961); on the five other logs, 177 of 179
  // and 0.966 vs 0.972. lmdd's CPU per robot-second fell by 13 % at 80
  // robots (lmd-bench load). Re-measured with this build on the same
  // queries: the best hit differs from exact scoring's for 4 (200), 7 (150)
  // and 8 (100) of the 204; the first hit from another pass shows the
  // query's place for 84 (exact), 83, 83 and 82 of 141, and on the five
  // other logs for 57 (200), 57 and 55 of 84 (150 and 200: the same best hit
  // for all 179). 150 spends 3.3 % fewer instructions per robot-second under
  // load than 200 (callgrind), 100 6.8 %.
  uint32_t max_maps_scored = 150;
  // The default method's index skips, in its first pass, the posting lists
  // of words with more than this many postings per stored map
  // (RetrieveOptions::bound_skip_postings_per_map); 0: reads every list.
  // On the fleet's demo world ten words hold about a third of all postings
  // and most of what a query reads. lmd-bench load at 150 robots for 30 s
  // read 70k instead of 106k postings per query at the end (4.7k maps),
  // with place_at_1 0.953 both; 2 read 50k but lost place_at_1 (0.940), 1
  // more (0.914). Callgrind on the 2.3k-map store: 38.65 vs 40.82 M
  // instructions per robot-second. On the real logs it changed little:
  // of the 204 lmdctl queries on intel, aces, mit and fr079, the first hit
  // from another pass showed the place for 84 (3) vs 83 (0) of 141.
  double bound_skip_postings_per_map = 3.0;
  // Under load, queries trade depth for time. A Retrieve or DetectChanges of
  // the default method that starts while at least `busy_queued_calls` calls
  // wait for a worker verifies `busy_verify_candidates` hits and scores at
  // most `busy_max_maps_scored` maps (if less than the settings above), and
  // says so in its response (reduced_depth). A request that names its own
  // verify_candidates is not reduced. 0: never. lmd-bench load at 200
  // robots: p99 16-32 ms in 18 of 18 runs with 0.2-6 % of queries reduced,
  // against 3 of 6 runs under 100 ms without (the others saturated in the
  // VM's slow minutes, p99 0.3-0.9 s); place_at_1 0.947-0.956 over all runs
  // (docs/capacity.md).
  uint32_t busy_queued_calls = 8;
  uint32_t busy_verify_candidates = 5;
  uint32_t busy_max_maps_scored = 60;
  // true: index each feature with its 3 m inner word too, 64 features per
  // map (WithInnerWords, core/describe/describer.h; lmd-eval's best). Fixed
  // when a store is created (a store made with the other setting is refused).
  // Measured: lmd-eval best's ANR 15.2 % vs 18.2 %, place recall@5 0.84 vs
  // 0.83, @1 0.79 vs 0.79 (full runs); lmd-bench load at 80 robots: lmdd CPU
  // 25 vs 14.4 ms per robot-second, p99 875 vs 25 ms (saturated).
  bool inner_words = false;
  // Memory (MiB) for prepared db maps kept for verification (about 100 KB
  // each on the demo world; preparing one costs about 0.5 ms, lmd-microbench).
  // A store with many robots verifies mostly recent maps: lmd-bench load at
  // 90 robots (about 1900 maps) spent 11-12 vs 13-14 ms of CPU per
  // robot-second with room for every map vs for 500, at 370 vs 181 MB peak
  // RSS. 0: no cache.
  uint32_t prepared_map_cache_mb = 1024;

  // Prometheus text metrics over HTTP at http://HOST:PORT/metrics. Empty: off.
  std::string metrics_listen;
};

// Reads "key = value" lines ('#' starts a comment; keys are the field names
// above) into *config. InvalidArgument naming file:line on an unknown key or a
// bad value; IoError if the file cannot be read.
Status LoadConfigFile(const std::string& path, ServerConfig* config);

// Applies one setting by name, e.g. ("max_top_k", "50"). InvalidArgument if the
// key is unknown or the value does not parse.
Status SetConfigValue(const std::string& key, const std::string& value, ServerConfig* config);

// True if HOST of a HOST:PORT address is a loopback address or "localhost".
bool IsLoopbackAddress(const std::string& host_port);

}  // namespace lmd::server
