// Decoders for the ROS messages lmd reads from bags, in ROS 2 CDR (XCDR1,
// little- or big-endian, as rosbag2 records them) and ROS 1 serialisation:
// sensor_msgs/LaserScan, nav_msgs/Odometry and tf2_msgs/TFMessage (also ROS
// 1's tf/tfMessage, the same layout). Only the fields lmd uses are kept.
// Every read is bounds-checked: an array never allocates more than the
// message's remaining bytes can hold.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/bag.h"
#include "core/status.h"

namespace lmd {

// A rigid 3D transform (geometry_msgs/Transform or Pose): translation in m,
// rotation as a unit quaternion (x, y, z, w).
struct Transform3 {
  double x = 0, y = 0, z = 0;
  double qx = 0, qy = 0, qz = 0, qw = 1;
};

struct LaserScanMessage {
  int64_t stamp_ns = 0;
  std::string frame_id;
  float angle_min = 0, angle_max = 0, angle_increment = 0;  // rad
  float time_increment = 0, scan_time = 0;                  // s
  float range_min = 0, range_max = 0;                       // m
  std::vector<float> ranges;                                // m
};

struct OdometryMessage {
  int64_t stamp_ns = 0;
  std::string frame_id;        // the pose's frame (odom)
  std::string child_frame_id;  // the robot's frame (base_link)
  Transform3 pose;             // child frame in frame_id
};

struct TransformStampedMessage {
  int64_t stamp_ns = 0;
  std::string frame_id;        // parent
  std::string child_frame_id;  // child
  Transform3 transform;        // child frame in the parent frame
};

struct TfMessage {
  std::vector<TransformStampedMessage> transforms;
};

// Decode `data` in `encoding` (kCdr or kRos1). InvalidArgument "<Type>
// (<encoding>): ..." naming the field and byte where it fails (truncated,
// an array longer than the message, an unsupported CDR encapsulation).
Result<LaserScanMessage> DecodeLaserScan(std::string_view data, MessageEncoding encoding);
Result<OdometryMessage> DecodeOdometry(std::string_view data, MessageEncoding encoding);
Result<TfMessage> DecodeTfMessage(std::string_view data, MessageEncoding encoding);

}  // namespace lmd
