// lmdd's configuration: one plain struct, filled from defaults, then an
// optional config file, then command-line flags (later wins).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace lmd::server {

// Calls run on a pool of threads; far more than any machine has cores only
// costs memory, and the system refuses tens of thousands (lmdd would abort).
inline constexpr uint32_t kMaxWorkerThreads = 1024;
// A write waits this long at most for a copy's confirmation: a minute is
// already far beyond a copy that keeps up.
inline constexpr uint32_t kMaxReplicateTimeoutMs = 60000;

struct ServerConfig {
  // Address to serve gRPC on, HOST:PORT. Port 0 picks a free port.
  std::string listen = "127.0.0.1:50051";
  // Directory of the RocksDB store. A new store is created only in an empty
  // or missing directory: one holding files but no store is refused.
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
  // Earlier maps in one sequence query (each costs a localisation).
  uint32_t max_sequence_maps = 8;
  // Maps a collection keeps: an insert beyond it deletes the collection's
  // oldest maps (insertion order) in the same write and lists them in the
  // response (evicted). 0: keep every map. A fleet that stores a map per
  // robot-second grows without bound and every query's first pass reads more
  // postings as it grows (docs/capacity.md); a cap bounds both.
  uint32_t retain_maps_per_collection = 0;
  // Insert request ids (InsertMapsRequest.request_id) each collection keeps
  // with their answers, so that a retry is answered instead of storing its
  // maps again: the newest this many. A retry comes seconds after its first
  // attempt; 10000 covers minutes of a busy fleet's inserts.
  uint32_t insert_request_ids_kept = 10000;
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

  // Concurrency. Threads that run calls (0: one per hardware thread; at most
  // kMaxWorkerThreads), and calls that may wait for one (at least 1); a call
  // beyond that is refused at once with RESOURCE_EXHAUSTED, which bounds
  // memory under overload.
  uint32_t worker_threads = 0;
  uint32_t max_queued_calls = 1024;
  // What lmdd computed from recently seen maps (descriptor, scan-matching
  // grids, place features), kept to skip doing it twice for a map sent twice
  // (query, then insert); about 100-200 KB each. 0: off.
  uint32_t descriptor_cache_entries = 256;

  // The default method (core/localize) scan matches the `verify_candidates`
  // stored maps its first stage's best pose hypotheses name (1-3 ms each on
  // real logs). A request may ask for another number (verify_candidates, up
  // to max_verify_candidates). docs/results.md measures 20.
  uint32_t verify_candidates = 20;
  // Longest a query (Retrieve, DetectChanges) may compute, s, whatever the
  // client's deadline: one then ends with DEADLINE_EXCEEDED and frees its
  // worker. Real local maps take milliseconds; an unstructured map the
  // limits allow (thousands of points scattered over max_map_extent_m) kept a
  // worker busy for minutes. 0: no bound but the client's deadline.
  double max_query_seconds = 30.0;
  // Under load, queries trade depth for time. A Retrieve or DetectChanges of
  // the default method that starts while at least `busy_queued_calls` calls
  // wait for a worker scan matches `busy_verify_candidates` maps (if less than
  // verify_candidates; no route neighbours retried, LocalizeOptions::
  // passed_over_retries, and the hypotheses left in vote order,
  // fit_rank_maps), and says so in its response (reduced_depth). A
  // request that names its own verify_candidates is not reduced. 0: never.
  uint32_t busy_queued_calls = 4;
  uint32_t busy_verify_candidates = 5;
  // ... and its first stage compares at most this many stored features
  // (PlaceSearchOptions::max_candidates, 100k otherwise; 0: the same bound).
  uint32_t busy_search_candidates = 20000;
  // true: the paper methods' LMD index holds each feature with its 3 m inner
  // word too, 64 features per map (WithInnerWords,
  // core/describe/describer.h). Fixed when a store is created (a store made
  // with the other setting is refused). The default method does not use it.
  bool inner_words = false;
  // false: lmdd keeps no index for the paper's methods (their LMD
  // descriptor and postings); Retrieve and DetectChanges with a paper method
  // fail with FAILED_PRECONDITION. For a fleet that asks the default method
  // only: 15 % less lmdd CPU per robot tick, measured (docs/capacity.md,
  // twenty-fifth stop). Fixed when a store is created, as inner_words.
  bool paper_index = true;
  // Memory (MiB) for stored maps prepared for scan matching (about 100-200
  // KB each; a map is prepared when it is inserted, and again on its first
  // hit after a restart or an eviction, 1-5 ms). 0: no cache.
  uint32_t prepared_map_cache_mb = 1024;

  // Prometheus text metrics over HTTP at http://HOST:PORT/metrics. Empty: off.
  std::string metrics_listen;

  // Replicated collections (server/cluster, deploy/README.md). Empty
  // cluster_etcd: a single node, exactly as without these settings.
  // etcd members' client addresses, comma-separated ("10.0.0.1:2379,...").
  std::string cluster_etcd;
  // This node's name in the cluster (default: its advertised address) and the
  // address other nodes and clients reach it on (default: listen).
  std::string cluster_node_id;
  std::string cluster_advertise;
  // Copies of one collection go to nodes of different zones when set.
  std::string cluster_zone;
  // Copies of each collection (the primary included), when nodes allow.
  uint32_t cluster_replication_factor = 3;
  // How long a node may be gone, s, before its collections are copied to
  // other nodes: a restart or a short network cut costs no copy (its own
  // catches up when it returns). Its primaries fail over at once all the same.
  uint32_t cluster_replace_after_s = 60;
  // The node's etcd lease, s: a node silent this long loses its primaries to
  // in-sync copies. etcd grants at least 2 s with its default flags.
  uint32_t cluster_lease_ttl_s = 2;
  // How long a primary waits for a copy to confirm a write, ms, before it
  // takes that copy out of the in-sync set (it then catches up). At most
  // kMaxReplicateTimeoutMs.
  uint32_t cluster_replicate_timeout_ms = 1000;
  // Writes a primary keeps in memory per collection, MiB, for copies that
  // catch up after a short absence; one further behind is copied whole.
  uint32_t cluster_log_mb = 64;
  // Keys in etcd start with this.
  std::string cluster_prefix = "/lmd";
  // With tokens_file: a file holding the token (first line) this node sends
  // on calls to other nodes; it needs write access to every collection ("*").
  std::string cluster_token_file;
  // With TLS (tls_cert_file), nodes call each other over TLS with their own
  // certificate and key, trusting this CA (default: tls_client_ca_file); the
  // name other nodes' certificates are checked for, when not their address.
  std::string cluster_tls_ca_file;
  std::string cluster_tls_server_name;
};

// Reads "key = value" lines ('#' starts a comment; keys are the field names
// above) into *config. InvalidArgument naming file:line on an unknown key or a
// bad value; IoError if the file cannot be read.
Status LoadConfigFile(const std::string& path, ServerConfig* config);

// Applies one setting by name, e.g. ("max_top_k", "50"). InvalidArgument if the
// key is unknown or the value does not parse.
Status SetConfigValue(const std::string& key, const std::string& value, ServerConfig* config);

// True if HOST of a HOST:PORT address (ParseHostPort) is a loopback address
// or "localhost"; false for anything else, HOST:PORT or not.
bool IsLoopbackAddress(const std::string& host_port);

}  // namespace lmd::server
