// Call metrics: per RPC method, calls, errors by status code and a latency
// histogram; exported to the Stats call and as Prometheus text.
// Thread-safe (one mutex; recording is a few increments).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/localize/confidence.h"
#include "lmd/v1/lmd.pb.h"

namespace lmd::server {

// CPU time the process has used since start, s (all threads).
double ProcessCpuSeconds();

class CallMetrics {
 public:
  // Records one finished call. `code` is the gRPC status code (0 = OK).
  void Record(const std::string& method, int code, double latency_ms);

  // Records the work of one default-method query (Retrieve or
  // DetectChanges): stored features the first stage compared, maps scan
  // matched, and whether the server was busy and reduced the query's depth.
  // Exported as Prometheus counters, so that an operator sees what
  // verify_candidates costs and how often load reduced it.
  void RecordQueryWork(uint64_t features_compared, uint64_t maps_matched, bool reduced_depth);

  // Records how a default-method query was answered: what the robot asked
  // (a prior, a sequence, or neither: global) and whether lmdd was sure; and
  // a prior that no map near it matched, whatever followed (a global answer
  // on request). Exported as lmd_answers_total{asked, verdict} and
  // lmd_priors_failed_total: a fleet's share of sure answers, and how often
  // its robots' priors are wrong, are its health.
  void RecordAnswer(const Verdict& verdict);

  // Records maps deleted to keep a collection within its cap.
  void RecordEvicted(uint64_t maps);

  // Calls, errors and latency percentiles per method, by method name.
  // Percentiles are bucket upper bounds: within 10 % of the true value.
  std::vector<v1::MethodStats> Snapshot() const;

  // What the cache of prepared maps did (core/localize/prepared_map_cache.h).
  struct PreparedCache {
    uint64_t misses = 0;  // maps prepared on a hit since start
    uint64_t bytes = 0;   // bytes held now
  };

  // Prometheus text exposition (version 0.0.4) of the calls, of
  // `collections` (maps, points, postings per collection), of the prepared
  // maps' cache and of the process's CPU time.
  std::string PrometheusText(const std::vector<v1::CollectionInfo>& collections, double uptime_s,
                             const PreparedCache& prepared, double cpu_seconds) const;

 private:
  // Latency buckets grow by 10 %: bucket i holds latencies up to
  // kFirstBoundMs * 1.1^i; the last bucket holds everything larger.
  static constexpr int kBuckets = 200;
  static constexpr double kFirstBoundMs = 0.01;
  static double BucketBoundMs(int i);

  struct Method {
    uint64_t calls = 0;
    std::map<int, uint64_t> by_code;
    double total_ms = 0.0;
    std::array<uint64_t, kBuckets> buckets{};
  };
  static double Percentile(const Method& method, double q);

  struct QueryWork {
    uint64_t queries = 0, features_compared = 0, maps_matched = 0, reduced_depth = 0;
  };

  mutable std::mutex mutex_;
  std::map<std::string, Method> methods_;  // guarded by mutex_
  QueryWork work_;                         // guarded by mutex_
  // Answers by what was asked (global, prior, sequence) and verdict (sure, unsure).
  std::map<std::pair<std::string, std::string>, uint64_t> answers_;  // guarded by mutex_
  uint64_t priors_failed_ = 0;                                        // guarded by mutex_
  uint64_t maps_evicted_ = 0;              // guarded by mutex_
};

}  // namespace lmd::server
