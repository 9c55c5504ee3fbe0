// Reader for CARMEN laser logs (plain text or gzip, detected by magic bytes).
//
// Records read (one per line, fields separated by blanks):
//   FLASER n r_1..r_n x y theta odom_x odom_y odom_theta [ts host ts]
//       180 deg centred on the heading. n even (180, 360): n beams with
//       centres at -90 + step/2, ..., +90 - step/2 deg, step = 180/n;
//       n odd (181, 361): end points included, -90..+90, step = 180/(n-1).
//   ROBOTLASER1 type start fov res max_range acc rmode n r_1..r_n m e_1..e_m
//       laser_x laser_y laser_theta robot_x robot_y robot_theta ...
//       (ROBOTLASER2 alike); pose = laser pose.
//   RAWLASER1 type start fov res max_range acc rmode n r_1..r_n m e_1..e_m ...
//       (RAWLASER2..4 alike); pose = the latest ODOM / POS / TRUEPOS line
//       before it (x y theta = its first three fields); a RAWLASER before any
//       such line is an error.
// Skipped: empty lines, lines starting with '#', every other record type
// (PARAM, NEFF, SYNC, RLASER, ...). Order is line order; timestamps ignored.
//
// Ranges: a reading >= the scan's max_range means "no return" (free space up
// to max_range, no point). Scan::max_range = min(max_usable_range, the
// record's own maximum if it has one). Readings below min_valid_range are
// invalid and stored as max_range.
#pragma once

#include <istream>
#include <string>

#include "core/io/laser_log.h"
#include "core/status.h"

namespace lmd {

struct CarmenReadOptions {
  // m. Readings at or above this are "no return". Default 30 m: below every
  // no-return sentinel of the nine real logs (32.77, 50.0, ~51.1, 81.83,
  // 81.91 m; edmonton/mit's sentinel is noisy, 51.05..51.16) and the SICK
  // LMS's rated range; the few real returns beyond 30 m are dropped.
  float max_usable_range = 30.0f;
  // m. Readings below this (0 = sensor error) are stored as no return.
  float min_valid_range = 0.01f;
};

// Reads a CARMEN log from `path` (gzip if the file starts with 1f 8b, plain
// otherwise). Returns NotFound / IoError if the file cannot be opened or read,
// Corruption for a damaged gzip stream, InvalidArgument "<path>:<line>: ..."
// for a malformed record (wrong field count, text in a number, NaN/inf pose or
// range, bad beam count) or a line longer than 4 MiB (not a text log: the
// read stops there). The file is read as a stream, one line at a time. A
// file with no laser record is an InvalidArgument too.
Result<LaserLog> ReadCarmenLog(const std::string& path, const CarmenReadOptions& options = {});

// Same from a stream of plain text; errors name `name_for_errors`:<line>.
Result<LaserLog> ParseCarmenLog(std::istream& in, const std::string& name_for_errors,
                                const CarmenReadOptions& options = {});

// Same from a text buffer (the whole log).
Result<LaserLog> ParseCarmenText(const std::string& text, const std::string& name_for_errors,
                                 const CarmenReadOptions& options = {});

}  // namespace lmd
