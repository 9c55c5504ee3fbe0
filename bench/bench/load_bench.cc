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
#include "bench/common/calibration.h"
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
  std::string answers;  // --answers FILE: one row per DetectChanges answer (TSV)
};

bool ParseLoadOptions(int argc, char** argv, LoadOptions* options) {
  Flags flags({"server", "collection", "token", "log", "mode", "robots", "first-robot", "hz", "seconds", "answers"},
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
  options->answers = flags.Get("answers", options->answers);
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

// One DetectChanges of a run, as answered: what lmd-bench load reports is
// counted from these, and --answers writes them out.
struct AnswerRow {
  bool answered = false;  // the call returned OK
  const char* asked = "global";  // global, prior or sequence
  double prior_radius_m = 0.0, latency_ms = 0.0;
  bool reduced_depth = false, localized = false, prior_failed = false, posed = false;
  int sequence_maps = 0;
  std::string top_hit;  // "" if none
  Pose2 got;  // the query's pose in the collection's frame, if posed
  bool right = false;  // posed within 0.2 m / 1 deg of the truth (the site frame is the world's)
  double confidence = 0.0;  // Localization.confidence
};

// A robot of --mode fleet: it starts where it knows it is (a dock: its
// first map's true pose) and tracks with priors from its last fix and its
// drifting odometry. An answer lmdd is not sure of, or a failed prior (where
// no stored map shows its place, every prior fails), leaves it on odometry
// from its last fix, the prior growing with the travel since; once that
// drift passes kMaxPriorRadiusM it is lost and asks with a sequence (its
// maps 3 and 6 ticks back; none just after a kidnap, SamePass: a global
// query) until lmdd is sure again. Becoming lost at the
// first unsure answer instead (and asking for a global answer with each
// prior) gave 0.79 right fixes at 30 robots against 0.96, with 30 % of the
// answers costly sequence queries.
struct FleetRobot {
  std::mt19937_64 rng;
  bool lost = false;
  Pose2 fix;          // its last sure pose in the site frame
  size_t fixed_at = 0;  // ... the tick of that map
};

constexpr size_t kSequenceStepTicks = 3;
constexpr double kMaxPriorRadiusM = 5.0;  // about 30 m of travel at OdometryDrift's defaults

// Whether the robot drove from `before` to `now`. A robot of a log world
// that reaches the log's end goes on from its start: a kidnap, across which
// its odometry says nothing (it gave priors of a kilometre, refused).
bool SamePass(const LocalMap& before, const LocalMap& now) {
  return before.truth.travel_start <= now.truth.travel_start;
}

void AskAsTracked(const std::vector<LocalMap>& maps, size_t t, FleetRobot* robot, v1::DetectChangesRequest* request) {
  const OdometryDrift drift;
  const LocalMap& now = maps[t];
  if (!robot->lost && !SamePass(maps[robot->fixed_at], now)) robot->lost = true;
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
    if (!SamePass(before, now)) break;  // none: a global query
    const double travel = now.truth.travel_start - before.truth.travel_start;
    v1::SequenceMap* earlier = request->add_sequence();
    *earlier->mutable_map() = ToProto(before);
    *earlier->mutable_in_query() =
        ToProto(DriftedOdometry(before.truth.global_frame, now.truth.global_frame, travel, drift, robot->rng));
    earlier->set_travel_m(std::abs(travel));
  }
}

// The answer to a DetectChanges of `map`, scored against its truth (the
// site frame is the world's).
AnswerRow ReadAnswer(const LocalMap& map, const v1::DetectChangesRequest& request,
                     const v1::DetectChangesResponse& response) {
  const v1::Localization& verdict = response.localization();
  AnswerRow row;
  row.answered = true;
  row.asked = request.has_prior() ? "prior" : request.sequence_size() > 0 ? "sequence" : "global";
  row.prior_radius_m = request.has_prior() ? request.prior().radius_m() : 0.0;
  row.reduced_depth = response.reduced_depth();
  row.localized = verdict.localized();
  row.confidence = verdict.confidence();
  row.prior_failed = verdict.prior_failed();
  row.sequence_maps = static_cast<int>(verdict.sequence_maps());
  row.posed = verdict.has_collection_pose();
  if (response.hits_size() > 0) row.top_hit = response.hits(0).hit().map_id();
  if (row.posed) row.got = FromProto(verdict.collection_pose());
  const Pose2& truth = map.truth.global_frame;
  row.right = row.posed && std::hypot(row.got.x - truth.x, row.got.y - truth.y) <= 0.2 &&
              std::abs(std::remainder(row.got.theta - truth.theta, 2 * M_PI)) <= M_PI / 180;
  return row;
}

// A fleet robot's state after its answer of tick t.
void Track(const std::vector<LocalMap>& maps, size_t t, const AnswerRow& answer, FleetRobot* robot) {
  if (answer.localized && answer.posed) {
    robot->lost = false, robot->fix = answer.got, robot->fixed_at = t;
  } else if (!robot->lost) {
    const double travel = maps[t].truth.travel_start - maps[robot->fixed_at].truth.travel_start;
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

double PositionError(const AnswerRow& answer, const LocalMap& map) {
  return std::hypot(answer.got.x - map.truth.global_frame.x, answer.got.y - map.truth.global_frame.y);
}

double HeadingErrorDeg(const AnswerRow& answer, const LocalMap& map) {
  return std::abs(std::remainder(answer.got.theta - map.truth.global_frame.theta, 2 * M_PI)) * 180 / M_PI;
}

void PrintFleet(const std::vector<std::vector<AnswerRow>>& rows, const std::vector<LocalMap>& seed,
                const std::vector<std::vector<LocalMap>>& robot_maps) {
  const SeededPlaces seeded(seed);
  size_t asked = 0, right = 0, sure = 0, sure_unposed = 0, by_prior = 0, by_sequence = 0, prior_failed = 0;
  // Sure and wrong: all, by how it was asked, and those off by less than 1 m
  // (the right place at a slightly wrong pose).
  size_t sure_wrong = 0, wrong_by_prior = 0, wrong_by_sequence = 0, wrong_within_1m = 0;
  // Answers where a seeded map shows the place: all, right, failed priors.
  size_t at_seeded = 0, right_seeded = 0, failed_seeded = 0;
  std::vector<StatedOutcome> stated;  // the confidence against a right fix
  for (size_t r = 0; r < rows.size(); ++r) {
    for (size_t t = 0; t < rows[r].size(); ++t) {
      const AnswerRow& a = rows[r][t];
      if (!a.answered) continue;
      const bool prior = std::string(a.asked) == "prior", sequence = std::string(a.asked) == "sequence";
      ++asked, right += a.right, sure += a.localized, sure_unposed += a.localized && !a.posed;
      stated.push_back({a.confidence, a.right});
      by_prior += prior, by_sequence += sequence, prior_failed += a.prior_failed;
      if (a.localized && a.posed && !a.right) {
        ++sure_wrong, wrong_by_prior += prior, wrong_by_sequence += sequence;
        wrong_within_1m += PositionError(a, robot_maps[r][t]) < 1.0;
      }
      if (!seeded.Shows(robot_maps[r][t])) continue;
      ++at_seeded, right_seeded += a.right, failed_seeded += a.prior_failed;
    }
  }
  const double n = std::max<double>(1.0, static_cast<double>(asked));
  std::printf("fleet: %zu answers, right fixes %zu (%.3f; place and pose within 0.2 m / 1 deg; at places a seeded map "
              "shows %zu of %zu, %.3f), sure %zu (%.3f), "
              "sure and wrong %zu (by prior %zu, by sequence %zu; %zu off by less than 1 m), sure without a site pose "
              "%zu; by prior %zu (of them failed %zu, %zu at a place a seeded map shows), by sequence %zu, global %zu\n",
              asked, right, right / n, right_seeded, at_seeded,
              static_cast<double>(right_seeded) / std::max<size_t>(1, at_seeded), sure, sure / n, sure_wrong,
              wrong_by_prior, wrong_by_sequence, wrong_within_1m, sure_unposed, by_prior, prior_failed, failed_seeded,
              by_sequence, asked - by_prior - by_sequence);
  const Reliability reliability = MeasureReliability(stated);
  std::printf("fleet: confidence against right fixes: calibration error %.3f, Brier score %.3f",
              reliability.calibration_error, reliability.brier);
  for (int b = 0; b < kReliabilityBins; ++b) {
    if (reliability.count[b] > 0) {
      std::printf("; %.1f-%.1f: %zu said %.3f, right %.3f", b / 10.0, (b + 1) / 10.0, reliability.count[b],
                  reliability.mean_probability[b], reliability.share_right[b]);
    }
  }
  std::printf("\n");
}

// --answers: one line per DetectChanges of the run, tab-separated, with a
// header; the truth is the map's pose in the world (= site) frame.
Status WriteAnswers(const std::string& path, const std::vector<std::vector<AnswerRow>>& rows,
                    const std::vector<LocalMap>& seed, const std::vector<std::vector<LocalMap>>& robot_maps,
                    int first_robot) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (out == nullptr) return Status::InvalidArgument("cannot write " + path);
  std::fprintf(out, "robot\ttick\tanswered\tasked\tprior_radius_m\treduced_depth\tlatency_ms\tlocalized\t"
                    "prior_failed\tsequence_maps\ttop_hit\ttop_hit_shows_place\tposed\tright\terror_m\t"
                    "error_deg\ttruth_x\ttruth_y\ttruth_theta\tgot_x\tgot_y\tgot_theta\tconfidence\n");
  for (size_t r = 0; r < rows.size(); ++r) {
    for (size_t t = 0; t < rows[r].size(); ++t) {
      const AnswerRow& a = rows[r][t];
      const LocalMap& map = robot_maps[r][t];
      const LocalMap* hit = MapOfId(a.top_hit, seed, robot_maps, first_robot);
      const Pose2& truth = map.truth.global_frame;
      std::fprintf(out, "robot%zu\t%zu\t%d\t%s\t%.2f\t%d\t%.2f\t%d\t%d\t%d\t%s\t%s\t%d\t%d\t%.3f\t%.2f\t%.3f\t"
                        "%.3f\t%.4f\t%.3f\t%.3f\t%.4f\t%.4f\n",
                   first_robot + r, t, a.answered, a.asked, a.prior_radius_m, a.reduced_depth, a.latency_ms,
                   a.localized, a.prior_failed, a.sequence_maps, a.top_hit.empty() ? "-" : a.top_hit.c_str(),
                   hit == nullptr ? "-" : PlaceOverlap(map, *hit) >= 0.5 ? "1" : "0", a.posed, a.right,
                   a.posed ? PositionError(a, map) : NAN, a.posed ? HeadingErrorDeg(a, map) : NAN, truth.x, truth.y,
                   truth.theta, a.got.x, a.got.y, a.got.theta, a.confidence);
    }
  }
  if (std::fclose(out) != 0) return Status::InvalidArgument("cannot write " + path);
  return Status::Ok();
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
  std::string first_error;           // guarded by mutex
  // Per robot and tick, its DetectChanges as answered (each robot's thread writes its own).
  std::vector<std::vector<AnswerRow>> rows(options.robots);
  for (int r = 0; r < options.robots; ++r) rows[r].resize(plans[r].size());
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
          return ms;
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
        v1::DetectChangesRequest request;
        request.set_collection(options.collection);
        *request.mutable_map() = map.map();
        request.set_top_k(5);
        // The robot asks about stored maps other than the one it just sent.
        request.add_exclude_map_ids(map.metadata().map_id());
        if (options.fleet) AskAsTracked(robot_maps[r], t, &fleet[r], &request);
        v1::DetectChangesResponse response;
        grpc::Status status;
        const double ms = timed([&] { return status = (*client)->DetectChanges(request, &response); });
        if (status.ok()) {
          rows[r][t] = ReadAnswer(robot_maps[r][t], request, response);
          rows[r][t].latency_ms = ms;
          if (options.fleet) Track(robot_maps[r], t, rows[r][t], &fleet[r]);
        }
        if (options.fleet) timed(insert);
      }
    });
  }
  for (auto& robot : robots) robot.join();
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Localisation: does the top hit show the query's place (the product's
  // criterion, core/eval: half of the query's points within 0.3 m of the
  // hit's, in the world frame)? Among DetectChanges answered with a hit.
  // Sure answers whose top hit does not show the place are wrong whatever
  // their pose; where no seeded map shows the place, a look-alike may be all
  // the store has of it. Sure answers with a site pose are also counted
  // wrong where that pose is off (an anchored map of a twin room may agree
  // with a top hit at the right place).
  const SeededPlaces seeded(base);
  size_t answered = 0, localised = 0, detects_ok = 0, reduced = 0, sure = 0, sure_elsewhere = 0;
  size_t sure_elsewhere_seeded = 0, sure_site_off = 0, sure_wrong = 0;
  for (int r = 0; r < options.robots; ++r) {
    for (size_t t = 0; t < rows[r].size(); ++t) {
      detects_ok += rows[r][t].answered, reduced += rows[r][t].reduced_depth;
      // The site pose is checked against the truth whatever the top hit.
      const bool site_off = rows[r][t].localized && rows[r][t].posed && !rows[r][t].right;
      sure_site_off += site_off;
      const LocalMap* hit = MapOfId(rows[r][t].top_hit, base, robot_maps, options.first_robot);
      if (hit == nullptr) {
        sure_wrong += site_off;
        continue;
      }
      ++answered;
      const bool shows_place = PlaceOverlap(robot_maps[r][t], *hit) >= 0.5;
      localised += shows_place;
      sure += rows[r][t].localized;
      if (rows[r][t].localized && !shows_place) {
        ++sure_elsewhere;
        sure_elsewhere_seeded += seeded.Shows(robot_maps[r][t]);
      }
      sure_wrong += site_off || (rows[r][t].localized && !shows_place);
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
  std::printf("localisation: the top hit shows the robot's place for %zu of %zu answered DetectChanges (%.3f); "
              "lmdd was sure of %zu (%.3f), %zu of them with a top hit elsewhere (%zu at a place a seeded map shows), "
              "%zu with a site pose off by more than 0.2 m or 1 deg; wrong either way %zu\n",
              localised, answered, place_at_1, sure, answered > 0 ? static_cast<double>(sure) / answered : 0.0,
              sure_elsewhere, sure_elsewhere_seeded, sure_site_off, sure_wrong);
  const double reduced_share = detects_ok > 0 ? static_cast<double>(reduced) / static_cast<double>(detects_ok) : 0.0;
  std::printf("lmdd was busy and answered %zu of %zu DetectChanges at its reduced depth (%.3f)\n", reduced, detects_ok,
              reduced_share);
  if (options.fleet) PrintFleet(rows, base, robot_maps);
  if (!options.answers.empty()) {
    const Status written = WriteAnswers(options.answers, rows, base, robot_maps, options.first_robot);
    if (!written.ok()) {
      std::fprintf(stderr, "lmd-bench load: %s\n", written.message().c_str());
      return 1;
    }
  }
  if (options.json) {
    std::printf("{\"robots\": %d, \"rps\": %.2f, \"p50_ms\": %.3f, \"p95_ms\": %.3f, \"p99_ms\": %.3f, \"errors\": %ld, "
                "\"place_at_1\": %.4f, \"reduced_depth\": %.4f}\n",
                options.robots, rps, p50, p95, p99, errors.load(), place_at_1, reduced_share);
  }
  return errors.load() == 0 ? 0 : 1;
}

}  // namespace lmd::bench
