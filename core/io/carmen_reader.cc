#include "core/io/carmen_reader.h"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string_view>
#include <vector>

#include "core/util/line_splitter.h"
#include "core/util/quoted.h"

namespace lmd {
namespace {

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Splits one line into blank-separated tokens (views into the text).
void Tokenize(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  size_t i = 0;
  const size_t n = line.size();
  while (i < n) {
    while (i < n && IsBlank(line[i])) ++i;
    if (i >= n) break;
    size_t j = i;
    while (j < n && !IsBlank(line[j])) ++j;
    tokens->emplace_back(line.data() + i, j - i);
    i = j;
  }
}

// Parses a whole token as a double; false on any trailing text.
bool ParseDouble(std::string_view tok, double* out) {
  char buf[64];
  if (tok.empty() || tok.size() >= sizeof(buf)) return false;
  std::memcpy(buf, tok.data(), tok.size());
  buf[tok.size()] = '\0';
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(buf, &end);
  if (end != buf + tok.size()) return false;
  *out = v;
  return true;
}

bool ParseInt(std::string_view tok, long* out) {
  char buf[32];
  if (tok.empty() || tok.size() >= sizeof(buf)) return false;
  std::memcpy(buf, tok.data(), tok.size());
  buf[tok.size()] = '\0';
  char* end = nullptr;
  const long v = std::strtol(buf, &end, 10);
  if (end != buf + tok.size()) return false;
  *out = v;
  return true;
}

constexpr long kMaxBeams = 100000;
// m. A pose coordinate beyond this is a corrupt record, not a robot's
// position (the nine real logs stay within a few hundred metres).
constexpr double kMaxPoseCoordinate = 1e6;
// rad. Headings are kept unwrapped by some loggers, but never by this much.
constexpr double kMaxPoseTheta = 1e3;

class Parser {
 public:
  Parser(const std::string& name, const CarmenReadOptions& options) : name_(name), options_(options) {}

  Status Error(size_t line, const std::string& msg) const {
    return Status::InvalidArgument(name_ + ":" + std::to_string(line) + ": " + msg);
  }

  // Reads tokens[i] as a number into *v; `what` names the field in errors.
  Status Number(size_t line, const std::vector<std::string_view>& t, size_t i, const char* what,
                double* v) const {
    if (i >= t.size()) return Error(line, std::string("missing ") + what);
    if (!ParseDouble(t[i], v)) {
      return Error(line, std::string(what) + " is not a number: " + Quoted(t[i]));
    }
    if (!std::isfinite(*v)) {
      return Error(line, std::string(what) + " is not finite: " + Quoted(t[i]));
    }
    return Status::Ok();
  }

  Status Count(size_t line, const std::vector<std::string_view>& t, size_t i, const char* what,
               long min_value, long* v) const {
    if (i >= t.size()) return Error(line, std::string("missing ") + what);
    if (!ParseInt(t[i], v)) {
      return Error(line, std::string(what) + " is not an integer: " + Quoted(t[i]));
    }
    if (*v < min_value || *v > kMaxBeams) {
      return Error(line, std::string(what) + " out of range [" + std::to_string(min_value) + ", " +
                             std::to_string(kMaxBeams) + "]: " + std::to_string(*v));
    }
    return Status::Ok();
  }

  Status Pose(size_t line, const std::vector<std::string_view>& t, size_t i, Pose2* pose) const {
    Status s = Number(line, t, i, "pose x", &pose->x);
    if (s.ok()) s = Number(line, t, i + 1, "pose y", &pose->y);
    if (s.ok()) s = Number(line, t, i + 2, "pose theta", &pose->theta);
    if (s.ok() && (std::abs(pose->x) > kMaxPoseCoordinate || std::abs(pose->y) > kMaxPoseCoordinate)) {
      s = Error(line, "pose (" + std::string(t[i]) + ", " + std::string(t[i + 1]) +
                          ") is more than 1e6 m from the origin");
    }
    if (s.ok() && std::abs(pose->theta) > kMaxPoseTheta) {
      s = Error(line, "pose theta is not an angle: " + Quoted(t[i + 2]));
    }
    return s;
  }

  // Reads n ranges starting at tokens[i] into scan->ranges, applying the
  // max / min range rules (scan->max_range must be set).
  Status Ranges(size_t line, const std::vector<std::string_view>& t, size_t i, long n, Scan* scan) const {
    scan->ranges.resize(static_cast<size_t>(n));
    for (long k = 0; k < n; ++k) {
      double r = 0.0;
      if (!ParseDouble(t[i + static_cast<size_t>(k)], &r)) {
        return Error(line, "range " + std::to_string(k + 1) + " is not a number: " +
                               Quoted(t[i + static_cast<size_t>(k)]));
      }
      if (!std::isfinite(r)) {
        return Error(line, "range " + std::to_string(k + 1) + " is not finite");
      }
      float f = static_cast<float>(r);
      if (f >= scan->max_range || f < options_.min_valid_range) f = scan->max_range;
      scan->ranges[static_cast<size_t>(k)] = f;
    }
    return Status::Ok();
  }

  Status Flaser(size_t line, const std::vector<std::string_view>& t, LaserLog* log) const {
    long n = 0;
    Status s = Count(line, t, 1, "FLASER beam count", 2, &n);
    if (!s.ok()) return s;
    const size_t nn = static_cast<size_t>(n);
    // FLASER n r_1..r_n x y theta odom_x odom_y odom_theta [ipc_ts host logger_ts]
    if (t.size() != nn + 8 && t.size() != nn + 11) {
      return Error(line, "FLASER with " + std::to_string(n) + " beams needs " + std::to_string(nn + 11) +
                             " fields (or " + std::to_string(nn + 8) + " without timestamps), found " +
                             std::to_string(t.size()));
    }
    Scan scan;
    scan.max_range = options_.max_usable_range;
    if (n % 2 == 0) {
      scan.angle_step = static_cast<float>(M_PI / n);
      scan.first_angle = static_cast<float>(-M_PI / 2 + M_PI / n / 2);
    } else {
      scan.angle_step = static_cast<float>(M_PI / (n - 1));
      scan.first_angle = static_cast<float>(-M_PI / 2);
    }
    s = Ranges(line, t, 2, n, &scan);
    if (!s.ok()) return s;
    s = Pose(line, t, nn + 2, &scan.pose);
    if (!s.ok()) return s;
    log->scans.push_back(std::move(scan));
    return Status::Ok();
  }

  // Shared head of ROBOTLASER1 / RAWLASER1: type start fov res max acc rmode n
  // ranges m remissions. Returns the index of the first token after them.
  Status LaserHead(size_t line, const std::vector<std::string_view>& t, Scan* scan, size_t* next) const {
    double start = 0, fov = 0, res = 0, maxr = 0, dummy = 0;
    Status s = Number(line, t, 1, "laser type", &dummy);
    if (s.ok()) s = Number(line, t, 2, "start angle", &start);
    if (s.ok()) s = Number(line, t, 3, "field of view", &fov);
    if (s.ok()) s = Number(line, t, 4, "angular resolution", &res);
    if (s.ok()) s = Number(line, t, 5, "maximum range", &maxr);
    if (s.ok()) s = Number(line, t, 6, "accuracy", &dummy);
    if (s.ok()) s = Number(line, t, 7, "remission mode", &dummy);
    if (!s.ok()) return s;
    if (!(res > 0) || res > M_PI) return Error(line, "angular resolution must be in (0, pi] rad");
    long n = 0;
    s = Count(line, t, 8, "beam count", 1, &n);
    if (!s.ok()) return s;
    const size_t nn = static_cast<size_t>(n);
    if (t.size() < 9 + nn + 1) {
      return Error(line, "expected " + std::to_string(n) + " ranges, found " +
                             std::to_string(t.size() > 9 ? t.size() - 9 : 0) + " fields");
    }
    scan->first_angle = static_cast<float>(start);
    scan->angle_step = static_cast<float>(res);
    scan->max_range = options_.max_usable_range;
    if (maxr > 0 && maxr < scan->max_range) scan->max_range = static_cast<float>(maxr);
    s = Ranges(line, t, 9, n, scan);
    if (!s.ok()) return s;
    long m = 0;
    s = Count(line, t, 9 + nn, "remission count", 0, &m);
    if (!s.ok()) return s;
    *next = 9 + nn + 1 + static_cast<size_t>(m);
    if (t.size() < *next) return Error(line, "expected " + std::to_string(m) + " remissions");
    return Status::Ok();
  }

  Status RobotLaser(size_t line, const std::vector<std::string_view>& t, LaserLog* log) const {
    Scan scan;
    size_t next = 0;
    Status s = LaserHead(line, t, &scan, &next);
    if (!s.ok()) return s;
    if (t.size() < next + 6) return Error(line, "missing laser and robot poses after the remissions");
    s = Pose(line, t, next, &scan.pose);
    if (!s.ok()) return s;
    log->scans.push_back(std::move(scan));
    return Status::Ok();
  }

  Status RawLaser(size_t line, const std::vector<std::string_view>& t, LaserLog* log) {
    Scan scan;
    size_t next = 0;
    Status s = LaserHead(line, t, &scan, &next);
    if (!s.ok()) return s;
    if (pose_line_ == 0) return Error(line, "RAWLASER before any ODOM / POS line: no pose");
    std::vector<std::string_view> pt;
    Tokenize(pose_text_, &pt);
    s = Pose(pose_line_, pt, 1, &scan.pose);
    if (!s.ok()) return s;
    log->scans.push_back(std::move(scan));
    return Status::Ok();
  }

  // One line; `line` is 1-based.
  Status Line(size_t line, std::string_view text, LaserLog* log) {
    Tokenize(text, &tokens_);
    if (tokens_.empty() || tokens_[0][0] == '#') return Status::Ok();
    const std::string_view type = tokens_[0];
    if (type == "FLASER") return Flaser(line, tokens_, log);
    if (type == "ROBOTLASER1" || type == "ROBOTLASER2") return RobotLaser(line, tokens_, log);
    if (type == "RAWLASER1" || type == "RAWLASER2" || type == "RAWLASER3" || type == "RAWLASER4") {
      return RawLaser(line, tokens_, log);
    }
    if (type == "ODOM" || type == "POS" || type == "TRUEPOS") {
      // Parsed lazily, only if a RAWLASER needs it.
      pose_text_.assign(text.data(), text.size());
      pose_line_ = line;
    }
    return Status::Ok();
  }

 private:
  const std::string& name_;
  const CarmenReadOptions& options_;
  std::vector<std::string_view> tokens_;
  std::string pose_text_;
  size_t pose_line_ = 0;
};

// A log read as it arrives, one line at a time (never the whole file).
class LogStream {
 public:
  LogStream(const std::string& name, const CarmenReadOptions& options)
      : name_(name),
        parser_(name, options),
        lines_(name, kMaxLineBytes, "a CARMEN record is a few KB: is this a CARMEN text log?",
               [this](size_t number, std::string_view text) { return parser_.Line(number, text, &log_); }) {}

  // The next bytes of the log, in pieces of any size.
  Status Feed(std::string_view bytes) { return lines_.Feed(bytes); }
  Status FeedAll(std::istream& in) { return lines_.FeedAll(in); }

  // The last line (if it has no newline) and the log.
  Result<LaserLog> Finish() {
    Status s = lines_.Finish();
    if (!s.ok()) return s;
    if (log_.scans.empty()) {
      return Status::InvalidArgument(name_ + ":" + std::to_string(lines_.lines()) +
                                     ": no laser record (FLASER, ROBOTLASER1, RAWLASER1) in " +
                                     (lines_.lines() == 0 ? "an empty log" : "the log"));
    }
    return std::move(log_);
  }

 private:
  // A real CARMEN line holds one record: at most about 2 KB in the nine real
  // logs, under 2 MiB for the largest beam count accepted (kMaxBeams ranges
  // and as many remissions). A longer "line" is not a log (binary data,
  // /dev/zero): refusing it bounds memory.
  static constexpr size_t kMaxLineBytes = 4 << 20;

  const std::string& name_;
  Parser parser_;
  LaserLog log_;
  LineSplitter lines_;
};

// The file at `path` through zlib, which reads gzip (by its magic bytes) and
// plain files alike, fed to `log` piece by piece.
Status StreamFile(const std::string& path, LogStream* log) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    const std::string msg = path + ": cannot open: " + std::strerror(err);
    return err == ENOENT ? Status::NotFound(msg) : Status::IoError(msg);
  }
  gzFile gz = gzdopen(fd, "rb");
  if (gz == nullptr) {
    ::close(fd);
    return Status::IoError(path + ": cannot open");
  }
  gzbuffer(gz, 1 << 18);
  std::vector<char> buf(1 << 18);
  for (;;) {
    const int k = gzread(gz, buf.data(), static_cast<unsigned>(buf.size()));
    if (k <= 0) break;  // the end, or an error gzerror says below
    Status s = log->Feed(std::string_view(buf.data(), static_cast<size_t>(k)));
    if (!s.ok()) {
      gzclose(gz);
      return s;
    }
  }
  int errnum = Z_OK;
  const std::string zmsg = gzerror(gz, &errnum);
  const int closed = gzclose(gz);
  if (errnum == Z_ERRNO) return Status::IoError(path + ": read error: " + zmsg);
  if (errnum != Z_OK) return Status::Corruption(path + ": corrupt gzip data: " + zmsg);  // e.g. cut short
  if (closed != Z_OK) return Status::Corruption(path + ": corrupt gzip data (bad trailer)");
  return Status::Ok();
}

}  // namespace

Result<LaserLog> ParseCarmenText(const std::string& text, const std::string& name_for_errors,
                                 const CarmenReadOptions& options) {
  LogStream log(name_for_errors, options);
  Status s = log.Feed(text);
  if (!s.ok()) return s;
  return log.Finish();
}

Result<LaserLog> ParseCarmenLog(std::istream& in, const std::string& name_for_errors,
                                const CarmenReadOptions& options) {
  LogStream log(name_for_errors, options);
  Status s = log.FeedAll(in);
  if (!s.ok()) return s;
  return log.Finish();
}

Result<LaserLog> ReadCarmenLog(const std::string& path, const CarmenReadOptions& options) {
  LogStream log(path, options);
  Status s = StreamFile(path, &log);
  if (!s.ok()) return s;
  return log.Finish();
}

}  // namespace lmd
