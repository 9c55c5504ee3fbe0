#include "bench/bench/writes_bench.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "bench/common/flags.h"
#include "core/sim/simulate.h"
#include "core/util/split.h"
#include "lmd/v1/lmd.grpc.pb.h"
#include "proto/convert.h"

namespace lmd::bench {
namespace {

using Clock = std::chrono::steady_clock;

std::unique_ptr<v1::LmdService::Stub> StubFor(const std::string& address) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  return v1::LmdService::NewStub(grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args));
}

int Write(const std::vector<std::string>& servers, const std::string& collection, double rate, double seconds,
          const std::string& acked_path) {
  std::ofstream acked(acked_path, std::ios::app);
  if (!acked) {
    std::fprintf(stderr, "lmd-bench writes: cannot write %s\n", acked_path.c_str());
    return 1;
  }
  std::vector<std::unique_ptr<v1::LmdService::Stub>> stubs;
  for (const std::string& s : servers) stubs.push_back(StubFor(s));
  SimulationOptions sim;
  sim.num_maps = std::max<size_t>(1, static_cast<size_t>(rate * seconds));
  sim.local_map.id_prefix = "w";
  std::vector<LocalMap> maps;
  SimulateLocalMapsStreaming(sim, [&](LocalMap&& map) {
    maps.push_back(std::move(map));
    return true;
  });
  size_t server = 0, failures = 0, count = 0;
  double longest_gap_s = 0;
  const auto start = Clock::now();
  auto last_ack = start;
  for (size_t i = 0; i < maps.size(); ++i) {
    std::this_thread::sleep_until(start + std::chrono::microseconds(static_cast<int64_t>(i * 1e6 / rate)));
    // lmdd assigns the id; the request id makes the retries below safe, and
    // the write's number (as the map's sequence) lets --verify find a map
    // stored twice under two ids.
    char id[32];
    std::snprintf(id, sizeof id, "w%08zu", i);
    v1::InsertMapsRequest request;
    request.set_request_id(id);
    v1::InsertMapRequest* insert = request.add_maps();
    insert->mutable_metadata()->set_collection(collection);
    insert->mutable_metadata()->set_robot_id("lmd-bench-writes");
    insert->mutable_metadata()->set_sequence(i + 1);
    *insert->mutable_map() = ToProto(maps[i]);
    v1::InsertMapsResponse response;
    for (;;) {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(3));
      response.Clear();
      const grpc::Status status = stubs[server]->InsertMaps(&context, request, &response);
      if (status.ok() && response.maps_size() == 1) break;
      ++failures;
      if (failures <= 20 || failures % 50 == 0) {
        std::fprintf(stderr, "write %s to %s: %s\n", id, servers[server].c_str(), status.error_message().c_str());
      }
      server = (server + 1) % servers.size();
      if (Clock::now() - last_ack > std::chrono::seconds(60)) {
        std::fprintf(stderr, "lmd-bench writes: nothing acknowledged for 60 s; giving up\n");
        return 1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    const auto now = Clock::now();
    longest_gap_s = std::max(longest_gap_s, std::chrono::duration<double>(now - last_ack).count());
    last_ack = now;
    acked << response.maps(0).map_id() << ' ' << i + 1 << '\n' << std::flush;
    ++count;
  }
  const double took = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf("acknowledged %zu writes in %.1f s (%.0f/s), %zu failed attempts, longest gap %.2f s\n", count, took,
              count / took, failures, longest_gap_s);
  return 0;
}

int Verify(const std::vector<std::string>& servers, const std::string& collection, const std::string& acked_path,
           size_t copies_needed) {
  std::ifstream in(acked_path);
  std::map<std::string, uint64_t> acked;  // map id -> write number
  std::string id;
  for (uint64_t number = 0; in >> id >> number;) acked[id] = number;
  size_t complete = 0;
  for (const std::string& address : servers) {
    std::unique_ptr<v1::LmdService::Stub> stub = StubFor(address);
    std::map<std::string, uint64_t> held;  // map id -> write number
    std::string page;
    bool ok = true;
    for (;;) {
      grpc::ClientContext context;
      context.AddMetadata("lmd-local", "1");
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
      v1::ListMapsRequest request;
      request.set_collection(collection);
      request.set_page_token(page);
      request.set_page_size(1000);
      v1::ListMapsResponse response;
      const grpc::Status status = stub->ListMaps(&context, request, &response);
      if (!status.ok()) {
        std::printf("%s: cannot list: %s\n", address.c_str(), status.error_message().c_str());
        ok = false;
        break;
      }
      for (const v1::MapMetadata& m : response.maps()) held[m.map_id()] = m.sequence();
      if (response.next_page_token().empty()) break;
      page = response.next_page_token();
    }
    if (!ok) continue;
    // Missing: an acknowledged id not held as that write; duplicated: a write
    // held under more than one id (a retry stored twice).
    size_t missing = 0, duplicates = 0;
    for (const auto& [map_id, number] : acked) {
      const auto it = held.find(map_id);
      missing += it == held.end() || it->second != number;
    }
    std::map<uint64_t, int> copies_of;
    for (const auto& [map_id, number] : held) duplicates += ++copies_of[number] == 2;
    std::printf("%s: holds %zu maps; %zu of %zu acknowledged missing, %zu duplicated\n", address.c_str(), held.size(),
                missing, acked.size(), duplicates);
    complete += missing == 0 && duplicates == 0;
  }
  const bool pass = complete >= copies_needed;
  std::printf("%s: %zu copies hold every acknowledged write (%zu needed)\n", pass ? "PASS" : "FAIL", complete,
              copies_needed);
  return pass ? 0 : 1;
}

}  // namespace

int RunWritesBench(int argc, char** argv) {
  Flags flags({"servers", "collection", "acked", "rate", "seconds", "copies"}, {"verify"});
  double rate = 100, seconds = 10;
  uint64_t copies = 0;
  if (!flags.Parse(argc, argv) || !flags.Number("rate", 1e-3, 1e6, 100, &rate) ||
      !flags.Number("seconds", 1e-3, 86400, 10, &seconds) || !flags.Count("copies", 1, 9, 1, &copies)) {
    std::fprintf(stderr, "lmd-bench writes: %s\n", flags.error().c_str());
    return 2;
  }
  const std::vector<std::string> servers = SplitCommas(flags.Get("servers"));
  const std::string collection = flags.Get("collection", "replicated"), acked = flags.Get("acked");
  const bool verify = flags.Has("verify");
  if (servers.empty() || acked.empty()) {
    std::fprintf(stderr, "lmd-bench writes: needs --servers and --acked\n");
    return 2;
  }
  if (verify) return Verify(servers, collection, acked, flags.Has("copies") ? static_cast<size_t>(copies) : servers.size());
  return Write(servers, collection, rate, seconds, acked);
}

}  // namespace lmd::bench
