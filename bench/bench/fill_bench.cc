#include "bench/bench/fill_bench.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "client/lmd_client.h"
#include "core/sim/simulate.h"
#include "core/util/progress_bar.h"
#include "proto/convert.h"

namespace lmd::bench {

int RunFillBench(int argc, char** argv) {
  std::string server = "127.0.0.1:50051", collection = "fill", token;
  long maps = 0;
  long batch_size = 100;
  bool scans = false;
  for (int i = 0; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--scans") { scans = true; continue; }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "lmd-bench fill: %s needs a value\n", flag.c_str());
      return 2;
    }
    const std::string value = argv[++i];
    if (flag == "--server") server = value;
    else if (flag == "--collection") collection = value;
    else if (flag == "--token") token = value;
    else if (flag == "--maps") maps = std::strtol(value.c_str(), nullptr, 10);
    else if (flag == "--batch") batch_size = std::strtol(value.c_str(), nullptr, 10);
    else {
      std::fprintf(stderr, "lmd-bench fill: unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  if (maps <= 0 || batch_size <= 0) {
    std::fprintf(stderr, "lmd-bench fill: --maps and --batch must be positive numbers\n");
    return 2;
  }
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
    return batch.maps_size() < batch_size || flush();
  });
  if (!flush()) {
    std::fprintf(stderr, "lmd-bench fill: insert failed: %s\n", error.c_str());
    return 1;
  }
  progress.Done();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("stored %ld maps in '%s' in %.1f s (%.0f maps/s, %.0f calls/s of %ld maps)\n", maps,
              collection.c_str(), seconds, maps / seconds, maps / seconds / batch_size, batch_size);
  return 0;
}

}  // namespace lmd::bench
