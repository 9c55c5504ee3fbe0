#include "bench/bench/load_bench.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <random>
#include <thread>
#include <vector>

#include "bench/bench/reobserve.h"
#include "bench/common/flags.h"
#include "client/lmd_client.h"
#include "core/eval/ground_truth.h"
#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/odometry_drift.h"
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
  bool fleet = false;  // --mode fleet: robots track with priors (else every query is global)
};

bool ParseLoadOptions(int argc, char** argv, LoadOptions* options) {
  Flags flags({"server", "collection", "token", "log", "mode", "robots", "first-robot", "hz", "seconds"},
              {"json", "no-seed"});
  uint64_t robots = 0, first_robot = 0;
  if (!flags.Parse(argc, argv) || !flags.Count("robots", 1, 5000, static_cast<uint64_t>(options->robots), &robots) ||
      !flags.Count("first-robot", 0, 100000, static_cast<uint64_t>(options->first_robot), &first_robot) ||
      !flags.Number("hz", 1e-6, 100, options->hz, &options->hz) ||
      !flags.Number("seconds", 1e-6, 3600, options->seconds, &options->seconds)) {
    std::fprintf(stderr, "lmd-bench load: %s\n", flags.error().c_str());
    return false;
  }
  const std::string mode = flags.Get("mode", options->fleet ? "fleet" : "global");
  if (mode != "fleet" && mode != "global") {
    std::fprintf(stderr, "lmd-bench load: --mode is global or fleet, got '%s'\n", mode.c_str());
    return false;
  }
  options->robots = static_cast<int>(robots);
  options->first_robot = static_cast<int>(first_robot);
  options->fleet = mode == "fleet";
  options->server = flags.Get("server", options->server);
  options->collection = flags.Get("collection", options->collection);
  options->token = flags.Get("token", options->token);
  options->log = flags.Get("log", options->log);
  options->json = flags.Has("json");
  options->seed = !flags.Has("no-seed");
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

// Robot 0's run through the demo world, and each robot's own route through
// it, as long as the run: a route repeated from its start would teleport the
// robot (its odometry cannot know) and have it send the very map it stored a
// lap before.
World SimulatedWorld(const LoadOptions& options, size_t ticks) {
  World world;
  world.seed = SimulateLocalMaps(DefaultDemoOptions());
  ProgressBar progress("load: simulating robots", options.robots);
  for (int r = 0; r < options.robots; ++r) {
    SimulationOptions sim = DefaultDemoOptions();
    sim.route.seed = 1000 + options.first_robot + r;
    sim.route.length_m = static_cast<double>(ticks) + 6.0;
    std::vector<LocalMap> maps = SimulateLocalMaps(sim);
    if (maps.size() > ticks) maps.resize(ticks);
    world.robots.push_back(std::move(maps));
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

// A robot of --mode fleet: it starts where it knows it is (a dock: its
// first map's true pose) and tracks with priors from its last fix and its
// drifting odometry. An answer lmdd is not sure of, or a failed prior (where
// no stored map shows its place, every prior fails), leaves it on odometry
// from its last fix, the prior growing with the travel since; once that
// drift passes kMaxPriorRadiusM it is lost and asks with a sequence (its
// maps 3 and 6 ticks back) until lmdd is sure again. Becoming lost at the
// first unsure answer instead (and asking for a global answer with each
// prior) gave 0.79 right fixes at 30 robots against 0.96, with 30 % of the
// answers costly sequence queries.
struct FleetRobot {
  std::mt19937_64 rng;
  bool lost = false;
  Pose2 fix;          // its last sure pose in the site frame
  size_t fixed_at = 0;  // ... the tick of that map
  // Outcomes, over its answered DetectChanges.
  size_t asked = 0, right = 0, sure = 0, sure_wrong = 0, sure_unposed = 0, by_prior = 0, by_sequence = 0,
         prior_failed = 0;
  // Sure and wrong, by how it was asked, and those off by less than 1 m
  // (the right place at a slightly wrong pose).
  size_t wrong_by_prior = 0, wrong_by_sequence = 0, wrong_within_1m = 0;
  // Each answered tick, whether its pose was right and its prior failed
  // (whether a seeded map shows the place is scored after the run).
  struct Answer {
    size_t tick = 0;
    bool right = false, prior_failed = false;
  };
  std::vector<Answer> answers;
};

constexpr size_t kSequenceStepTicks = 3;
constexpr double kMaxPriorRadiusM = 5.0;  // about 30 m of travel at OdometryDrift's defaults

void AskAsTracked(const std::vector<LocalMap>& maps, size_t t, FleetRobot* robot, v1::DetectChangesRequest* request) {
  const OdometryDrift drift;
  const LocalMap& now = maps[t];
  if (!robot->lost) {
    const LocalMap& then = maps[robot->fixed_at];
    const double travel = now.truth.travel_start - then.truth.travel_start;
    const Pose2 odometry = DriftedOdometry(then.truth.global_frame, now.truth.global_frame, travel, drift, robot->rng);
    v1::Prior* prior = request->mutable_prior();
    *prior->mutable_pose() = ToProto(Compose(robot->fix, Inverse(odometry)));
    prior->set_radius_m(DriftRadius(travel, drift));
    prior->set_heading_sigma_rad(2 * M_PI / 180 + drift.heading_rad_per_m * std::abs(travel));
    prior->set_fall_back_to_global(false);
    return;
  }
  for (size_t k = 1; k <= 2 && t >= k * kSequenceStepTicks; ++k) {
    const LocalMap& before = maps[t - k * kSequenceStepTicks];
    const double travel = now.truth.travel_start - before.truth.travel_start;
    v1::SequenceMap* earlier = request->add_sequence();
    *earlier->mutable_map() = ToProto(before);
    *earlier->mutable_in_query() =
        ToProto(DriftedOdometry(before.truth.global_frame, now.truth.global_frame, travel, drift, robot->rng));
    earlier->set_travel_m(std::abs(travel));
  }
}

// Scores the answer against the truth (the site frame is the world's) and
// updates the robot's state.
void Track(const std::vector<LocalMap>& maps, size_t t, const v1::DetectChangesResponse& response, FleetRobot* robot) {
  const LocalMap& map = maps[t];
  const v1::Localization& verdict = response.localization();
  ++robot->asked;
  robot->by_prior += verdict.prior_used();
  robot->prior_failed += verdict.prior_failed();
  robot->by_sequence += verdict.sequence_maps() > 0;
  const bool posed = verdict.has_collection_pose();
  const Pose2 got = posed ? FromProto(verdict.collection_pose()) : Pose2{};
  const Pose2& truth = map.truth.global_frame;
  const bool right = posed && std::hypot(got.x - truth.x, got.y - truth.y) <= 0.2 &&
                     std::abs(std::remainder(got.theta - truth.theta, 2 * M_PI)) <= M_PI / 180;
  robot->right += right;
  robot->answers.push_back({t, right, verdict.prior_failed()});
  robot->sure += verdict.localized();
  const bool sure_wrong = verdict.localized() && posed && !right;
  robot->sure_wrong += sure_wrong;
  robot->wrong_by_prior += sure_wrong && verdict.prior_used();
  robot->wrong_by_sequence += sure_wrong && verdict.sequence_maps() > 0;
  robot->wrong_within_1m += sure_wrong && std::hypot(got.x - truth.x, got.y - truth.y) < 1.0;
  robot->sure_unposed += verdict.localized() && !posed;  // no returned hit that agrees with the top one is anchored
  if (verdict.localized() && posed) {
    robot->lost = false, robot->fix = got, robot->fixed_at = t;
  } else if (!robot->lost) {
    const double travel = map.truth.travel_start - maps[robot->fixed_at].truth.travel_start;
    robot->lost = DriftRadius(travel, OdometryDrift{}) > kMaxPriorRadiusM;
  }
}

// Whether a seeded map shows a place (PlaceOverlap >= 0.5), among the seeds
// that start within 20 m of it. The seeds are gridded once, as every answer
// of a run is scored.
class SeededPlaces {
 public:
  explicit SeededPlaces(const std::vector<LocalMap>& seed) {
    for (const LocalMap& s : seed) places_.push_back({s.truth.global_frame, PlaceOf(s)});
  }
  bool Shows(const LocalMap& map) const {
    const Pose2& at = map.truth.global_frame;
    for (const auto& [origin, place] : places_) {
      if (std::hypot(origin.x - at.x, origin.y - at.y) < 20.0 && place.Overlap(map) >= 0.5) return true;
    }
    return false;
  }

 private:
  std::vector<std::pair<Pose2, PlaceOf>> places_;
};

void PrintFleet(const std::vector<FleetRobot>& fleet, const std::vector<LocalMap>& seed,
                const std::vector<std::vector<LocalMap>>& robot_maps) {
  FleetRobot all;
  const SeededPlaces seeded(seed);
  // Answers where a seeded map shows the place: all, right, failed priors.
  size_t at_seeded = 0, right_seeded = 0, failed_seeded = 0;
  for (size_t i = 0; i < fleet.size(); ++i) {
    const FleetRobot& r = fleet[i];
    all.asked += r.asked, all.right += r.right, all.sure += r.sure, all.sure_wrong += r.sure_wrong;
    all.sure_unposed += r.sure_unposed;
    all.wrong_by_prior += r.wrong_by_prior, all.wrong_by_sequence += r.wrong_by_sequence;
    all.wrong_within_1m += r.wrong_within_1m;
    all.by_prior += r.by_prior, all.by_sequence += r.by_sequence, all.prior_failed += r.prior_failed;
    for (const FleetRobot::Answer& a : r.answers) {
      if (!seeded.Shows(robot_maps[i][a.tick])) continue;
      ++at_seeded, right_seeded += a.right, failed_seeded += a.prior_failed;
    }
  }
  const double n = std::max<double>(1.0, static_cast<double>(all.asked));
  std::printf("fleet: %zu answers, right fixes %zu (%.3f; place and pose within 0.2 m / 1 deg; at places a seeded map "
              "shows %zu of %zu, %.3f), sure %zu (%.3f), "
              "sure and wrong %zu (by prior %zu, by sequence %zu; %zu off by less than 1 m), sure without a site pose "
              "%zu; by prior %zu (of them failed %zu, %zu at a place a seeded map shows), by sequence %zu, global %zu\n",
              all.asked, all.right, all.right / n, right_seeded, at_seeded,
              static_cast<double>(right_seeded) / std::max<size_t>(1, at_seeded), all.sure, all.sure / n,
              all.sure_wrong, all.wrong_by_prior, all.wrong_by_sequence, all.wrong_within_1m, all.sure_unposed,
              all.by_prior, all.prior_failed, failed_seeded, all.by_sequence,
              all.asked - all.by_prior - all.by_sequence);
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
        // The seeded run is a site map: anchored by its (true) poses.
        v1::InsertMapRequest* insert = request.add_maps();
        *insert = ToInsert(options.collection, "seed", k, base[k]);
        *insert->mutable_metadata()->mutable_pose_hint() = ToProto(base[k].truth.global_frame);
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
  std::vector<FleetRobot> fleet(options.robots);
  for (int r = 0; r < options.robots; ++r) {
    fleet[r].rng.seed(0x5EED0000ULL + static_cast<uint64_t>(options.first_robot + r));
    if (!robot_maps[r].empty()) fleet[r].fix = robot_maps[r][0].truth.global_frame;
  }
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
        auto insert = [&] {
          v1::InsertMapsRequest request;
          *request.add_maps() = map;
          v1::InsertMapsResponse response;
          return (*client)->InsertMaps(request, &response);
        };
        // Fleet robots ask first and store after: a sure answer then anchors
        // the map they store (lmdd derives it).
        if (!options.fleet) timed(insert);
        timed([&] {
          v1::DetectChangesRequest request;
          request.set_collection(options.collection);
          *request.mutable_map() = map.map();
          request.set_top_k(5);
          // The robot asks about stored maps other than the one it just sent.
          request.add_exclude_map_ids(map.metadata().map_id());
          if (options.fleet) AskAsTracked(robot_maps[r], t, &fleet[r], &request);
          v1::DetectChangesResponse response;
          const grpc::Status status = (*client)->DetectChanges(request, &response);
          if (status.ok() && response.hits_size() > 0) top_hits[r][t] = response.hits(0).hit().map_id();
          if (status.ok() && options.fleet) Track(robot_maps[r], t, response, &fleet[r]);
          detects_ok += status.ok();
          reduced += status.ok() && response.reduced_depth();
          return status;
        });
        if (options.fleet) timed(insert);
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
  if (options.fleet) PrintFleet(fleet, base, robot_maps);
  if (options.json) {
    std::printf("{\"robots\": %d, \"rps\": %.2f, \"p50_ms\": %.3f, \"p95_ms\": %.3f, \"p99_ms\": %.3f, \"errors\": %ld, "
                "\"place_at_1\": %.4f, \"reduced_depth\": %.4f}\n",
                options.robots, rps, p50, p95, p99, errors.load(), place_at_1, reduced_share);
  }
  return errors.load() == 0 ? 0 : 1;
}

}  // namespace lmd::bench
