#include "core/io/carmen_writer.h"

#include <zlib.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <string>

namespace lmd {
namespace {

void Append(std::string* out, double v, int precision) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed, precision);
  out->append(buf, r.ptr);
}

bool IsFlaserGeometry(const Scan& scan) {
  const size_t n = scan.ranges.size();
  if (n < 2) return false;
  double step = 0, first = 0;
  if (n % 2 == 0) {
    step = M_PI / static_cast<double>(n);
    first = -M_PI / 2 + step / 2;
  } else {
    step = M_PI / static_cast<double>(n - 1);
    first = -M_PI / 2;
  }
  return std::abs(scan.angle_step - step) < 1e-6 && std::abs(scan.first_angle - first) < 1e-5;
}

void AppendRanges(const Scan& scan, std::string* line) {
  for (float r : scan.ranges) {
    line->push_back(' ');
    Append(line, r >= scan.max_range ? scan.max_range : (r < 0 ? 0.0 : r), 3);
  }
}

void AppendPose(const Pose2& p, std::string* line) {
  line->push_back(' ');
  Append(line, p.x, 6);
  line->push_back(' ');
  Append(line, p.y, 6);
  line->push_back(' ');
  Append(line, p.theta, 6);
}

// One record (with its newline) for scan number `index`.
void FormatScan(const Scan& scan, size_t index, std::string* line) {
  line->clear();
  if (IsFlaserGeometry(scan)) {
    line->append("FLASER ");
    line->append(std::to_string(scan.ranges.size()));
    AppendRanges(scan, line);
    AppendPose(scan.pose, line);
    AppendPose(scan.pose, line);
  } else {
    const size_t n = scan.ranges.size();
    line->append("ROBOTLASER1 0 ");
    Append(line, scan.first_angle, 9);
    line->push_back(' ');
    Append(line, scan.angle_step * static_cast<double>(n > 0 ? n - 1 : 0), 9);
    line->push_back(' ');
    Append(line, scan.angle_step, 9);
    line->push_back(' ');
    Append(line, scan.max_range, 3);
    line->append(" 0.01 0 ");
    line->append(std::to_string(n));
    AppendRanges(scan, line);
    line->append(" 0");
    AppendPose(scan.pose, line);
    AppendPose(scan.pose, line);
    line->append(" 0 0 0 0 0");
  }
  const double t = 0.1 * static_cast<double>(index);
  line->push_back(' ');
  Append(line, t, 3);
  line->append(" lmd ");
  Append(line, t, 3);
  line->push_back('\n');
}

constexpr char kHeader[] = "# CARMEN laser log written by lmd (FLASER / ROBOTLASER1; ranges in m, poses in m, rad)\n";

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

Status WriteCarmenLog(std::ostream& out, const LaserLog& log) {
  out << kHeader;
  std::string line;
  for (size_t i = 0; i < log.scans.size(); ++i) {
    FormatScan(log.scans[i], i, &line);
    out.write(line.data(), static_cast<std::streamsize>(line.size()));
  }
  out.flush();
  if (!out) return Status::IoError("cannot write the CARMEN log stream");
  return Status::Ok();
}

Status WriteCarmenLog(const std::string& path, const LaserLog& log) {
  if (!EndsWith(path, ".gz")) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) return Status::IoError(path + ": cannot open for writing");
    Status s = WriteCarmenLog(out, log);
    out.close();
    if (!s.ok() || !out) return Status::IoError(path + ": write failed");
    return Status::Ok();
  }
  gzFile gz = gzopen(path.c_str(), "wb6");
  if (gz == nullptr) return Status::IoError(path + ": cannot open for writing");
  bool ok = gzputs(gz, kHeader) >= 0;
  std::string line;
  for (size_t i = 0; ok && i < log.scans.size(); ++i) {
    FormatScan(log.scans[i], i, &line);
    ok = gzwrite(gz, line.data(), static_cast<unsigned>(line.size())) == static_cast<int>(line.size());
  }
  if (gzclose(gz) != Z_OK) ok = false;
  if (!ok) return Status::IoError(path + ": write failed");
  return Status::Ok();
}

}  // namespace lmd
