#include "server/validate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lmd::server {
namespace {

bool AllCharsIn(const std::string& s, const std::string& extra) {
  for (char c : s) {
    const bool alnum = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (!alnum && extra.find(c) == std::string::npos) return false;
  }
  return true;
}

// What a map id is (ValidateMapId); a page token is one too.
constexpr char kMapIdForm[] = "1 to 128 characters from [A-Za-z0-9._:-]";
// A bound on odometry's heading drift (LocalMap.heading_drift_rad_per_m):
// 29 deg per metre is no odometry; beyond it the value is a mistake.
constexpr double kMaxHeadingDriftRadPerM = 0.5;
bool IsMapId(const std::string& s) { return !s.empty() && s.size() <= 128 && AllCharsIn(s, "._:-"); }

// "12.5": metres for messages, without trailing zeros.
std::string Metres(double m) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", m);
  return buffer;
}

bool CoordinateOk(double v, double limit) { return std::isfinite(v) && std::fabs(v) <= limit; }

// OK if v is finite and |v| <= limit; otherwise says which value is bad.
Status CheckCoordinate(double v, double limit, const std::string& what) {
  if (std::isnan(v)) return Status::InvalidArgument(what + " is NaN");
  if (std::isinf(v)) return Status::InvalidArgument(what + " is infinite");
  if (std::fabs(v) > limit) {
    return Status::InvalidArgument(what + " = " + Metres(v) + " m exceeds max_abs_coordinate_m (" + Metres(limit) +
                                   ")");
  }
  return Status::Ok();
}

bool PoseOk(const v1::Pose2& pose, double limit) {
  return CoordinateOk(pose.x(), limit) && CoordinateOk(pose.y(), limit) && std::isfinite(pose.theta());
}

Status CheckPose(const v1::Pose2& pose, double limit, const std::string& what) {
  Status s = CheckCoordinate(pose.x(), limit, what + ".x");
  if (s.ok()) s = CheckCoordinate(pose.y(), limit, what + ".y");
  if (s.ok() && !std::isfinite(pose.theta())) s = Status::InvalidArgument(what + ".theta is not finite");
  return s;
}

// Bounding box of the map's points and poses.
struct Extent {
  double lo_x = 0, hi_x = 0, lo_y = 0, hi_y = 0;
  bool empty = true;
  void Add(double x, double y) {
    if (empty) {
      lo_x = hi_x = x, lo_y = hi_y = y, empty = false;
      return;
    }
    lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x);
    lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
  }
};

}  // namespace

Status ValidateCollectionName(const std::string& name) {
  if (name.empty()) return Status::InvalidArgument("collection is empty");
  if (name.size() > 64 || !AllCharsIn(name, "._-") || name.find_first_not_of('.') == std::string::npos) {
    return Status::InvalidArgument("collection " + Quoted(name) +
                                   " must be 1 to 64 characters from [A-Za-z0-9._-], not only dots");
  }
  return Status::Ok();
}

Status ValidateMapId(const std::string& map_id, bool allow_empty) {
  if (map_id.empty()) return allow_empty ? Status::Ok() : Status::InvalidArgument("map_id is empty");
  if (!IsMapId(map_id)) return Status::InvalidArgument("map_id " + Quoted(map_id) + " must be " + kMapIdForm);
  return Status::Ok();
}

Status ValidatePageToken(const std::string& page_token) {
  if (page_token.empty() || IsMapId(page_token)) return Status::Ok();
  return Status::InvalidArgument("page_token " + Quoted(page_token) +
                                 " is not a next_page_token of ListMaps (a map id: " + kMapIdForm + ")");
}

Status ValidateLocalMap(const v1::LocalMap& map, const ServerConfig& config, const std::string& where) {
  const double limit = config.max_abs_coordinate_m;
  if (map.x_size() != map.y_size()) {
    return Status::InvalidArgument(where + ": x has " + std::to_string(map.x_size()) + " values but y has " +
                                   std::to_string(map.y_size()));
  }
  if (map.x_size() == 0) return Status::InvalidArgument(where + ": the map has no points");
  const double drift = map.heading_drift_rad_per_m();
  if (!(drift >= 0 && drift <= kMaxHeadingDriftRadPerM)) {
    return Status::InvalidArgument(where + ": heading_drift_rad_per_m must be a number from 0 to 0.5 rad per metre, " +
                                   "got " + std::to_string(drift));
  }
  if (drift > 0 && map.trajectory_size() == 0 && map.scans_size() == 0) {
    return Status::InvalidArgument(where + ": heading_drift_rad_per_m needs the map's trajectory or scans (the path "
                                           "it bends along)");
  }
  if (static_cast<uint32_t>(map.x_size()) > config.max_points_per_map) {
    return Status::InvalidArgument(where + ": " + std::to_string(map.x_size()) +
                                   " points exceed max_points_per_map (" +
                                   std::to_string(config.max_points_per_map) + ")");
  }
  Extent extent;
  // The messages are built only for a bad value (a map has thousands of points).
  for (int i = 0; i < map.x_size(); ++i) {
    if (CoordinateOk(map.x(i), limit) && CoordinateOk(map.y(i), limit)) {
      extent.Add(map.x(i), map.y(i));
      continue;
    }
    const std::string point = where + ": point " + std::to_string(i);
    Status s = CheckCoordinate(map.x(i), limit, point + " x");
    if (s.ok()) s = CheckCoordinate(map.y(i), limit, point + " y");
    return s;
  }
  for (int i = 0; i < map.trajectory_size(); ++i) {
    if (PoseOk(map.trajectory(i), limit)) {
      extent.Add(map.trajectory(i).x(), map.trajectory(i).y());
      continue;
    }
    return CheckPose(map.trajectory(i), limit, where + ": trajectory pose " + std::to_string(i));
  }
  if (static_cast<uint32_t>(map.scans_size()) > config.max_scans_per_map) {
    return Status::InvalidArgument(where + ": " + std::to_string(map.scans_size()) +
                                   " scans exceed max_scans_per_map (" + std::to_string(config.max_scans_per_map) +
                                   ")");
  }
  for (int i = 0; i < map.scans_size(); ++i) {
    const v1::Scan& scan = map.scans(i);
    const std::string name = where + ": scan " + std::to_string(i);
    if (!PoseOk(scan.pose(), limit)) return CheckPose(scan.pose(), limit, name + " pose");
    if (!(scan.angle_step() > 0) || !std::isfinite(scan.angle_step())) {
      return Status::InvalidArgument(name + ": angle_step must be a positive finite number of radians");
    }
    if (!std::isfinite(scan.first_angle())) {
      return Status::InvalidArgument(name + ": first_angle must be a finite number of radians");
    }
    if (!(scan.max_range() > 0) || !(scan.max_range() <= config.max_map_extent_m)) {
      return Status::InvalidArgument(name + ": max_range must be a positive number of metres up to max_map_extent_m (" +
                                     Metres(config.max_map_extent_m) + ")");
    }
    extent.Add(scan.pose().x(), scan.pose().y());
    if (static_cast<uint32_t>(scan.ranges_size()) > config.max_beams_per_scan) {
      return Status::InvalidArgument(name + ": " + std::to_string(scan.ranges_size()) +
                                     " beams exceed max_beams_per_scan (" +
                                     std::to_string(config.max_beams_per_scan) + ")");
    }
    for (int b = 0; b < scan.ranges_size(); ++b) {
      if (std::isnan(scan.ranges(b)) || scan.ranges(b) < 0) {
        return Status::InvalidArgument(name + ": range " + std::to_string(b) + " is negative or NaN");
      }
    }
  }
  const double width = extent.hi_x - extent.lo_x, height = extent.hi_y - extent.lo_y;
  if (width > config.max_map_extent_m || height > config.max_map_extent_m) {
    return Status::InvalidArgument(where + ": the map spans " + Metres(width) + " x " + Metres(height) +
                                   " m, more than max_map_extent_m (" + Metres(config.max_map_extent_m) + ")");
  }
  return Status::Ok();
}

Status ValidateInsert(const v1::InsertMapRequest& request, const ServerConfig& config, size_t index) {
  const v1::MapMetadata& meta = request.metadata();
  std::string where = "map " + std::to_string(index);
  if (!meta.map_id().empty()) where += " (" + Quoted(meta.map_id()) + ")";
  Status s = ValidateCollectionName(meta.collection());
  if (s.ok()) s = ValidateMapId(meta.map_id(), /*allow_empty=*/true);
  if (s.ok() && meta.has_pose_hint()) s = CheckPose(meta.pose_hint(), config.max_abs_coordinate_m, "pose_hint");
  if (!s.ok()) return Status::InvalidArgument(where + ": " + s.message());
  return ValidateLocalMap(request.map(), config, where);
}

Status ValidateRequestId(const std::string& request_id) {
  const bool printable = std::all_of(request_id.begin(), request_id.end(), [](char c) { return c > ' ' && c <= '~'; });
  if (request_id.size() > 64 || !printable) {
    return Status::InvalidArgument("request_id must be at most 64 printable ASCII characters without spaces");
  }
  return Status::Ok();
}

Status ValidatePriorAndSequence(bool has_prior, const v1::Prior& prior,
                                const google::protobuf::RepeatedPtrField<v1::SequenceMap>& sequence,
                                const ServerConfig& config) {
  if (has_prior && !sequence.empty()) {
    return Status::InvalidArgument("a query takes a prior or a sequence, not both");
  }
  if (has_prior) {
    Status s = CheckPose(prior.pose(), config.max_abs_coordinate_m, "prior.pose");
    if (s.ok() && !(prior.radius_m() > 0 && prior.radius_m() <= 100)) {
      s = Status::InvalidArgument("prior.radius_m must be in (0, 100] m, got " + std::to_string(prior.radius_m()));
    }
    if (s.ok() && !(prior.heading_sigma_rad() >= 0 && std::isfinite(prior.heading_sigma_rad()))) {
      s = Status::InvalidArgument("prior.heading_sigma_rad must be a finite angle >= 0");
    }
    if (!s.ok()) return s;
  }
  if (static_cast<uint32_t>(sequence.size()) > config.max_sequence_maps) {
    return Status::InvalidArgument(std::to_string(sequence.size()) + " sequence maps exceed max_sequence_maps (" +
                                   std::to_string(config.max_sequence_maps) + ")");
  }
  for (int i = 0; i < sequence.size(); ++i) {
    const std::string where = "sequence[" + std::to_string(i) + "]";
    const v1::SequenceMap& step = sequence[i];
    if (!step.has_in_query()) return Status::InvalidArgument(where + ".in_query (its pose relative to the query) is missing");
    Status s = CheckPose(step.in_query(), config.max_abs_coordinate_m, where + ".in_query");
    if (s.ok() && !(step.travel_m() >= 0 && std::isfinite(step.travel_m()))) {
      s = Status::InvalidArgument(where + ".travel_m must be a finite distance >= 0");
    }
    if (s.ok()) s = ValidateLocalMap(step.map(), config, where + ".map");
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

}  // namespace lmd::server
