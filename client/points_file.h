// The plain points file lmdctl reads a local map from:
//
//   # comment (from '#' to the end of the line)
//   1.25 -0.40            a point: x y, metres, the map's own frame
//   pose 0.0 0.0 1.5708   a trajectory pose: x y (m) theta (rad), optional
//   heading_drift 0.0087  how far the poses may turn per metre (rad; LocalMap.heading_drift_rad_per_m), optional
//
// Blank lines are skipped. Anything else is an error naming file:line.
#pragma once

#include <string>

#include "core/status.h"
#include "lmd/v1/lmd.pb.h"

namespace lmd::client {

// IoError if the file cannot be read; InvalidArgument naming file:line for a
// malformed line (quoting at most 80 characters of it, escaped), a
// non-finite number or a line longer than 64 KiB (the read stops there), or
// if the file holds no point.
Result<v1::LocalMap> ReadPointsFile(const std::string& path);

// Writes `map` in the format above. IoError if the file cannot be written.
Status WritePointsFile(const std::string& path, const v1::LocalMap& map);

}  // namespace lmd::client
