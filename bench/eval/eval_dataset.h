// One dataset of the evaluation protocol (DESIGN.md §4), loaded once and
// shared by every method: local maps, relevant pairs, place truth and the
// simulated change in each query.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bench/common/flags.h"
#include "core/eval/ground_truth.h"
#include "core/eval/point_grid.h"
#include "core/sim/change.h"
#include "core/status.h"
#include "core/types.h"

namespace lmd::eval {

// Runs fn(i) for i in [0, n) on `threads` threads (>= 1), dynamic schedule.
void ParallelFor(size_t n, int threads, const std::function<void(size_t)>& fn);

// No relevant map (EvalQuery::relevant): the query's place was not revisited.
inline constexpr size_t kNoRelevant = static_cast<size_t>(-1);
// m of travel around a query whose maps are not its candidates (the paper's 10 m).
inline constexpr double kExcludedTravelM = 10.0;

struct EvalQuery {
  size_t map = 0;                 // index of the query map
  size_t relevant = kNoRelevant;  // index of its relevant map (paper's scoring)
  double mean_dist_m = 0.0;       // ground truth mean distance to it
  std::vector<size_t> candidates; // valid candidates (> 10 m of travel away), ascending
  std::vector<size_t> places;     // candidates showing the query's place (overlap >= 0.5), ascending
  LocalMap changed;               // copy of the query map with a simulated change
  bool change_ok = false;         // false: no change could be placed (query used unchanged)
  std::vector<Point2> changed_points;  // own frame of the query
};

struct Dataset {
  std::string name;
  std::vector<LocalMap> maps;
  std::vector<EvalQuery> queries;  // one per relevant pair (or every map), sorted by query map
  double load_seconds = 0.0;

  // Pose of the query's own frame in map db's own frame (ground truth).
  Pose2 TruePose(size_t query_map, size_t db_map) const;
  bool ShowsPlace(const EvalQuery& q, size_t db_map) const;
};

struct DatasetOptions {
  uint64_t seed = 1;  // simulated changes (one rng per query from seed, dataset, query) and range noise
  double place_radius_m = 0.3;    // place truth: query points within this of the map's
  double place_min_overlap = 0.5; //   ... at least this fraction
  int threads = 2;
  // false: the paper's queries, one per relevant pair; true: every map with
  // points (the served protocol: a robot cannot know whether its place was
  // revisited, so queries without a relevant map are asked too).
  bool every_map = false;
  // A bag (MCAP, rosbag2, ROS 1) instead of a CARMEN log: its ground-truth
  // poses come from this tf frame (e.g. "map" of a SLAM or simulator) or
  // this nav_msgs/Odometry topic; one of the two is required.
  std::string truth_frame;
  std::string truth_odom;
  // m, > 0: the laser taken as one that reaches only this far (readings at
  // or beyond it are no return), as a robot with a shorter-range sensor than
  // the logs' would see the same place. 0: the readers' default (30 m).
  // Not beyond it: the logs' no-return codes (32.8-81.9 m) would read as walls.
  float max_range_m = 0.0f;
  // m, > 0: Gaussian noise of this standard deviation added to every
  // return (seeded by `seed`), as a noisier laser than the logs' would read.
  double range_noise_m = 0.0;
  // deg, < 360: only the beams within half this either side of the laser's
  // heading kept, as a narrower sensor (a depth camera's 60-90 deg, a
  // front laser's 180) would see. 360: every beam the log holds.
  double fov_deg = 360.0;
  // deg per m, > 0: every local map (stored and queried alike) built on
  // odometry that drifts within it, as a robot without a scan matcher builds
  // its maps: a heading rate of up to this and a length error of up to 2 %,
  // drawn once per map (WithDriftedOdometry, seeded by `seed`). Place truth,
  // relevant pairs and the maps' frames stay those of the logs' poses.
  double map_drift_deg_per_m = 0.0;
  // m of travel per local map (the protocol's 5), as robots that send
  // shorter or longer maps; a new one still starts every metre.
  double map_length_m = 5.0;
};

// `valued` with the flags SensorFromFlags reads, for the commands that load
// datasets.
std::vector<std::string> WithSensorFlags(std::vector<std::string> valued);

// --max-range M (1-30 m), --range-noise S (0-1 m), --fov F (10-360 deg),
// --map-drift D (0-10 deg per m) and --map-length L (1-20 m) from `args`
// into `options`; false, with args.error() saying what is wrong, when one
// is out of range.
bool SensorFromFlags(Flags& args, DatasetOptions* options);

// Reads the log, builds local maps (map_length_m every 1 m), ground truth,
// place truth and simulated changes. IoError etc. from the reader.
Result<Dataset> LoadDataset(const std::string& log_path, const DatasetOptions& options);

}  // namespace lmd::eval
