#include "client/points_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string_view>

#include "core/util/line_splitter.h"
#include "core/util/quoted.h"

namespace lmd::client {
namespace {

// Reads exactly `count` finite numbers and nothing else from `in`.
bool ReadNumbers(std::istringstream& in, int count, double* out) {
  for (int i = 0; i < count; ++i) {
    if (!(in >> out[i]) || !std::isfinite(out[i])) return false;
  }
  std::string rest;
  return !(in >> rest);
}

// A points line is "x y", "pose x y theta" or "heading_drift r" with perhaps a comment; a
// longer one is not a points file (binary data, /dev/zero, which once grew
// lmdctl's memory for ever): refusing it bounds memory.
constexpr size_t kMaxLineBytes = 64 << 10;

// One line of a points file into *map; `where` ("file:line") names it in errors.
Status ParsePointsLine(std::string line, const std::string& where, v1::LocalMap* map) {
  const auto hash = line.find('#');
  if (hash != std::string::npos) line.resize(hash);
  std::istringstream in(line);
  std::string first;
  if (!(in >> first)) return Status::Ok();
  double values[3];
  if (first == "pose") {
    if (!ReadNumbers(in, 3, values)) {
      return Status::InvalidArgument(where + ": expected 'pose x y theta' with finite numbers");
    }
    v1::Pose2* pose = map->add_trajectory();
    pose->set_x(values[0]);
    pose->set_y(values[1]);
    pose->set_theta(values[2]);
    return Status::Ok();
  }
  if (first == "heading_drift") {
    if (!ReadNumbers(in, 1, values)) {
      return Status::InvalidArgument(where + ": expected 'heading_drift r' with a finite number (rad per metre)");
    }
    map->set_heading_drift_rad_per_m(values[0]);
    return Status::Ok();
  }
  std::istringstream point(line);
  if (!ReadNumbers(point, 2, values)) {
    return Status::InvalidArgument(where + ": expected 'x y' with finite numbers, got " + Quoted(line));
  }
  // Points travel as floats: a larger value would arrive infinite.
  if (std::fabs(values[0]) > std::numeric_limits<float>::max() ||
      std::fabs(values[1]) > std::numeric_limits<float>::max()) {
    return Status::InvalidArgument(where + ": a coordinate is beyond the float range (about 3.4e38)");
  }
  map->add_x(static_cast<float>(values[0]));
  map->add_y(static_cast<float>(values[1]));
  return Status::Ok();
}

}  // namespace

Result<v1::LocalMap> ReadPointsFile(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return Status::InvalidArgument(path + " is a directory, not a points file");
  std::ifstream file(path);
  if (!file) return Status::IoError("cannot read points file " + path);
  v1::LocalMap map;
  LineSplitter lines(path, kMaxLineBytes, "a points file holds 'x y' lines",
                     [&](size_t number, std::string_view text) {
                       return ParsePointsLine(std::string(text), path + ":" + std::to_string(number), &map);
                     });
  Status s = lines.FeedAll(file);
  if (s.ok()) s = lines.Finish();
  if (!s.ok()) return s;
  if (map.x_size() == 0) return Status::InvalidArgument(path + ": no points");
  return map;
}

Status WritePointsFile(const std::string& path, const v1::LocalMap& map) {
  std::ofstream out(path);
  if (!out) return Status::IoError("cannot write points file " + path);
  out << "# lmd points file: x y (m, own frame); pose x y theta; heading_drift r\n";
  if (map.heading_drift_rad_per_m() != 0) {  // as sent: read back, it is the same double
    out << "heading_drift " << std::setprecision(std::numeric_limits<double>::max_digits10)
        << map.heading_drift_rad_per_m() << std::setprecision(6) << '\n';
  }
  for (const auto& pose : map.trajectory()) out << "pose " << pose.x() << ' ' << pose.y() << ' ' << pose.theta() << '\n';
  for (int i = 0; i < map.x_size(); ++i) out << map.x(i) << ' ' << map.y(i) << '\n';
  out.close();
  return out ? Status::Ok() : Status::IoError("writing " + path + " failed");
}

}  // namespace lmd::client
