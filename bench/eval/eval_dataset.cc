#include "bench/eval/eval_dataset.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <random>
#include <thread>

#include "bench/eval/data_paths.h"
#include "core/io/bag_log.h"
#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/odometry_drift.h"
#include "core/util/progress_bar.h"

namespace lmd::eval {

void ParallelFor(size_t n, int threads, const std::function<void(size_t)>& fn) {
  const int t = std::max(1, threads);
  if (t == 1 || n < 2) {
    for (size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::vector<std::thread> workers;
  for (int k = 0; k < t; ++k) {
    workers.emplace_back([&] {
      for (size_t i = next++; i < n; i = next++) fn(i);
    });
  }
  for (std::thread& w : workers) w.join();
}

Pose2 Dataset::TruePose(size_t query_map, size_t db_map) const {
  return Compose(Inverse(maps[db_map].truth.global_frame), maps[query_map].truth.global_frame);
}

bool Dataset::ShowsPlace(const EvalQuery& q, size_t db_map) const {
  return std::binary_search(q.places.begin(), q.places.end(), db_map);
}

namespace {

uint64_t Fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ULL;
  return h;
}

struct Box {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  bool Meets(const Box& o, double margin) const {
    return x0 - margin <= o.x1 && o.x0 - margin <= x1 && y0 - margin <= o.y1 && o.y0 - margin <= y1;
  }
};

// The bag's scans posed by its ground truth.
Result<LaserLog> ReadTruthBag(const std::string& path, const DatasetOptions& options) {
  if (options.truth_frame.empty() == options.truth_odom.empty()) {
    return Status::InvalidArgument(path + ": a bag needs --truth-frame FRAME or --truth-odom TOPIC (one of them): " +
                                   "lmd-eval scores against ground-truth poses");
  }
  BagLogOptions bag;
  bag.frame = options.truth_frame;
  bag.odom_topic = options.truth_odom;
  if (options.max_range_m > 0) bag.max_usable_range = options.max_range_m;
  return ReadBagLaserLog(path, bag);
}

// Every return (a reading below the scan's max_range) moved by Gaussian
// noise of `sigma_m`, kept at 1 cm at the least and below max_range.
void AddRangeNoise(double sigma_m, uint64_t seed, LaserLog* log) {
  std::mt19937_64 rng(seed ^ 0x6e6f697365ULL);  // "noise"
  std::normal_distribution<double> noise(0.0, sigma_m);
  for (Scan& scan : log->scans) {
    const double below_max = std::nextafter(static_cast<double>(scan.max_range), 0.0);
    for (float& r : scan.ranges) {
      if (r < scan.max_range) r = static_cast<float>(std::clamp(r + noise(rng), 0.01, below_max));
    }
  }
}

// Each scan cut to its beams within fov_deg / 2 of the laser's heading. A
// scan may start anywhere (a 360-deg lidar's at 0 rad): the kept beams are
// ordered by their angle about the heading, so that they run on from the
// first by the scan's own step even where the scan wrapped past 180 deg.
void NarrowFieldOfView(double fov_deg, LaserLog* log) {
  const double half = fov_deg / 2 * M_PI / 180;
  for (Scan& scan : log->scans) {
    std::vector<std::pair<double, float>> kept;  // angle in (-pi, pi], range
    for (size_t b = 0; b < scan.ranges.size(); ++b) {
      const double angle = std::remainder(scan.first_angle + static_cast<double>(b) * scan.angle_step, 2 * M_PI);
      if (std::abs(angle) <= half) kept.push_back({angle, scan.ranges[b]});
    }
    std::sort(kept.begin(), kept.end(), [&](const auto& a, const auto& b) {
      return scan.angle_step >= 0 ? a.first < b.first : a.first > b.first;
    });
    scan.first_angle = kept.empty() ? 0.0f : static_cast<float>(kept.front().first);
    scan.ranges.clear();
    for (const auto& beam : kept) scan.ranges.push_back(beam.second);
  }
}

// Each map as built on drifting odometry (one rng per map, from the seed,
// the dataset and the map's index).
void DriftMaps(double deg_per_m, uint64_t seed, std::vector<LocalMap>* maps) {
  OdometryDrift drift;
  drift.heading_rad_per_m = deg_per_m * M_PI / 180;
  const double dedup_cell_m = LocalMapOptions().dedup_cell_m;
  for (size_t i = 0; i < maps->size(); ++i) {
    std::mt19937_64 rng(seed ^ 0x6472696674ULL ^ (0x9E3779B97F4A7C15ULL * (i + 1)));  // "drift"
    (*maps)[i] = WithDriftedOdometry(std::move((*maps)[i]), drift, dedup_cell_m, rng);
  }
}

}  // namespace

std::vector<std::string> WithSensorFlags(std::vector<std::string> valued) {
  for (const char* flag : {"max-range", "range-noise", "fov", "map-drift", "map-length"}) valued.push_back(flag);
  return valued;
}

bool SensorFromFlags(Flags& args, DatasetOptions* options) {
  double max_range = 0.0;
  if (!args.Number("max-range", 1.0, CarmenReadOptions().max_usable_range, 0.0, &max_range) ||
      !args.Number("range-noise", 0.0, 1.0, 0.0, &options->range_noise_m) ||
      !args.Number("fov", 10.0, 360.0, 360.0, &options->fov_deg) ||
      !args.Number("map-drift", 0.0, 10.0, 0.0, &options->map_drift_deg_per_m) ||
      !args.Number("map-length", 1.0, 20.0, 5.0, &options->map_length_m)) {
    return false;
  }
  options->max_range_m = static_cast<float>(max_range);
  return true;
}

Result<Dataset> LoadDataset(const std::string& log_path, const DatasetOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Dataset d;
  d.name = DatasetName(log_path);
  CarmenReadOptions carmen;
  if (options.max_range_m > 0) carmen.max_usable_range = options.max_range_m;
  Result<LaserLog> log = IsBagPath(log_path) ? ReadTruthBag(log_path, options) : ReadCarmenLog(log_path, carmen);
  if (!log.ok()) return log.status();
  if (options.range_noise_m > 0) AddRangeNoise(options.range_noise_m, options.seed, &*log);
  if (options.fov_deg < 360) NarrowFieldOfView(options.fov_deg, &*log);
  LocalMapOptions lm;
  lm.length_m = options.map_length_m;
  lm.id_prefix = d.name;
  d.maps = BuildLocalMaps(*log, lm);
  const std::vector<RelevantPair> pairs = FindRelevantPairs(d.maps, GroundTruthOptions{10.0, 0.5,
                                                                 static_cast<size_t>(std::max(1, options.threads))});
  // Global points, boxes and grids for place truth.
  const size_t n = d.maps.size();
  std::vector<std::vector<Point2>> global(n);
  std::vector<Box> boxes(n);
  std::vector<PointGrid> grids(n);
  ParallelFor(n, options.threads, [&](size_t i) {
    global[i] = ToGlobal(d.maps[i]);
    for (const Point2& p : global[i]) {
      Box& b = boxes[i];
      b.x0 = std::min(b.x0, p.x), b.y0 = std::min(b.y0, p.y), b.x1 = std::max(b.x1, p.x), b.y1 = std::max(b.y1, p.y);
    }
    grids[i] = PointGrid(global[i], options.place_radius_m);
  });
  // The robots' maps; the truth above stays the logs'.
  if (options.map_drift_deg_per_m > 0) DriftMaps(options.map_drift_deg_per_m, options.seed ^ Fnv1a(d.name), &d.maps);

  std::vector<RelevantPair> asked = pairs;
  if (options.every_map) {
    std::vector<RelevantPair> all;
    size_t next = 0;
    for (size_t i = 0; i < n; ++i) {
      if (d.maps[i].points.empty()) continue;
      while (next < pairs.size() && pairs[next].query < i) ++next;
      all.push_back(next < pairs.size() && pairs[next].query == i ? pairs[next]
                                                                  : RelevantPair{i, kNoRelevant, 0.0, 0});
    }
    asked = std::move(all);
  }
  d.queries.resize(asked.size());
  const uint64_t base = options.seed * 0x9E3779B97F4A7C15ULL ^ Fnv1a(d.name);
  ProgressBar bar(d.name + ": ground truth and changes", asked.size());
  std::atomic<size_t> done{0};
  std::mutex bar_mutex;
  ParallelFor(asked.size(), options.threads, [&](size_t k) {
    const RelevantPair& p = asked[k];
    EvalQuery& q = d.queries[k];
    q.map = p.query, q.relevant = p.relevant, q.mean_dist_m = p.mean_dist_m;
    const LocalMap& qm = d.maps[p.query];
    const std::vector<Point2>& qg = global[p.query];
    for (size_t j = 0; j < n; ++j) {
      if (std::abs(d.maps[j].truth.travel_start - qm.truth.travel_start) <= kExcludedTravelM) continue;
      if (d.maps[j].points.empty()) continue;
      q.candidates.push_back(j);
      if (!boxes[p.query].Meets(boxes[j], options.place_radius_m)) continue;
      const size_t need = static_cast<size_t>(std::ceil(options.place_min_overlap * qg.size()));
      size_t within = 0, seen = 0;
      for (const Point2& pt : qg) {
        within += grids[j].AnyWithin(pt, options.place_radius_m) ? 1 : 0;
        ++seen;
        if (within + (qg.size() - seen) < need) break;  // cannot reach the threshold
      }
      if (!qg.empty() && within >= need) q.places.push_back(j);
    }
    q.changed = qm;
    std::mt19937_64 rng(base ^ (0xD1B54A32D192ED03ULL * (p.query + 1)));
    Result<SimulatedChange> ch = ApplySimulatedChange(q.changed, rng);
    if (ch.ok()) {
      q.change_ok = true;
      q.changed_points = ch->changed_points;
    } else {
      q.changed = qm;
    }
    std::lock_guard<std::mutex> lock(bar_mutex);
    bar.Update(++done);
  });
  bar.Done();
  d.load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return d;
}

}  // namespace lmd::eval
