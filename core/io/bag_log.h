// A laser log from a recorded bag (bag.h): the scans of one LaserScan topic,
// each posed by the bag's pose source, so that bags feed the same local-map
// builder as CARMEN logs (local_map_builder.h).
//
// Pose source, in this order unless chosen:
//   1. tf in `frame` (e.g. "map": a SLAM pose, map -> odom -> base_link ->
//      laser), when `frame` is set, or when no odometry topic is chosen and
//      tf links a "map" frame to the laser;
//   2. a nav_msgs/Odometry topic (`odom_topic`, or the only one recorded):
//      the base pose, composed with the laser's mounting from tf (base ->
//      laser frame, /tf_static) when recorded;
//   3. tf in "odom" when it links odom to the laser;
//   4. scan matching (scan_odometry.h) when the bag records no pose at all.
// Scans stay in recording order. Poses are looked up at each scan's header stamp (its log time when the
// stamp is zero). Ranges follow the CARMEN reader's rules, so that the same
// scans give the same maps: a reading at or beyond min(range_max,
// max_usable_range), +inf, below max(range_min, min_valid_range), or -inf
// is "no return" (stored as max_range).
#pragma once

#include <string>

#include "core/align/scan_odometry.h"
#include "core/io/bag.h"
#include "core/io/laser_log.h"
#include "core/status.h"

namespace lmd {

struct BagLogOptions {
  std::string scan_topic;  // "" = the bag's only sensor_msgs/LaserScan topic
  std::string odom_topic;  // "" = chosen as above
  std::string frame;       // tf frame to take poses in ("map", "odom"); "" = chosen as above
  bool scan_matching = false;  // true: poses by scan matching even if the bag records some
  // m; as CarmenReadOptions (the same defaults, so both paths agree).
  float max_usable_range = 30.0f;
  float min_valid_range = 0.01f;
  // false: a NaN range is an error naming the scan. true: read as an invalid
  // reading (REP 117), stored as no return.
  bool allow_nan_ranges = false;
  // s; a pose source sample this far beyond the scan's stamp (or half a gap
  // this wide) still poses it; scans farther from any sample are dropped.
  double pose_tolerance_s = 0.25;
  // s; a header stamp this much before the previous one on the same topic is
  // tolerated (logger clocks jitter: intel's log steps back by 0.86 s);
  // more is an error (a clock reset, two recordings in one bag).
  double max_time_backstep_s = 1.0;
  ScanOdometryOptions scan_odometry;
  BagReadOptions read;
};

struct BagLogSummary {
  std::string format;         // the container, as BagReader::format() says
  std::string scan_topic;
  std::string pose_source;    // "odometry /odom (odom -> base_link)", "tf map -> laser", "scan matching ..."
  std::string laser_mounting; // "base_link -> laser from tf: (0.10 m, 0.00 m, 0.0 deg)" or why none
  size_t scans_read = 0;      // messages on the scan topic
  size_t scans_without_pose = 0;  // dropped: no pose source sample near their stamp
};

// The laser log of the bag at `path` (a file or a rosbag2 directory). Errors
// name the bag, the topic and the message (number and offset or row):
// InvalidArgument for a missing or ambiguous topic (listing the
// candidates), a topic of another type, angle_increment <= 0, NaN ranges,
// header stamps going backwards, no scan with a pose; Corruption / IoError
// from the container.
Result<LaserLog> ReadBagLaserLog(const std::string& path, const BagLogOptions& options = {},
                                 BagLogSummary* summary = nullptr);

// Same from an open bag.
Result<LaserLog> BagLaserLog(BagReader& bag, const BagLogOptions& options = {}, BagLogSummary* summary = nullptr);

}  // namespace lmd
