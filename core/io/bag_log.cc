#include "core/io/bag_log.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/io/ros_messages.h"
#include "core/io/tf_tree.h"

namespace lmd {
namespace {

constexpr const char* kLaserScan = "sensor_msgs/LaserScan";
constexpr const char* kOdometry = "nav_msgs/Odometry";
constexpr const char* kTfMessage = "tf2_msgs/TFMessage";

std::string FrameName(std::string f) {  // tf2 ignores a leading slash (ROS 1 frames often have one)
  while (!f.empty() && f.front() == '/') f.erase(0, 1);
  return f;
}

std::string Describe(const BagTopic& t) {
  return t.name + " (" + t.type + (t.message_count ? ", " + std::to_string(t.message_count) : "") + ")";
}

// "a (T, n), b (T, n), ..." for the topics that pass `keep`, at most 40.
template <typename Keep>
std::string TopicList(const std::vector<BagTopic>& topics, Keep keep) {
  std::string out;
  size_t shown = 0, total = 0;
  for (const BagTopic& t : topics) {
    if (!keep(t)) continue;
    if (++total > 40) continue;
    out += (shown++ ? ", " : "") + Describe(t);
  }
  if (total > shown) out += ", and " + std::to_string(total - shown) + " more";
  return out.empty() ? "none" : out;
}

std::vector<size_t> OfType(const std::vector<BagTopic>& topics, const char* type) {
  std::vector<size_t> out;
  for (size_t i = 0; i < topics.size(); ++i) {
    if (CanonicalType(topics[i].type) == type) out.push_back(i);
  }
  return out;
}

// The topic named `name` (which must be of `type`), or the only topic of `type`.
Result<size_t> ChooseTopic(const BagReader& bag, const std::string& name, const char* type, const char* flag) {
  const std::vector<BagTopic>& topics = bag.topics();
  const auto all = [](const BagTopic&) { return true; };
  const auto of_type = [&](const BagTopic& t) { return CanonicalType(t.type) == type; };
  if (!name.empty()) {
    for (size_t i = 0; i < topics.size(); ++i) {
      if (topics[i].name != name) continue;
      if (CanonicalType(topics[i].type) != type) {
        return Status::InvalidArgument(bag.path() + ": topic " + name + " is " + topics[i].type + ", not " + type +
                                       " (" + type + " topics: " + TopicList(topics, of_type) + ")");
      }
      return i;
    }
    return Status::InvalidArgument(bag.path() + ": no topic " + name + " in the bag (" + type +
                                   " topics: " + TopicList(topics, of_type) + ")");
  }
  const std::vector<size_t> candidates = OfType(topics, type);
  if (candidates.empty()) {
    return Status::InvalidArgument(bag.path() + ": no " + type + " topic; the bag's " +
                                   std::to_string(topics.size()) + " topics: " + TopicList(topics, all));
  }
  if (candidates.size() > 1) {
    return Status::InvalidArgument(bag.path() + ": " + std::to_string(candidates.size()) + " " + type +
                                   " topics, choose one with " + flag + ": " + TopicList(topics, of_type));
  }
  return candidates[0];
}

struct RawScan {
  int64_t stamp = 0;
  std::string frame;
  Scan scan;
  uint64_t number = 0;
  std::string where;
};

struct OdomSample {
  TransformStampedMessage transform;  // frame_id -> child_frame_id
  uint64_t number = 0;
  std::string where;
};

std::string Seconds(int64_t ns) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.9f s", static_cast<double>(ns) * 1e-9);
  return buf;
}

std::string Mounting(const PlanarTransform& p, const std::string& base, const std::string& laser) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s -> %s from tf: (%.3f m, %.3f m, %.1f deg)%s", base.c_str(), laser.c_str(),
                p.pose.x, p.pose.y, p.pose.theta * 180 / M_PI, p.flipped ? ", upside down" : "");
  return buf;
}

}  // namespace

Result<LaserLog> BagLaserLog(BagReader& bag, const BagLogOptions& options, BagLogSummary* summary) {
  BagLogSummary local;
  BagLogSummary& sum = summary ? *summary : local;
  sum = BagLogSummary{};
  const std::vector<BagTopic>& topics = bag.topics();
  Result<size_t> scan_topic = ChooseTopic(bag, options.scan_topic, kLaserScan, "--scan-topic");
  if (!scan_topic.ok()) return scan_topic.status();
  sum.scan_topic = topics[*scan_topic].name;

  std::vector<size_t> odom_topics;
  if (!options.odom_topic.empty()) {
    Result<size_t> odom = ChooseTopic(bag, options.odom_topic, kOdometry, "--odom-topic");
    if (!odom.ok()) return odom.status();
    odom_topics.push_back(*odom);
  } else if (options.frame.empty() && !options.scan_matching) {
    odom_topics = OfType(topics, kOdometry);
  }
  std::vector<size_t> tf_topics = options.scan_matching ? std::vector<size_t>() : OfType(topics, kTfMessage);

  std::vector<size_t> wanted{*scan_topic};
  wanted.insert(wanted.end(), odom_topics.begin(), odom_topics.end());
  wanted.insert(wanted.end(), tf_topics.begin(), tf_topics.end());

  std::vector<RawScan> scans;
  std::vector<std::vector<OdomSample>> odom(topics.size());
  std::vector<std::pair<TransformStampedMessage, bool>> tf;  // (transform, static)
  const float max_range_cap = options.max_usable_range;
  std::vector<uint64_t> numbers(topics.size(), 0);  // messages seen per topic: errors count within a topic
  Status read = bag.ReadMessages(wanted, [&](const BagMessage& m) -> Status {
    const BagTopic& topic = topics[m.topic];
    const uint64_t number = ++numbers[m.topic];
    auto fail = [&](const std::string& what) {
      return Status::InvalidArgument(bag.path() + ": " + topic.name + " message " + std::to_string(number) + " (" +
                                     m.where + "): " + what);
    };
    if (m.topic == *scan_topic) {
      Result<LaserScanMessage> msg = DecodeLaserScan(m.data, topic.encoding);
      if (!msg.ok()) return fail(msg.status().message());
      if (!(msg->angle_increment > 0) || !std::isfinite(msg->angle_increment)) {
        return fail("angle_increment is " + std::to_string(msg->angle_increment) +
                    " rad: it must be a positive number (beams counter-clockwise, as REP 103 has them)");
      }
      if (!std::isfinite(msg->angle_min)) return fail("angle_min is not finite");
      RawScan raw;
      raw.stamp = msg->stamp_ns != 0 ? msg->stamp_ns : m.log_time_ns;
      raw.frame = FrameName(msg->frame_id);
      raw.number = number;
      raw.where = m.where;
      Scan& s = raw.scan;
      s.first_angle = msg->angle_min;
      s.angle_step = msg->angle_increment;
      s.max_range = max_range_cap;
      if (msg->range_max > 0 && msg->range_max < s.max_range) s.max_range = msg->range_max;
      const float min_range = std::max(options.min_valid_range, std::isfinite(msg->range_min) ? msg->range_min : 0.0f);
      s.ranges = std::move(msg->ranges);
      for (size_t i = 0; i < s.ranges.size(); ++i) {
        float& r = s.ranges[i];
        if (std::isnan(r) && !options.allow_nan_ranges) {
          return fail("range " + std::to_string(i) + " of " + std::to_string(s.ranges.size()) +
                      " is NaN (an invalid reading; --allow-nan reads such readings as no return)");
        }
        if (!(r >= min_range) || r >= s.max_range) r = s.max_range;
      }
      scans.push_back(std::move(raw));
      return Status::Ok();
    }
    if (CanonicalType(topic.type) == kOdometry) {
      Result<OdometryMessage> msg = DecodeOdometry(m.data, topic.encoding);
      if (!msg.ok()) return fail(msg.status().message());
      OdomSample o;
      o.transform.stamp_ns = msg->stamp_ns != 0 ? msg->stamp_ns : m.log_time_ns;
      o.transform.frame_id = FrameName(msg->frame_id);
      o.transform.child_frame_id = FrameName(msg->child_frame_id);
      o.transform.transform = msg->pose;
      o.number = number;
      o.where = m.where;
      odom[m.topic].push_back(std::move(o));
      return Status::Ok();
    }
    Result<TfMessage> msg = DecodeTfMessage(m.data, topic.encoding);
    if (!msg.ok()) return fail(msg.status().message());
    const bool is_static = topic.name.size() >= 9 && topic.name.compare(topic.name.size() - 9, 9, "tf_static") == 0;
    for (TransformStampedMessage& t : msg->transforms) {
      t.frame_id = FrameName(t.frame_id);
      t.child_frame_id = FrameName(t.child_frame_id);
      tf.emplace_back(std::move(t), is_static);
    }
    return Status::Ok();
  });
  if (!read.ok()) return read;
  sum.format = bag.format();  // after reading: chunk compressions are known then
  sum.scans_read = scans.size();
  if (scans.empty()) return Status::InvalidArgument(bag.path() + ": topic " + sum.scan_topic + " has no messages");

  // Messages stay in recording order (the order loggers wrote them, as a
  // CARMEN log's lines). Stamps may step back a little (clock jitter: intel's
  // log steps back by up to 0.86 s); a larger step is an error.
  const int64_t backstep = static_cast<int64_t>(options.max_time_backstep_s * 1e9);
  auto backwards = [&](const std::string& topic, uint64_t number, const std::string& where, int64_t stamp,
                       int64_t previous) {
    return Status::InvalidArgument(bag.path() + ": " + topic + " message " + std::to_string(number) + " (" + where +
                                   "): header stamp " + Seconds(stamp) + " is " + Seconds(previous - stamp) +
                                   " before the previous message's: time goes backwards (a clock reset, or two "
                                   "recordings in one bag?)");
  };
  for (size_t i = 1; i < scans.size(); ++i) {
    if (scans[i - 1].stamp - scans[i].stamp > backstep) {
      return backwards(sum.scan_topic, scans[i].number, scans[i].where, scans[i].stamp, scans[i - 1].stamp);
    }
  }
  for (size_t t : odom_topics) {
    for (size_t i = 1; i < odom[t].size(); ++i) {
      const int64_t stamp = odom[t][i].transform.stamp_ns, previous = odom[t][i - 1].transform.stamp_ns;
      if (previous - stamp > backstep) return backwards(topics[t].name, odom[t][i].number, odom[t][i].where, stamp, previous);
    }
  }

  TfTree tree;
  for (const auto& [t, is_static] : tf) tree.Add(t, is_static);
  const std::string laser = scans[0].frame;

  // Pose source.
  enum class Source { kTf, kOdometry, kScanMatching } source;
  std::string frame = options.frame;
  size_t odom_topic = 0;
  if (options.scan_matching) {
    source = Source::kScanMatching;
  } else if (!frame.empty()) {
    source = Source::kTf;
  } else if (!options.odom_topic.empty()) {
    source = Source::kOdometry, odom_topic = odom_topics[0];
  } else if (tree.Connected("map", laser)) {
    source = Source::kTf, frame = "map";
  } else if (odom_topics.size() > 1) {
    return Status::InvalidArgument(
        bag.path() + ": " + std::to_string(odom_topics.size()) + " nav_msgs/Odometry topics, choose one with " +
        "--odom-topic (or a tf frame with --frame): " +
        TopicList(topics, [](const BagTopic& t) { return CanonicalType(t.type) == kOdometry; }));
  } else if (odom_topics.size() == 1 && !odom[odom_topics[0]].empty()) {
    source = Source::kOdometry, odom_topic = odom_topics[0];
  } else if (tree.Connected("odom", laser)) {
    source = Source::kTf, frame = "odom";
  } else {
    source = Source::kScanMatching;
  }

  LaserLog log;
  const int64_t tolerance = static_cast<int64_t>(options.pose_tolerance_s * 1e9);
  if (source == Source::kScanMatching) {
    std::vector<Scan> plain;
    for (const RawScan& r : scans) plain.push_back(r.scan);
    const ScanOdometry poses = EstimateScanOdometry(plain, options.scan_odometry);
    char buf[200];
    std::snprintf(buf, sizeof buf, "scan matching (%s; mean score %.2f, %zu of %zu weak matches kept their guess)",
                  options.scan_matching ? "asked for" : "the bag records no odometry and no tf", poses.mean_score,
                  poses.weak_matches, plain.size() > 0 ? plain.size() - 1 : 0);
    sum.pose_source = buf;
    sum.laser_mounting = "not needed (scan matching poses the laser itself)";
    for (size_t i = 0; i < plain.size(); ++i) plain[i].pose = poses.poses[i];
    log.scans = std::move(plain);
    return log;
  }

  // Odometry: a tree of the odometry's frame -> base samples plus tf's other edges.
  TfTree odom_tree;
  std::string base;
  if (source == Source::kOdometry) {
    const std::vector<OdomSample>& samples = odom[odom_topic];
    if (samples.empty()) return Status::InvalidArgument(bag.path() + ": topic " + topics[odom_topic].name + " has no messages");
    frame = samples[0].transform.frame_id.empty() ? "odom" : samples[0].transform.frame_id;
    base = samples[0].transform.child_frame_id.empty() ? "base_link" : samples[0].transform.child_frame_id;
    for (OdomSample s : samples) {
      s.transform.frame_id = frame, s.transform.child_frame_id = base;
      odom_tree.Add(s.transform, false);
    }
    for (const auto& [t, is_static] : tf) {
      if (t.child_frame_id != base) odom_tree.Add(t, is_static);
    }
    sum.pose_source = "odometry " + topics[odom_topic].name + " (" + frame + " -> " + base + ")";
  } else {
    sum.pose_source = "tf " + frame + " -> " + (laser.empty() ? "(no frame)" : laser);
  }
  const TfTree& poses = source == Source::kOdometry ? odom_tree : tree;
  const bool mounted = source == Source::kTf || (!laser.empty() && laser != base && poses.Connected(base, laser));
  if (source == Source::kOdometry) {
    if (laser.empty() || laser == base) {
      sum.laser_mounting = "the scans are in the base frame " + base;
    } else if (!mounted) {
      sum.laser_mounting = "none recorded (no tf " + base + " -> " + laser + "): laser taken at " + base;
    }
  }
  Status last_miss;
  for (RawScan& r : scans) {
    const std::string source_frame = mounted ? r.frame : base;
    Result<Transform3> t = poses.Lookup(frame, source_frame, r.stamp, tolerance);
    if (!t.ok()) {
      ++sum.scans_without_pose;
      last_miss = t.status();
      continue;
    }
    const PlanarTransform p = ToPlanar(*t);
    Scan s = std::move(r.scan);
    s.pose = p.pose;
    if (p.flipped) {  // mirrored beam order
      std::reverse(s.ranges.begin(), s.ranges.end());
      s.first_angle = -(s.first_angle + s.angle_step * static_cast<float>(s.ranges.size() > 0 ? s.ranges.size() - 1 : 0));
    }
    if (sum.laser_mounting.empty()) {
      Result<Transform3> m = source == Source::kOdometry ? poses.Lookup(base, r.frame, r.stamp, tolerance)
                                                         : Status::NotFound("");
      if (m.ok()) {
        sum.laser_mounting = Mounting(ToPlanar(*m), base, r.frame);
      } else {
        sum.laser_mounting = "in the tf chain " + frame + " -> " + r.frame;
      }
    }
    log.scans.push_back(std::move(s));
  }
  if (log.scans.empty()) {
    std::string edges;
    for (const std::string& e : tree.Edges()) edges += (edges.empty() ? "" : ", ") + e;
    return Status::InvalidArgument(bag.path() + ": none of the " + std::to_string(scans.size()) + " scans on " +
                                   sum.scan_topic + " has a pose from " + sum.pose_source + ": " +
                                   last_miss.message() + " (tf: " + (edges.empty() ? "none" : edges) + ")");
  }
  return log;
}

Result<LaserLog> ReadBagLaserLog(const std::string& path, const BagLogOptions& options, BagLogSummary* summary) {
  Result<std::unique_ptr<BagReader>> bag = OpenBag(path, options.read);
  if (!bag.ok()) return bag.status();
  return BagLaserLog(**bag, options, summary);
}

}  // namespace lmd
