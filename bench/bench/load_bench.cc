#include "bench/bench/load_bench.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench/reobserve.h"
#include "client/lmd_client.h"
#include "core/eval/ground_truth.h"
#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/sim/simulate.h"
#include "core/util/progress_bar.h"
#include "proto/convert.h"

namespace lmd::bench {
namespace {

struct LoadOptions {
  std::string server = "127.0.0.1:50051";
  std::string collection = "load";
  std::string token;
  int robots = 10;
  int first_robot = 0;  // robots are first_robot .. first_robot + robots - 1 (several generators, one lmdd)
  double hz = 1.0;
  double seconds = 10.0;
  bool json = false;
  bool seed = true;
  std::string log;  // a CARMEN log instead of the simulated world
};

bool ParseLoadOptions(int argc, char** argv, LoadOptions* options) {
  for (int i = 0; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--json") { options->json = true; continue; }
    if (flag == "--no-seed") { options->seed = false; continue; }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "lmd-bench load: %s needs a value\n", flag.c_str());
      return false;
    }
    const std::string value = argv[++i];
    char* end = nullptr;
    if (flag == "--server") options->server = value;
    else if (flag == "--collection") options->collection = value;
    else if (flag == "--token") options->token = value;
    else if (flag == "--log") options->log = value;
    else if (flag == "--robots") options->robots = static_cast<int>(std::strtol(value.c_str(), &end, 10));
    else if (flag == "--first-robot") options->first_robot = static_cast<int>(std::strtol(value.c_str(), &end, 10));
    else if (flag == "--hz") options->hz = std::strtod(value.c_str(), &end);
    else if (flag == "--seconds") options->seconds = std::strtod(value.c_str(), &end);
    else {
      std::fprintf(stderr, "lmd-bench load: unknown flag %s\n", flag.c_str());
      return false;
    }
    if (end != nullptr && *end != '\0') {
      std::fprintf(stderr, "lmd-bench load: %s expects a number, got '%s'\n", flag.c_str(), value.c_str());
      return false;
    }
  }
  if (options->robots < 1 || options->robots > 5000 || options->first_robot < 0 || options->first_robot > 100000 ||
      !(options->hz > 0) || options->hz > 100 || !(options->seconds > 0) || options->seconds > 3600) {
    std::fprintf(stderr,
                 "lmd-bench load: need 1 <= robots <= 5000, 0 <= first-robot <= 100000, 0 < hz <= 100, "
                 "0 < seconds <= 3600\n");
    return false;
  }
  return true;
}

v1::InsertMapRequest ToInsert(const std::string& collection, const std::string& robot, uint64_t sequence,
                              const LocalMap& map) {
  v1::InsertMapRequest insert;
  insert.mutable_metadata()->set_collection(collection);
  insert.mutable_metadata()->set_map_id(robot + "-" + std::to_string(sequence));
  insert.mutable_metadata()->set_robot_id(robot);
  insert.mutable_metadata()->set_sequence(sequence);
  *insert.mutable_map() = ToProto(map);
  return insert;
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

// The simulated map a load-run id names: "seed-K" (the seeded run) or
// "robotR-T" (robot R's map of tick T, R counted from first_robot); nullptr
// for any other id, including robots of another generator.
const LocalMap* MapOfId(const std::string& id, const std::vector<LocalMap>& seed,
                        const std::vector<std::vector<LocalMap>>& robot_maps, int first_robot) {
  const size_t dash = id.rfind('-');
  if (dash == std::string::npos) return nullptr;
  const std::string owner = id.substr(0, dash);
  const size_t k = std::strtoul(id.c_str() + dash + 1, nullptr, 10);
  if (owner == "seed") return k < seed.size() ? &seed[k] : nullptr;
  if (owner.rfind("robot", 0) != 0) return nullptr;
  const long robot = std::strtol(owner.c_str() + 5, nullptr, 10) - first_robot;
  if (robot < 0 || static_cast<size_t>(robot) >= robot_maps.size()) return nullptr;
  const size_t r = static_cast<size_t>(robot);
  return k < robot_maps[r].size() ? &robot_maps[r][k] : nullptr;
}

// The stored world (seeded) and each robot's maps, one per tick.
struct World {
  std::vector<LocalMap> seed;
  std::vector<std::vector<LocalMap>> robots;
};

// Robot 0's run through the demo world, and each robot's own route through it
// (repeated if the route is short).
World SimulatedWorld(const LoadOptions& options, size_t ticks) {
  World world;
  world.seed = SimulateLocalMaps(DefaultDemoOptions());
  ProgressBar progress("load: simulating robots", options.robots);
  for (int r = 0; r < options.robots; ++r) {
    SimulationOptions sim = DefaultDemoOptions();
    sim.route.seed = 1000 + options.first_robot + r;
    sim.route.length_m = std::min<double>(static_cast<double>(ticks) + 6.0, 60.0);
    const std::vector<LocalMap> maps = SimulateLocalMaps(sim);
    world.robots.emplace_back();
    for (size_t t = 0; t < ticks && !maps.empty(); ++t) world.robots.back().push_back(maps[t % maps.size()]);
    progress.Add();
  }
  return world;
}

// A real log's local maps (1 m apart): the even ones are stored, and the
// robots drive the log again through the odd ones, each from its own start
// (spread over the log) and each seeing them anew (Reobserve: another own
// frame, 2 cm noise, 10 % of points dropped; two robots never send the same
// map), as when robots return to a mapped building.
Result<World> LogWorld(const LoadOptions& options, size_t ticks) {
  Result<LaserLog> log = ReadCarmenLog(options.log);
  if (!log.ok()) return log.status();
  const std::vector<LocalMap> maps = BuildLocalMaps(*log);
  World world;
  std::vector<LocalMap> odd;
  for (size_t i = 0; i < maps.size(); ++i) (i % 2 == 0 ? world.seed : odd).push_back(maps[i]);
  if (odd.empty()) return Status::InvalidArgument(options.log + " holds fewer than two local maps");
  for (int r = 0; r < options.robots; ++r) {
    const size_t start = odd.size() * static_cast<size_t>(options.first_robot + r) /
                         static_cast<size_t>(options.first_robot + options.robots);
    world.robots.emplace_back();
    for (size_t t = 0; t < ticks; ++t) {
      const uint64_t seed = (static_cast<uint64_t>(options.first_robot + r) << 32) | t;
      world.robots.back().push_back(Reobserve(odd[(start + t) % odd.size()], seed, 0.02, 0.1));
    }
  }
  return world;
}

}  // namespace

int RunLoadBench(int argc, char** argv) {
  LoadOptions options;
  if (!ParseLoadOptions(argc, argv, &options)) return 2;
  client::ClientOptions client_options;
  client_options.target = options.server;
  client_options.token = options.token;
  client_options.deadline = std::chrono::seconds(10);
  client_options.max_attempts = 1;  // a retry would hide the error being measured
  auto client = client::LmdClient::Create(client_options);
  if (!client.ok()) {
    std::fprintf(stderr, "lmd-bench load: %s\n", client.status().message().c_str());
    return 1;
  }

  const size_t ticks = static_cast<size_t>(std::ceil(options.hz * options.seconds));
  Result<World> world = options.log.empty() ? SimulatedWorld(options, ticks) : LogWorld(options, ticks);
  if (!world.ok()) {
    std::fprintf(stderr, "lmd-bench load: %s\n", world.status().message().c_str());
    return 1;
  }
  const std::vector<LocalMap>& base = world->seed;
  const std::vector<std::vector<LocalMap>>& robot_maps = world->robots;
  if (options.seed) {
    ProgressBar progress("load: seeding " + options.collection, base.size());
    for (size_t i = 0; i < base.size(); i += 25) {
      v1::InsertMapsRequest request;
      for (size_t k = i; k < std::min(base.size(), i + 25); ++k) {
        *request.add_maps() = ToInsert(options.collection, "seed", k, base[k]);
      }
      v1::InsertMapsResponse response;
      const grpc::Status status = (*client)->InsertMaps(request, &response);
      if (!status.ok()) {
        std::fprintf(stderr, "lmd-bench load: seeding failed: %s\n", status.error_message().c_str());
        return 1;
      }
      progress.Add(static_cast<size_t>(request.maps_size()));
    }
  }
  std::vector<std::vector<v1::InsertMapRequest>> plans(options.robots);
  for (int r = 0; r < options.robots; ++r) {
    const std::string robot = "robot" + std::to_string(options.first_robot + r);
    for (size_t t = 0; t < robot_maps[r].size(); ++t) {
      plans[r].push_back(ToInsert(options.collection, robot, t, robot_maps[r][t]));
    }
  }

  std::mutex mutex;
  std::vector<double> latencies_ms;  // guarded by mutex
  std::atomic<long> errors{0};
  std::atomic<long> calls{0};
  std::atomic<long> detects_ok{0};
  std::atomic<long> reduced{0};  // of those, answered at lmdd's busy depth
  std::string first_error;           // guarded by mutex
  // Per robot and tick, the top hit of its DetectChanges ("" if none).
  std::vector<std::vector<std::string>> top_hits(options.robots);
  for (int r = 0; r < options.robots; ++r) top_hits[r].resize(plans[r].size());
  const auto start = std::chrono::steady_clock::now();
  const auto period = std::chrono::duration<double>(1.0 / options.hz);
  std::vector<std::thread> robots;
  for (int r = 0; r < options.robots; ++r) {
    robots.emplace_back([&, r] {
      // Robots start spread over one period, as real robots would.
      const auto offset = period * (static_cast<double>(r) / options.robots);
      for (size_t t = 0; t < plans[r].size(); ++t) {
        std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                  offset + period * static_cast<double>(t)));
        const v1::InsertMapRequest& map = plans[r][t];
        auto timed = [&](auto&& call) {
          const auto t0 = std::chrono::steady_clock::now();
          const grpc::Status status = call();
          const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
          ++calls;
          std::lock_guard<std::mutex> lock(mutex);
          latencies_ms.push_back(ms);
          if (!status.ok()) {
            if (errors++ == 0) first_error = status.error_message();
          }
        };
        timed([&] {
          v1::InsertMapsRequest request;
          *request.add_maps() = map;
          v1::InsertMapsResponse response;
          return (*client)->InsertMaps(request, &response);
        });
        timed([&] {
          v1::DetectChangesRequest request;
          request.set_collection(options.collection);
          *request.mutable_map() = map.map();
          request.set_top_k(5);
          // The robot asks about stored maps other than the one it just sent.
          request.add_exclude_map_ids(map.metadata().map_id());
          v1::DetectChangesResponse response;
          const grpc::Status status = (*client)->DetectChanges(request, &response);
          if (status.ok() && response.hits_size() > 0) top_hits[r][t] = response.hits(0).hit().map_id();
          detects_ok += status.ok();
          reduced += status.ok() && response.reduced_depth();
          return status;
        });
      }
    });
  }
  for (auto& robot : robots) robot.join();
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Localisation: does the top hit show the query's place (the product's
  // criterion, core/eval: half of the query's points within 0.3 m of the
  // hit's, in the world frame)? Among DetectChanges answered with a hit.
  size_t answered = 0, localised = 0;
  for (int r = 0; r < options.robots; ++r) {
    for (size_t t = 0; t < top_hits[r].size(); ++t) {
      const LocalMap* hit = MapOfId(top_hits[r][t], base, robot_maps, options.first_robot);
      if (hit == nullptr) continue;
      ++answered;
      localised += PlaceOverlap(robot_maps[r][t], *hit) >= 0.5;
    }
  }
  const double place_at_1 = answered > 0 ? static_cast<double>(localised) / static_cast<double>(answered) : 0.0;

  const double rps = static_cast<double>(calls.load()) / elapsed;
  const double p50 = Percentile(latencies_ms, 0.50), p95 = Percentile(latencies_ms, 0.95);
  const double p99 = Percentile(latencies_ms, 0.99);
  std::printf("robots=%d hz=%.2f seconds=%.1f calls=%ld (insert + detect per tick) rps=%.1f\n", options.robots,
              options.hz, elapsed, calls.load(), rps);
  std::printf("latency p50=%.2f ms p95=%.2f ms p99=%.2f ms errors=%ld%s%s\n", p50, p95, p99, errors.load(),
              first_error.empty() ? "" : " first error: ", first_error.c_str());
  std::printf("localisation: the top hit shows the robot's place for %zu of %zu answered DetectChanges (%.3f)\n",
              localised, answered, place_at_1);
  const double reduced_share =
      detects_ok > 0 ? static_cast<double>(reduced.load()) / static_cast<double>(detects_ok.load()) : 0.0;
  std::printf("lmdd was busy and answered %ld of %ld DetectChanges at its reduced depth (%.3f)\n", reduced.load(),
              detects_ok.load(), reduced_share);
  if (options.json) {
    std::printf("{\"robots\": %d, \"rps\": %.2f, \"p50_ms\": %.3f, \"p95_ms\": %.3f, \"p99_ms\": %.3f, \"errors\": %ld, "
                "\"place_at_1\": %.4f, \"reduced_depth\": %.4f}\n",
                options.robots, rps, p50, p95, p99, errors.load(), place_at_1, reduced_share);
  }
  return errors.load() == 0 ? 0 : 1;
}

}  // namespace lmd::bench
