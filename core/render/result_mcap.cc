#include "core/render/result_mcap.h"

#include <cmath>

#include "core/io/cdr_writer.h"
#include "core/io/mcap_writer.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

// ros2msg schemas: the message's definition, then each type it uses after a
// line of '=' and "MSG: package/Type", as rosbag2 writes them into MCAP files.
constexpr const char* kSeparator = "================================================================================\n";

std::string Dep(const char* name, const char* text) { return std::string(kSeparator) + "MSG: " + name + "\n" + text; }

const char* kTime = "int32 sec\nuint32 nanosec\n";
const char* kHeader = "builtin_interfaces/Time stamp\nstring frame_id\n";
const char* kPoint = "float64 x\nfloat64 y\nfloat64 z\n";
const char* kQuaternion = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
const char* kPose = "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n";
const char* kVector3 = "float64 x\nfloat64 y\nfloat64 z\n";

std::string HeaderDeps() { return Dep("std_msgs/Header", kHeader) + Dep("builtin_interfaces/Time", kTime); }
std::string PoseDeps() {
  return Dep("geometry_msgs/Pose", kPose) + Dep("geometry_msgs/Point", kPoint) +
         Dep("geometry_msgs/Quaternion", kQuaternion);
}

std::string PointCloud2Schema() {
  return std::string(
             "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\nbool is_bigendian\n"
             "uint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n") +
         HeaderDeps() +
         Dep("sensor_msgs/PointField",
             "uint8 INT8    = 1\nuint8 UINT8   = 2\nuint8 INT16   = 3\nuint8 UINT16  = 4\nuint8 INT32   = 5\n"
             "uint8 UINT32  = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\nstring name\nuint32 offset\nuint8 datatype\n"
             "uint32 count\n");
}

std::string PathSchema() {
  return std::string("std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n") +
         Dep("geometry_msgs/PoseStamped", "std_msgs/Header header\ngeometry_msgs/Pose pose\n") + HeaderDeps() +
         PoseDeps();
}

std::string TfSchema() {
  return std::string("geometry_msgs/TransformStamped[] transforms\n") +
         Dep("geometry_msgs/TransformStamped",
             "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n") +
         HeaderDeps() +
         Dep("geometry_msgs/Transform", "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n") +
         Dep("geometry_msgs/Vector3", kVector3) + Dep("geometry_msgs/Quaternion", kQuaternion);
}

std::string MarkerArraySchema() {
  return std::string("visualization_msgs/Marker[] markers\n") +
         Dep("visualization_msgs/Marker",
             "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\n"
             "int32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\n"
             "int32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\n"
             "int32 DELETEALL=3\nstd_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\n"
             "geometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\n"
             "builtin_interfaces/Duration lifetime\nbool frame_locked\ngeometry_msgs/Point[] points\n"
             "std_msgs/ColorRGBA[] colors\nstring texture_resource\nsensor_msgs/CompressedImage texture\n"
             "visualization_msgs/UVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n"
             "visualization_msgs/MeshFile mesh_file\nbool mesh_use_embedded_materials\n") +
         HeaderDeps() + PoseDeps() + Dep("geometry_msgs/Vector3", kVector3) +
         Dep("std_msgs/ColorRGBA", "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n") +
         Dep("builtin_interfaces/Duration", kTime) +
         Dep("sensor_msgs/CompressedImage", "std_msgs/Header header\nstring format\nuint8[] data\n") +
         Dep("visualization_msgs/UVCoordinate", "float32 u\nfloat32 v\n") +
         Dep("visualization_msgs/MeshFile", "string filename\nuint8[] data\n");
}

void PoseOf(CdrWriter& w, const Pose2& p) {
  w.F64(p.x), w.F64(p.y), w.F64(0);
  w.F64(0), w.F64(0), w.F64(std::sin(p.theta / 2)), w.F64(std::cos(p.theta / 2));
}

std::string PointCloud(int64_t stamp, const std::string& frame, const std::vector<Point2>& points) {
  CdrWriter w;
  w.Header(stamp, frame);
  w.U32(1);
  w.U32(static_cast<uint32_t>(points.size()));
  w.U32(3);
  for (const char* axis : {"x", "y", "z"}) {
    w.String(axis);
    w.U32(static_cast<uint32_t>(4 * (axis[0] - 'x')));
    w.U8(7);  // FLOAT32
    w.U32(1);
  }
  w.U8(0);  // little-endian
  w.U32(12);
  w.U32(static_cast<uint32_t>(12 * points.size()));
  w.U32(static_cast<uint32_t>(12 * points.size()));
  std::string data;
  data.reserve(12 * points.size());
  for (const Point2& p : points) {
    PutF32(data, static_cast<float>(p.x));
    PutF32(data, static_cast<float>(p.y));
    PutF32(data, 0.0f);
  }
  w.Raw(data);
  w.U8(1);  // is_dense
  return w.data();
}

std::string Path(int64_t stamp, const std::string& frame, const std::vector<Pose2>& poses) {
  CdrWriter w;
  w.Header(stamp, frame);
  w.U32(static_cast<uint32_t>(poses.size()));
  for (const Pose2& p : poses) {
    w.Header(stamp, frame);
    PoseOf(w, p);
  }
  return w.data();
}

void Marker(CdrWriter& w, int64_t stamp, const std::string& ns, int32_t id, int32_t type, const Pose2& pose,
            double scale, const float rgba[4], const std::vector<Point2>& points, const std::string& text) {
  w.Header(stamp, "query");
  w.String(ns);
  w.I32(id);
  w.I32(type);
  w.I32(0);  // ADD
  PoseOf(w, pose);
  w.F64(scale), w.F64(scale), w.F64(scale);
  for (int i = 0; i < 4; ++i) w.F32(rgba[i]);
  w.I32(0), w.U32(0);  // lifetime: forever
  w.U8(0);             // frame_locked
  w.U32(static_cast<uint32_t>(points.size()));
  for (const Point2& p : points) w.F64(p.x), w.F64(p.y), w.F64(0);
  w.U32(0);       // colors
  w.String("");   // texture_resource
  w.Header(0, "");  // texture: header, format, data
  w.String("");
  w.U32(0);
  w.U32(0);  // uv_coordinates
  w.String(text);
  w.String("");  // mesh_resource
  w.String("");  // mesh_file: filename, data
  w.U32(0);
  w.U8(0);  // mesh_use_embedded_materials
}

std::string Changes(int64_t stamp, const std::vector<ResultSceneHit>& hits) {
  size_t masks = 0;
  for (const ResultSceneHit& h : hits) masks += h.masks.size();
  CdrWriter w;
  w.U32(static_cast<uint32_t>(2 * masks));
  const float red[4] = {0.9f, 0.1f, 0.1f, 0.9f}, white[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  for (const ResultSceneHit& h : hits) {
    const std::string ns = "hit_" + std::to_string(h.rank);
    for (size_t m = 0; m < h.masks.size(); ++m) {
      const int32_t id = static_cast<int32_t>(m + 1);
      Marker(w, stamp, ns, id, 7, Pose2{}, 0.12, red, h.masks[m], "");  // SPHERE_LIST
      Point2 centre;
      for (const Point2& p : h.masks[m]) centre.x += p.x / h.masks[m].size(), centre.y += p.y / h.masks[m].size();
      Marker(w, stamp, ns + "/label", id, 9, Pose2{centre.x, centre.y + 0.4, 0}, 0.3, white, {},
             "change " + std::to_string(m + 1) + " vs " + h.map_id);  // TEXT_VIEW_FACING
    }
  }
  return w.data();
}

std::string Tf(int64_t stamp, const std::vector<ResultSceneHit>& hits) {
  CdrWriter w;
  w.U32(static_cast<uint32_t>(hits.size()));
  for (const ResultSceneHit& h : hits) {
    w.Header(stamp, "query");
    w.String("hit_" + std::to_string(h.rank));
    PoseOf(w, Inverse(h.query_in_db));  // the stored map's frame in the query's
  }
  return w.data();
}

// rosbag2's QoS metadata: tf_static is transient local (latched), the rest the defaults.
std::string Qos(bool latched) {
  return std::string("- history: 3\n  depth: 0\n  reliability: 1\n  durability: ") + (latched ? "1" : "2") +
         "\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n  lifespan:\n    sec: 9223372036\n"
         "    nsec: 854775807\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 9223372036\n"
         "    nsec: 854775807\n  avoid_ros_namespace_conventions: false\n";
}

}  // namespace

std::string RenderResultMcap(const ResultScene& scene) {
  McapWriter w;
  const uint16_t cloud = w.AddSchema("sensor_msgs/msg/PointCloud2", "ros2msg", PointCloud2Schema());
  const uint16_t path = w.AddSchema("nav_msgs/msg/Path", "ros2msg", PathSchema());
  const uint16_t markers = w.AddSchema("visualization_msgs/msg/MarkerArray", "ros2msg", MarkerArraySchema());
  const uint16_t tf = w.AddSchema("tf2_msgs/msg/TFMessage", "ros2msg", TfSchema());
  auto channel = [&](uint16_t schema, const std::string& topic, bool latched = false) {
    return w.AddChannel(schema, topic, "cdr", {{"offered_qos_profiles", Qos(latched)}});
  };
  const uint64_t t = static_cast<uint64_t>(std::max<int64_t>(scene.stamp_ns, 0));
  uint32_t seq = 0;
  w.AddMessage(channel(tf, "/tf_static", true), seq++, t, t, Tf(scene.stamp_ns, scene.hits));
  if (scene.query != nullptr) {
    w.AddMessage(channel(cloud, "/lmd/query"), seq++, t, t, PointCloud(scene.stamp_ns, "query", scene.query->points));
    w.AddMessage(channel(path, "/lmd/query/trajectory"), seq++, t, t,
                 Path(scene.stamp_ns, "query", scene.query->trajectory));
  }
  for (const ResultSceneHit& h : scene.hits) {
    if (h.map == nullptr) continue;
    const std::string frame = "hit_" + std::to_string(h.rank);
    w.AddMessage(channel(cloud, "/lmd/" + frame), seq++, t, t, PointCloud(scene.stamp_ns, frame, h.map->points));
  }
  w.AddMessage(channel(markers, "/lmd/changes"), seq++, t, t, Changes(scene.stamp_ns, scene.hits));
  return w.Finish();
}

}  // namespace lmd
