#include "bench/bench/reads_bench.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench/common/flags.h"
#include "client/lmd_client.h"
#include "core/util/split.h"

namespace lmd::bench {
namespace {

using Clock = std::chrono::steady_clock;

// Up to `limit` stored maps of the collection, from `client`.
Result<std::vector<v1::StoredMap>> QueryMaps(const client::LmdClient& client, const std::string& collection,
                                             uint32_t limit) {
  v1::ListMapsRequest list;
  list.set_collection(collection);
  list.set_page_size(limit);
  v1::ListMapsResponse listed;
  const grpc::Status status = client.ListMaps(list, &listed);
  if (!status.ok()) return Status::Unavailable("listing " + collection + ": " + status.error_message());
  std::vector<v1::StoredMap> maps;
  for (const v1::MapMetadata& meta : listed.maps()) {
    v1::GetMapRequest get;
    get.set_collection(collection);
    get.set_map_id(meta.map_id());
    v1::GetMapResponse got;
    const grpc::Status read = client.GetMap(get, &got);
    if (!read.ok()) return Status::Unavailable("reading " + meta.map_id() + ": " + read.error_message());
    maps.push_back(std::move(*got.mutable_map()));
  }
  if (maps.empty()) return Status::NotFound("collection " + collection + " holds no maps");
  return maps;
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())))];
}

}  // namespace

int RunReadsBench(int argc, char** argv) {
  Flags flags({"servers", "collection", "threads", "seconds"});
  uint64_t thread_count = 4;
  double seconds = 10;
  if (!flags.Parse(argc, argv) || !flags.Count("threads", 1, 1024, 4, &thread_count) ||
      !flags.Number("seconds", 1e-3, 86400, 10, &seconds)) {
    std::fprintf(stderr, "lmd-bench reads: %s\n", flags.error().c_str());
    return 2;
  }
  const long threads = static_cast<long>(thread_count);
  const std::vector<std::string> servers = SplitCommas(flags.Get("servers"));
  const std::string collection = flags.Get("collection");
  if (servers.empty() || collection.empty()) {
    std::fprintf(stderr, "lmd-bench reads: needs --servers and --collection\n");
    return 2;
  }
  std::vector<std::unique_ptr<client::LmdClient>> clients;
  for (const std::string& address : servers) {
    client::ClientOptions options;
    options.target = address;
    options.max_attempts = 1;  // an error is counted, not hidden by a retry
    Result<std::unique_ptr<client::LmdClient>> made = client::LmdClient::Create(options);
    if (!made.ok()) {
      std::fprintf(stderr, "lmd-bench reads: %s\n", made.status().message().c_str());
      return 1;
    }
    clients.push_back(std::move(made).value());
  }
  Result<std::vector<v1::StoredMap>> maps = QueryMaps(*clients.front(), collection, 100);
  if (!maps.ok()) {
    std::fprintf(stderr, "lmd-bench reads: %s\n", maps.status().message().c_str());
    return 1;
  }
  std::vector<v1::RetrieveRequest> queries;
  for (const v1::StoredMap& map : *maps) {
    v1::RetrieveRequest query;
    query.set_collection(collection);
    *query.mutable_map() = map.map();
    query.set_top_k(5);
    query.add_exclude_map_ids(map.metadata().map_id());
    queries.push_back(std::move(query));
  }
  std::atomic<size_t> errors{0};
  std::vector<std::vector<double>> latencies(static_cast<size_t>(threads));
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  const auto start = Clock::now();
  std::vector<std::thread> workers;
  for (long t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      for (size_t k = static_cast<size_t>(t); Clock::now() < end; ++k) {
        const auto sent = Clock::now();
        v1::RetrieveResponse answer;
        const grpc::Status status = clients[k % clients.size()]->Retrieve(queries[k % queries.size()], &answer);
        if (!status.ok()) {
          ++errors;
          continue;
        }
        latencies[static_cast<size_t>(t)].push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
      }
    });
  }
  for (std::thread& w : workers) w.join();
  const double took = std::chrono::duration<double>(Clock::now() - start).count();
  std::vector<double> all;
  for (const auto& l : latencies) all.insert(all.end(), l.begin(), l.end());
  std::printf("%zu queries in %.1f s (%.1f queries/s) over %zu servers, %ld threads: p50 %.1f ms, p99 %.1f ms, %zu errors\n",
              all.size(), took, static_cast<double>(all.size()) / took, servers.size(), threads,
              Percentile(all, 0.5), Percentile(all, 0.99), errors.load());
  return errors.load() == 0 ? 0 : 1;
}

}  // namespace lmd::bench
