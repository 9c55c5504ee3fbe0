// A retrieval result as an MCAP file that Foxglove, Lichtblick and `ros2 bag
// play` (then RViz) open: ROS 2 CDR messages of standard types, their
// ros2msg schemas in the file. Frames: "query" (the query map's own frame)
// is the root; each hit's stored map sits in frame "hit_<rank>", placed by
// the hit's metric pose on /tf_static. Topics:
//   /lmd/query             sensor_msgs/PointCloud2      query points (frame query)
//   /lmd/query/trajectory  nav_msgs/Path                query trajectory (frame query)
//   /lmd/hit_<rank>        sensor_msgs/PointCloud2      the stored map's points (frame hit_<rank>)
//   /lmd/changes           visualization_msgs/MarkerArray  change masks: a sphere list and a label each (frame query)
//   /tf_static             tf2_msgs/TFMessage           query -> hit_<rank> (transient local, as tf2 expects)
// Message types follow ROS 2 Humble / Jazzy.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/types.h"

namespace lmd {

struct ResultSceneHit {
  std::string map_id;
  uint32_t rank = 0;
  double score = 0.0;
  Pose2 query_in_db;                       // the hit's metric pose
  const LocalMap* map = nullptr;           // the stored map, own frame (null: frame only, no points)
  std::vector<std::vector<Point2>> masks;  // ranked change masks, query's own frame
};

struct ResultScene {
  const LocalMap* query = nullptr;  // own frame
  std::vector<ResultSceneHit> hits;  // hits with a metric pose
  int64_t stamp_ns = 0;              // header stamps and log times of every message
};

// The MCAP file's bytes.
std::string RenderResultMcap(const ResultScene& scene);

}  // namespace lmd
