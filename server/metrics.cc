#include "server/metrics.h"

#include <ctime>

#include <cmath>
#include <sstream>

namespace lmd::server {
namespace {

const char* CodeName(int code) {
  static const char* const kNames[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
                                       "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED",
                                       "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED",
                                       "INTERNAL", "UNAVAILABLE", "DATA_LOSS", "UNAUTHENTICATED"};
  return code >= 0 && code <= 16 ? kNames[code] : "UNKNOWN";
}

// Bounds of the Prometheus histogram, seconds.
constexpr double kPrometheusBoundsS[] = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05,
                                         0.1,    0.25,  0.5,    1.0,   2.5,  5.0,   10.0};

}  // namespace

double CallMetrics::BucketBoundMs(int i) { return kFirstBoundMs * std::pow(1.1, i); }

void CallMetrics::Record(const std::string& method, int code, double latency_ms) {
  int bucket = latency_ms <= kFirstBoundMs ? 0 : static_cast<int>(std::ceil(std::log(latency_ms / kFirstBoundMs) / std::log(1.1)));
  if (bucket >= kBuckets) bucket = kBuckets - 1;
  std::lock_guard<std::mutex> lock(mutex_);
  Method& m = methods_[method];
  ++m.calls;
  ++m.by_code[code];
  m.total_ms += latency_ms;
  ++m.buckets[bucket];
}

double CallMetrics::Percentile(const Method& method, double q) {
  const double wanted = q * static_cast<double>(method.calls);
  uint64_t seen = 0;
  for (int i = 0; i < kBuckets; ++i) {
    seen += method.buckets[i];
    if (static_cast<double>(seen) >= wanted && seen > 0) return BucketBoundMs(i);
  }
  return 0.0;
}

std::vector<v1::MethodStats> CallMetrics::Snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<v1::MethodStats> out;
  for (const auto& [name, m] : methods_) {
    v1::MethodStats stats;
    stats.set_method(name);
    stats.set_calls(m.calls);
    const auto ok = m.by_code.find(0);
    stats.set_errors(m.calls - (ok == m.by_code.end() ? 0 : ok->second));
    stats.set_p50_ms(Percentile(m, 0.50));
    stats.set_p95_ms(Percentile(m, 0.95));
    stats.set_p99_ms(Percentile(m, 0.99));
    out.push_back(std::move(stats));
  }
  return out;
}

double ProcessCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

void CallMetrics::RecordQueryWork(uint64_t features_compared, uint64_t maps_matched, bool reduced_depth) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++work_.queries;
  work_.features_compared += features_compared;
  work_.maps_matched += maps_matched;
  work_.reduced_depth += reduced_depth;
}

void CallMetrics::RecordAnswer(const Verdict& verdict) {
  const char* asked = verdict.sequence_maps > 0 ? "sequence" : verdict.prior_used ? "prior" : "global";
  std::lock_guard<std::mutex> lock(mutex_);
  ++answers_[{asked, verdict.sure ? "sure" : "unsure"}];
  priors_failed_ += verdict.prior_failed;
}

void CallMetrics::RecordEvicted(uint64_t maps) {
  if (maps == 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  maps_evicted_ += maps;
}

std::string CallMetrics::PrometheusText(const std::vector<v1::CollectionInfo>& collections, double uptime_s,
                                        const PreparedCache& prepared, double cpu_seconds) const {
  std::ostringstream out;
  out << "# HELP lmd_uptime_seconds Seconds since lmdd started.\n# TYPE lmd_uptime_seconds gauge\n"
      << "lmd_uptime_seconds " << uptime_s << "\n";
  out << "# HELP process_cpu_seconds_total CPU time lmdd has used (user + system).\n"
      << "# TYPE process_cpu_seconds_total counter\nprocess_cpu_seconds_total " << cpu_seconds << "\n";
  out << "# HELP lmd_collection_maps Stored maps per collection.\n# TYPE lmd_collection_maps gauge\n";
  for (const auto& c : collections) out << "lmd_collection_maps{collection=\"" << c.name() << "\"} " << c.maps() << "\n";
  out << "# HELP lmd_collection_postings Index postings per collection.\n# TYPE lmd_collection_postings gauge\n";
  for (const auto& c : collections) {
    out << "lmd_collection_postings{collection=\"" << c.name() << "\"} " << c.postings() << "\n";
  }
  out << "# HELP lmd_collection_points Stored points per collection.\n# TYPE lmd_collection_points gauge\n";
  for (const auto& c : collections) out << "lmd_collection_points{collection=\"" << c.name() << "\"} " << c.points() << "\n";

  std::lock_guard<std::mutex> lock(mutex_);
  out << "# HELP lmd_calls_total Finished gRPC calls by method and status code.\n# TYPE lmd_calls_total counter\n";
  for (const auto& [name, m] : methods_) {
    for (const auto& [code, count] : m.by_code) {
      out << "lmd_calls_total{method=\"" << name << "\",code=\"" << CodeName(code) << "\"} " << count << "\n";
    }
  }
  out << "# HELP lmd_call_duration_seconds Latency of gRPC calls.\n# TYPE lmd_call_duration_seconds histogram\n";
  for (const auto& [name, m] : methods_) {
    for (double bound_s : kPrometheusBoundsS) {
      uint64_t count = 0;  // fine buckets wholly below the bound
      for (int i = 0; i < kBuckets && BucketBoundMs(i) <= bound_s * 1000.0 * (1 + 1e-9); ++i) count += m.buckets[i];
      out << "lmd_call_duration_seconds_bucket{method=\"" << name << "\",le=\"" << bound_s << "\"} " << count << "\n";
    }
    out << "lmd_call_duration_seconds_bucket{method=\"" << name << "\",le=\"+Inf\"} " << m.calls << "\n";
    out << "lmd_call_duration_seconds_sum{method=\"" << name << "\"} " << m.total_ms / 1000.0 << "\n";
    out << "lmd_call_duration_seconds_count{method=\"" << name << "\"} " << m.calls << "\n";
  }
  auto counter = [&](const char* name, const char* help, uint64_t value) {
    out << "# HELP " << name << " " << help << "\n# TYPE " << name << " counter\n" << name << " " << value << "\n";
  };
  counter("lmd_queries_total", "Default-method Retrieve and DetectChanges queries.", work_.queries);
  counter("lmd_query_features_compared_total", "Stored place features the first stage compared, summed over queries.",
          work_.features_compared);
  counter("lmd_query_maps_matched_total", "Stored maps scan matched, summed over queries.", work_.maps_matched);
  counter("lmd_maps_evicted_total", "Maps deleted to keep a collection within retain_maps_per_collection.",
          maps_evicted_);
  counter("lmd_queries_reduced_depth_total", "Queries answered at the busy depth because calls were waiting.",
          work_.reduced_depth);
  out << "# HELP lmd_answers_total Default-method queries answered, by what was asked (a prior, a sequence, "
         "or neither) and whether lmdd was sure.\n# TYPE lmd_answers_total counter\n";
  for (const auto& [key, count] : answers_) {
    out << "lmd_answers_total{asked=\"" << key.first << "\",verdict=\"" << key.second << "\"} " << count << "\n";
  }
  counter("lmd_priors_failed_total", "Prior queries that no map near the prior matched (answered globally on request).",
          priors_failed_);
  counter("lmd_maps_prepared_total", "Hits prepared for scan matching (misses of the prepared-map cache).",
          prepared.misses);
  out << "# HELP lmd_prepared_cache_bytes Bytes held by the prepared-map cache (prepared_map_cache_mb).\n"
      << "# TYPE lmd_prepared_cache_bytes gauge\nlmd_prepared_cache_bytes " << prepared.bytes << "\n";
  return out.str();
}

}  // namespace lmd::server
