#include "bench/bench/fill_bench.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/common/flags.h"
#include "client/lmd_client.h"
#include "core/sim/simulate.h"
#include "core/util/progress_bar.h"
#include "proto/convert.h"

namespace lmd::bench {

int RunFillBench(int argc, char** argv) {
  Flags flags({"server", "collection", "token", "maps", "batch"}, {"scans"});
  uint64_t maps = 0, batch_size = 0;
  if (!flags.Parse(argc, argv) || !flags.Count("maps", 1, 100000000, 0, &maps) ||
      !flags.Count("batch", 1, 100000, 100, &batch_size)) {
    std::fprintf(stderr, "lmd-bench fill: %s\n", flags.error().c_str());
    return 2;
  }
  if (!flags.Has("maps")) {
    std::fprintf(stderr, "lmd-bench fill: --maps is needed\n");
    return 2;
  }
  const std::string server = flags.Get("server", "127.0.0.1:50051"), collection = flags.Get("collection", "fill");
  const std::string token = flags.Get("token");
  const bool scans = flags.Has("scans");
  client::ClientOptions options;
  options.target = server;
  options.token = token;
  options.deadline = std::chrono::seconds(120);
  auto client = client::LmdClient::Create(options);
  if (!client.ok()) {
    std::fprintf(stderr, "lmd-bench fill: %s\n", client.status().message().c_str());
    return 1;
  }

  SimulationOptions sim;
  sim.num_maps = static_cast<size_t>(maps);
  sim.local_map.id_prefix = "fill";
  sim.local_map.keep_scans = scans;
  ProgressBar progress("fill " + collection, static_cast<size_t>(maps));
  v1::InsertMapsRequest batch;
  std::string error;
  auto flush = [&] {
    if (batch.maps_size() == 0) return true;
    v1::InsertMapsResponse response;
    const grpc::Status status = (*client)->InsertMaps(batch, &response);
    if (!status.ok()) {
      error = status.error_message();
      return false;
    }
    progress.Add(static_cast<size_t>(batch.maps_size()));
    batch.Clear();
    return true;
  };
  const auto start = std::chrono::steady_clock::now();
  SimulateLocalMapsStreaming(sim, [&](LocalMap&& map) {
    v1::InsertMapRequest* insert = batch.add_maps();
    insert->mutable_metadata()->set_collection(collection);
    insert->mutable_metadata()->set_map_id(map.id);
    *insert->mutable_map() = ToProto(map);
    return static_cast<uint64_t>(batch.maps_size()) < batch_size || flush();
  });
  if (!flush()) {
    std::fprintf(stderr, "lmd-bench fill: insert failed: %s\n", error.c_str());
    return 1;
  }
  progress.Done();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double stored = static_cast<double>(maps);
  std::printf("stored %.0f maps in '%s' in %.1f s (%.0f maps/s, %.0f calls/s of %.0f maps)\n", stored,
              collection.c_str(), seconds, stored / seconds, stored / seconds / static_cast<double>(batch_size),
              static_cast<double>(batch_size));
  return 0;
}

}  // namespace lmd::bench
