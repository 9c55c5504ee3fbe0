// CARMEN log reading: real logs, record types, malformed input.
#include "core/io/carmen_reader.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <streambuf>
#include <string>

namespace lmd {
namespace {

std::string TempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("lmd_reader_test_" + name)).string();
}

void WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

std::string FlaserLine(int n, double range, double x, double y, double theta) {
  std::ostringstream s;
  s << "FLASER " << n;
  for (int i = 0; i < n; ++i) s << ' ' << range;
  s << ' ' << x << ' ' << y << ' ' << theta << ' ' << x << ' ' << y << ' ' << theta << " 1.0 host 1.0\n";
  return s.str();
}

Result<LaserLog> Parse(const std::string& text) {
  std::istringstream in(text);
  return ParseCarmenLog(in, "test.log");
}

TEST(CarmenReader, FlaserEvenBeamCountIsCentredOnTheHeading) {
  auto log = Parse(FlaserLine(180, 2.0, 1.0, 2.0, 0.5));
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  ASSERT_EQ(log->scans.size(), 1u);
  const Scan& s = log->scans[0];
  EXPECT_EQ(s.ranges.size(), 180u);
  EXPECT_NEAR(s.angle_step, M_PI / 180, 1e-7);
  EXPECT_NEAR(s.first_angle, -M_PI / 2 + M_PI / 360, 1e-6);
  // Symmetric about the heading: last beam at +89.5 deg.
  EXPECT_NEAR(s.first_angle + 179 * s.angle_step, M_PI / 2 - M_PI / 360, 1e-5);
  EXPECT_DOUBLE_EQ(s.pose.x, 1.0);
  EXPECT_DOUBLE_EQ(s.pose.y, 2.0);
  EXPECT_DOUBLE_EQ(s.pose.theta, 0.5);
  EXPECT_FLOAT_EQ(s.ranges[7], 2.0f);
}

TEST(CarmenReader, FlaserOddBeamCountIncludesTheEndPoints) {
  auto log = Parse(FlaserLine(361, 2.0, 0, 0, 0));
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  const Scan& s = log->scans[0];
  EXPECT_NEAR(s.first_angle, -M_PI / 2, 1e-6);
  EXPECT_NEAR(s.angle_step, M_PI / 360, 1e-7);
  EXPECT_NEAR(s.first_angle + 360 * s.angle_step, M_PI / 2, 1e-5);
}

TEST(CarmenReader, RangesAtOrBeyondTheUsableMaximumMeanNoReturn) {
  auto log = Parse(FlaserLine(180, 81.91, 0, 0, 0));
  ASSERT_TRUE(log.ok());
  const Scan& s = log->scans[0];
  EXPECT_FLOAT_EQ(s.max_range, 30.0f);
  EXPECT_GE(s.ranges[0], s.max_range);
  CarmenReadOptions opt;
  opt.max_usable_range = 100.0f;
  std::istringstream in(FlaserLine(180, 81.91, 0, 0, 0));
  auto wide = ParseCarmenLog(in, "x", opt);
  ASSERT_TRUE(wide.ok());
  EXPECT_LT(wide->scans[0].ranges[0], wide->scans[0].max_range);
}

TEST(CarmenReader, SkipsCommentsAndUnknownRecords) {
  const std::string text = "# comment\nPARAM robot_use_laser on nohost 0\n\nNEFF 12 3\nSYNC x\n" +
                           FlaserLine(180, 1, 0, 0, 0) + "ODOM 1 2 3 0 0 0 0 h 0\n" +
                           FlaserLine(180, 1, 1, 0, 0);
  auto log = Parse(text);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  EXPECT_EQ(log->scans.size(), 2u);
}

TEST(CarmenReader, RobotLaserCarriesItsOwnGeometryAndLaserPose) {
  std::ostringstream t;
  t << "ROBOTLASER1 0 -1.5 3.0 0.01 20 0.01 0 5 1 2 3 4 25 0 7 8 0.25 0 0 0 0 0 0 0 0 1.0 h 1.0\n";
  auto log = Parse(t.str());
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  const Scan& s = log->scans[0];
  EXPECT_EQ(s.ranges.size(), 5u);
  EXPECT_FLOAT_EQ(s.first_angle, -1.5f);
  EXPECT_FLOAT_EQ(s.angle_step, 0.01f);
  EXPECT_FLOAT_EQ(s.max_range, 20.0f);
  EXPECT_GE(s.ranges[4], s.max_range);  // 25 >= 20: no return
  EXPECT_DOUBLE_EQ(s.pose.x, 7);
  EXPECT_DOUBLE_EQ(s.pose.theta, 0.25);
}

TEST(CarmenReader, RawLaserTakesThePoseOfTheLatestOdomOrPosLine) {
  const std::string text =
      "ODOM 1 2 0.1 0 0 0 0 h 0\n"
      "RAWLASER1 0 -1.57 3.14 0.0174 30 0.01 0 3 1 2 3 0 0 h 0\n"
      "POS 5 6 0.2 0 0 0 h 0\n"
      "RAWLASER1 0 -1.57 3.14 0.0174 30 0.01 0 3 1 2 3 0 0 h 0\n";
  auto log = Parse(text);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  ASSERT_EQ(log->scans.size(), 2u);
  EXPECT_DOUBLE_EQ(log->scans[0].pose.x, 1);
  EXPECT_DOUBLE_EQ(log->scans[1].pose.x, 5);
  EXPECT_DOUBLE_EQ(log->scans[1].pose.theta, 0.2);
}

// Expects a failed read whose message contains `where` and `what`.
void ExpectError(const Result<LaserLog>& r, const std::string& where, const std::string& what) {
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find(where), std::string::npos) << r.status().ToString();
  EXPECT_NE(r.status().message().find(what), std::string::npos) << r.status().ToString();
}

TEST(CarmenReader, TruncatedLineNamesFileAndLine) {
  std::string line = FlaserLine(180, 1, 0, 0, 0);
  line = line.substr(0, line.size() / 2) + "\n";
  ExpectError(Parse("# c\n" + line), "test.log:2:", "fields");
}

TEST(CarmenReader, TextInANumberNamesTheField) {
  std::string line = FlaserLine(180, 1, 0, 0, 0);
  line.replace(line.find(" 1 "), 3, " 1x ");
  ExpectError(Parse(line), "test.log:1:", "not a number: '1x'");
}

// A binary token once came back whole (up to a 4 MiB line) in the message.
TEST(CarmenReader, ABinaryTokenIsQuotedShortAndEscaped) {
  const std::string binary(1000, '\x80');
  auto r = Parse("FLASER " + binary + " 1 2 3\n");
  ExpectError(r, "test.log:1:", "FLASER beam count is not an integer: '\\x80\\x80");
  EXPECT_LT(r.status().message().size(), 500u) << r.status().message();
  EXPECT_NE(r.status().message().find("...'"), std::string::npos) << r.status().message();
}

TEST(CarmenReader, RobotLaserWithoutAPositiveResolutionIsAnError) {
  ExpectError(Parse("ROBOTLASER1 0 -1.5 3.0 0 20 0.01 0 5 1 2 3 4 25 0 7 8 0.25 0 0 0 0 0 0 0 0 1.0 h 1.0\n"),
              "test.log:1:", "angular resolution must be in (0, pi]");
}

TEST(CarmenReader, WrongBeamCountIsAnError) {
  std::string line = FlaserLine(180, 1, 0, 0, 0);
  line.replace(0, 10, "FLASER 181");
  ExpectError(Parse(line), "test.log:1:", "181 beams");
  ExpectError(Parse("FLASER -3 1 2 3\n"), "test.log:1:", "beam count");
  ExpectError(Parse("FLASER abc 1 2 3\n"), "test.log:1:", "not an integer");
}

TEST(CarmenReader, NanOrInfinitePoseIsAnError) {
  ExpectError(Parse(FlaserLine(180, 1, 0, 0, 0) + FlaserLine(180, 1, NAN, 0, 0)), "test.log:2:",
              "pose x is not finite");
  ExpectError(Parse(FlaserLine(180, 1, 0, INFINITY, 0)), "test.log:1:", "pose y is not finite");
}

// A corrupt pose far away used to make local-map building step through its
// whole travel, 1 m at a time (lmdctl ingest never ended on 1e300).
TEST(CarmenReader, AFarAwayOrNonAnglePoseIsAnError) {
  ExpectError(Parse(FlaserLine(180, 1, 0, 0, 0) + FlaserLine(180, 1, 1e300, 0, 0)), "test.log:2:",
              "more than 1e6 m from the origin");
  ExpectError(Parse(FlaserLine(180, 1, 0, -2e6, 0)), "test.log:1:", "more than 1e6 m");
  ExpectError(Parse(FlaserLine(180, 1, 0, 0, 1e30)), "test.log:1:", "pose theta is not an angle");
  EXPECT_TRUE(Parse(FlaserLine(180, 1, 9e5, -9e5, -6.2)).ok());
}

TEST(CarmenReader, RawLaserWithoutAPoseIsAnError) {
  ExpectError(Parse("RAWLASER1 0 -1.57 3.14 0.0174 30 0.01 0 3 1 2 3 0 0 h 0\n"), "test.log:1:", "no pose");
}

TEST(CarmenReader, EmptyOrLaserlessLogIsAnError) {
  ExpectError(Parse(""), "test.log", "no laser record");
  ExpectError(Parse("# only\nPARAM a b\n"), "test.log:2:", "no laser record");
}

// `size` zero bytes without a newline (as /dev/zero gives), counting how
// many of them were read.
class ZeroBytes : public std::streambuf {
 public:
  explicit ZeroBytes(size_t size) : left_(size) {}
  size_t read() const { return read_; }

 protected:
  int_type underflow() override {
    if (left_ == 0) return traits_type::eof();
    const size_t n = std::min(left_, buffer_.size());
    left_ -= n;
    read_ += n;
    setg(buffer_.data(), buffer_.data(), buffer_.data() + n);
    return traits_type::to_int_type(buffer_[0]);
  }

 private:
  std::array<char, 1 << 16> buffer_{};
  size_t left_;
  size_t read_ = 0;
};

// `lmdctl ingest --log /dev/zero` once read until memory ran out: a line is
// bounded, and the read stops at the first line beyond the bound.
TEST(CarmenReader, ALineBeyondTheBoundStopsTheReadAndNamesTheLine) {
  ZeroBytes zeros(size_t{64} << 20);
  std::istream in(&zeros);
  ExpectError(ParseCarmenLog(in, "zeros.log"), "zeros.log:1:", "line longer than 4 MiB");
  EXPECT_LE(zeros.read(), size_t{5} << 20);
  ExpectError(Parse(FlaserLine(180, 1, 0, 0, 0) + std::string(size_t{5} << 20, 'x') + "\n"), "test.log:2:",
              "line longer than 4 MiB");
  // A record with far more beams than any real one (20,000: about 180 KB) is no such line.
  auto wide = Parse(FlaserLine(20000, 12.3456, 0, 0, 0));
  ASSERT_TRUE(wide.ok()) << wide.status().ToString();
  EXPECT_EQ(wide->scans[0].ranges.size(), 20000u);
}

TEST(CarmenReader, MissingFileIsNotFound) {
  auto r = ReadCarmenLog(TempPath("does_not_exist.log"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), Status::Code::kNotFound);
  EXPECT_NE(r.status().message().find("does_not_exist.log"), std::string::npos);
}

TEST(CarmenReader, GzipIsDetectedByMagicBytesNotByName) {
  const std::string path = TempPath("gz_without_suffix.log");
  gzFile gz = gzopen(path.c_str(), "wb");
  ASSERT_NE(gz, nullptr);
  const std::string text = FlaserLine(180, 3, 0, 0, 0) + FlaserLine(180, 3, 1, 0, 0);
  gzwrite(gz, text.data(), static_cast<unsigned>(text.size()));
  gzclose(gz);
  auto r = ReadCarmenLog(path);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(r->scans.size(), 2u);
  const std::string plain = TempPath("plain.log.gz");  // plain text despite the name
  WriteFile(plain, text);
  auto p = ReadCarmenLog(plain);
  ASSERT_TRUE(p.ok()) << p.status().ToString();
  EXPECT_EQ(p->scans.size(), 2u);
  std::remove(path.c_str());
  std::remove(plain.c_str());
}

TEST(CarmenReader, CorruptGzipIsCorruptionNotACrash) {
  const std::string path = TempPath("corrupt.log.gz");
  std::string bytes = "\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03";
  for (int i = 0; i < 200; ++i) bytes.push_back(static_cast<char>((i * 37) & 0xff));
  WriteFile(path, bytes);
  auto r = ReadCarmenLog(path);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), Status::Code::kCorruption) << r.status().ToString();
  EXPECT_NE(r.status().message().find(path), std::string::npos);

  // A valid stream cut short.
  const std::string cut = TempPath("cut.log.gz");
  gzFile gz = gzopen(cut.c_str(), "wb");
  std::string text;
  for (int i = 0; i < 200; ++i) text += FlaserLine(180, 1.0 + i * 0.01, i, 0, 0);
  gzwrite(gz, text.data(), static_cast<unsigned>(text.size()));
  gzclose(gz);
  std::ifstream in(cut, std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  WriteFile(cut, all.substr(0, all.size() / 2));
  auto c = ReadCarmenLog(cut);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.status().code(), Status::Code::kCorruption) << c.status().ToString();
  std::remove(path.c_str());
  std::remove(cut.c_str());
}

struct RealLog {
  const char* file;
  size_t scans;
  size_t beams;
};

TEST(CarmenReader, ReadsAllNineRealLogsWithTheReadmeCounts) {
  const std::string dir = LMD_SHARED_DATA_DIR;
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "real logs not found in " << dir;
  const RealLog logs[] = {{"aces.log.gz", 440, 180},     {"csail.log.gz", 406, 361},
                          {"edmonton.log.gz", 340, 180}, {"fr079.log.gz", 4791, 360},
                          {"fr101.log.gz", 292, 360},    {"frcampus.log.gz", 2008, 360},
                          {"intel.log.gz", 910, 180},    {"mit.log.gz", 1941, 180},
                          {"orebro.log.gz", 237, 181}};
  const auto t0 = std::chrono::steady_clock::now();
  for (const RealLog& l : logs) {
    auto r = ReadCarmenLog(dir + "/" + l.file);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_EQ(r->scans.size(), l.scans) << l.file;
    size_t wrong_beams = 0, returns = 0, beams = 0;
    for (const Scan& s : r->scans) {
      if (s.ranges.size() != l.beams) ++wrong_beams;
      for (float x : s.ranges) returns += x < s.max_range ? 1 : 0;
      beams += s.ranges.size();
    }
    EXPECT_EQ(wrong_beams, 0u) << l.file;
    EXPECT_GT(returns, beams / 2) << l.file << ": most beams should hit something";
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RecordProperty("read_all_seconds", std::to_string(secs));
}

}  // namespace
}  // namespace lmd
