// lmdctl as a user runs it: exit codes, one line on stderr for errors, and
// one JSON object per line with --json.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sys/wait.h>

#include <gtest/gtest.h>

#include "core/io/carmen_reader.h"
#include "core/io/carmen_writer.h"
#include "core/localmap/local_map_builder.h"
#include "core/sim/simulate.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

int CountLines(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }
int CountOccurrences(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

class LmdctlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::ofstream points(dir_.path() + "/room.txt");
    points << "# a room\npose 0 0 0\n0 0\n1 0\n1 1\n0 1\n";
  }
  TempDir dir_;
  TempDir data_;
};

TEST_F(LmdctlTest, InsertThenListPrintsOneJsonObjectPerMap) {
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  CliRun inserted = RunLmdctl(base + "insert --collection site --id r1 --file " + dir_.path() + "/room.txt", dir_);
  ASSERT_EQ(inserted.exit_code, 0) << inserted.err;
  EXPECT_NE(inserted.out.find("inserted site/r1 (4 points)"), std::string::npos) << inserted.out;
  ASSERT_EQ(RunLmdctl(base + "insert --collection site --id r2 --file " + dir_.path() + "/room.txt", dir_).exit_code, 0);

  CliRun listed = RunLmdctl(base + "--json maps --collection site", dir_);
  ASSERT_EQ(listed.exit_code, 0) << listed.err;
  EXPECT_EQ(CountLines(listed.out), 2);
  EXPECT_EQ(listed.out.rfind("{\"id\":\"r1\",\"collection\":\"site\",\"map_id\":\"r1\"", 0), 0u) << listed.out;
}

TEST_F(LmdctlTest, AnInsertIntoACappedCollectionPrintsWhatItEvicted) {
  server::ServerConfig config;
  config.retain_maps_per_collection = 1;
  TestServer server(data_.path(), config);
  const std::string base = "--server " + server.address() + " ";
  ASSERT_EQ(RunLmdctl(base + "insert --collection site --id r1 --file " + dir_.path() + "/room.txt", dir_).exit_code, 0);
  CliRun json = RunLmdctl(base + "--json insert --collection site --id r2 --file " + dir_.path() + "/room.txt", dir_);
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_EQ(CountLines(json.out), 2);
  EXPECT_NE(json.out.find("\n{\"evicted\":\"r1\",\"collection\":\"site\"}\n"), std::string::npos) << json.out;
  CliRun text = RunLmdctl(base + "insert --collection site --id r3 --file " + dir_.path() + "/room.txt", dir_);
  EXPECT_NE(text.out.find("evicted site/r2"), std::string::npos) << text.out;
}

TEST_F(LmdctlTest, MissingMapExitsOneWithOneLineOnStderr) {
  TestServer server(data_.path());
  CliRun run = RunLmdctl("--server " + server.address() + " get --collection site --id nope", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("NOT_FOUND"), std::string::npos) << run.err;
  EXPECT_TRUE(run.out.empty());
}

TEST_F(LmdctlTest, UsageErrorsExitTwo) {
  EXPECT_EQ(RunLmdctl("frobnicate", dir_).exit_code, 2);
  EXPECT_EQ(RunLmdctl("insert --collection site", dir_).exit_code, 2);
  EXPECT_EQ(RunLmdctl("", dir_).exit_code, 2);
  EXPECT_EQ(RunLmdctl("--help", dir_).exit_code, 0);
}

TEST_F(LmdctlTest, TyposAndOutOfRangeNumbersAreUsageErrors) {
  const std::string query = "--server 127.0.0.1:1 query --collection site --file " + dir_.path() + "/room.txt ";
  CliRun typo = RunLmdctl(query + "--topk 1", dir_);
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.err.find("unknown option --topk"), std::string::npos) << typo.err;
  CliRun wrapped = RunLmdctl(query + "--top-k 4294967297", dir_);  // once wrapped to top_k 1
  EXPECT_EQ(wrapped.exit_code, 2);
  EXPECT_NE(wrapped.err.find("--top-k must be a whole number from 1 to"), std::string::npos) << wrapped.err;
}

// A bad CA file once showed as gRPC log lines and "UNAVAILABLE: empty
// address list", and a certificate without its key as "cannot read " (no
// name): each now says which file or flag is wrong, before any call.
TEST_F(LmdctlTest, BadTlsFilesAndFlagsAreNamed) {
  const std::string garbage = dir_.path() + "/garbage.pem";
  std::ofstream(garbage) << "not a certificate\n";
  CliRun run = RunLmdctl("--server 127.0.0.1:1 --tls-ca " + garbage + " collections", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("the TLS CA certificate file " + garbage + " holds no PEM CERTIFICATE"), std::string::npos)
      << run.err;
  run = RunLmdctl("--server 127.0.0.1:1 --tls-ca " + dir_.path() + "/none.pem collections", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("cannot read the TLS CA certificate file " + dir_.path() + "/none.pem: No such file"),
            std::string::npos)
      << run.err;
  const std::string pairs[][2] = {{"--tls-ca " + garbage + " --tls-cert x.pem", "--tls-cert needs --tls-key"},
                                  {"--tls-ca " + garbage + " --tls-key x.key", "--tls-key needs --tls-cert"},
                                  {"--tls-cert x.pem --tls-key x.key", "--tls-cert needs --tls-ca"}};
  for (const auto& [flags, message] : pairs) {
    run = RunLmdctl("--server 127.0.0.1:1 " + flags + " collections", dir_);
    EXPECT_EQ(run.exit_code, 2) << flags;
    EXPECT_EQ(CountLines(run.err), 1) << run.err;
    EXPECT_NE(run.err.find("lmdctl: " + message), std::string::npos) << run.err;
  }
}

// A CA file that looks like PEM but is not a certificate fails inside
// gRPC, which logged four "E..." lines of its own before lmdctl's error.
TEST_F(LmdctlTest, AFailedCallIsOneLineWithoutGrpcsOwnLog) {
  const std::string ca = dir_.path() + "/bad-ca.pem";
  std::ofstream(ca) << "-----BEGIN CERTIFICATE-----\nAAAA\n-----END CERTIFICATE-----\n";
  CliRun run = RunLmdctl("--server 127.0.0.1:1 --timeout 2 --tls-ca " + ca + " collections", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_EQ(run.err.rfind("lmdctl: UNAVAILABLE", 0), 0u) << run.err;
  // Asked for, gRPC's lines are back.
  setenv("GRPC_VERBOSITY", "ERROR", 1);
  run = RunLmdctl("--server 127.0.0.1:1 --timeout 2 --tls-ca " + ca + " collections", dir_);
  unsetenv("GRPC_VERBOSITY");
  EXPECT_GT(CountLines(run.err), 1) << run.err;
}

TEST_F(LmdctlTest, ANameThatCannotBeAHeaderIsRefusedNotACrash) {
  TestServer server(data_.path());
  // popen runs /bin/sh (dash): printf makes the bytes (UTF-8 e acute, a tab).
  CliRun run = RunLmdctl("--server " + server.address() + " list --collection \"$(printf 'caf\\303\\251\\tx')\"", dir_);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("INVALID_ARGUMENT"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("\\x09"), std::string::npos) << run.err;  // the tab, escaped
  CliRun token = RunLmdctl("--server " + server.address() + " --token \"$(printf 't\\303\\266k')\" collections", dir_);
  EXPECT_EQ(token.exit_code, 1) << token.err;
  EXPECT_NE(token.err.find("printable ASCII"), std::string::npos) << token.err;
}

// A points file of binary bytes once had its line echoed raw on stderr: it
// is quoted short and escaped.
TEST_F(LmdctlTest, ABinaryPointsLineIsQuotedShortAndEscaped) {
  std::string bytes = "0 0\n";
  for (int i = 0; i < 300; ++i) bytes += static_cast<char>(0x80 + i % 100);
  std::ofstream(dir_.path() + "/binary.txt") << bytes << "\n";
  const std::string insert = "--server 127.0.0.1:1 insert --collection site --file " + dir_.path();
  CliRun run = RunLmdctl(insert + "/binary.txt", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("binary.txt:2: expected 'x y' with finite numbers, got '\\x80\\x81"), std::string::npos)
      << run.err;
  EXPECT_LT(run.err.size(), 600u) << run.err;  // 80 bytes shown, as \xNN
  EXPECT_TRUE(std::all_of(run.err.begin(), run.err.end(), [](char c) { return c == '\n' || (c >= 0x20 && c < 0x7f); }))
      << run.err;
}

// --file /dev/zero once grew lmdctl's memory for ever (one endless line):
// a line beyond 64 KiB stops the read.
TEST_F(LmdctlTest, APointsFileWithoutNewlinesIsRefusedAtItsFirstLine) {
  std::ofstream(dir_.path() + "/zeros.txt") << std::string(size_t{1} << 20, '\0');
  CliRun run = RunLmdctl("--server 127.0.0.1:1 insert --collection site --file " + dir_.path() + "/zeros.txt", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(CountLines(run.err), 1) << run.err.substr(0, 200);
  EXPECT_NE(run.err.find("zeros.txt:1: line longer than 64 KiB"), std::string::npos) << run.err.substr(0, 200);
}

TEST_F(LmdctlTest, MalformedPointsFileNamesTheLine) {
  std::ofstream(dir_.path() + "/bad.txt") << "0 0\n1 oops\n";
  TestServer server(data_.path());
  CliRun run = RunLmdctl("--server " + server.address() + " insert --collection site --file " + dir_.path() + "/bad.txt",
                      dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("bad.txt:2"), std::string::npos) << run.err;

  std::ofstream(dir_.path() + "/far.txt") << "0 0\n1e39 1\n";  // a double, not a float
  run = RunLmdctl("--server " + server.address() + " insert --collection site --file " + dir_.path() + "/far.txt", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("far.txt:2: a coordinate is beyond the float range"), std::string::npos) << run.err;
  run = RunLmdctl("--server " + server.address() + " insert --collection site --file " + dir_.path(), dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("is a directory"), std::string::npos) << run.err;
}

// /dev/zero as a log once grew lmdctl's memory until it was killed: the
// reader stops at a line beyond its bound, naming it, before any call.
TEST_F(LmdctlTest, ALogWithoutNewlinesIsRefusedAtItsFirstLine) {
  std::ofstream(dir_.path() + "/zeros.log") << std::string(size_t{6} << 20, '\0');
  CliRun run = RunLmdctl("--server 127.0.0.1:1 ingest --collection site --log " + dir_.path() + "/zeros.log", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("zeros.log:1: line longer than 4 MiB"), std::string::npos) << run.err;
}

TEST_F(LmdctlTest, UnreachableServerFailsCleanly) {
  CliRun run = RunLmdctl("--server 127.0.0.1:1 --timeout 2 collections", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("UNAVAILABLE"), std::string::npos) << run.err;
}

// gRPC would dial port 99999 modulo 65536 (34463).
TEST_F(LmdctlTest, APortOutOfRangeIsRefusedNotWrappedAround) {
  for (const std::string port : {"99999", "65536", "0"}) {
    CliRun run = RunLmdctl("--server 127.0.0.1:" + port + " --timeout 2 collections", dir_);
    EXPECT_EQ(run.exit_code, 1) << run.err;
    EXPECT_EQ(run.err, "lmdctl: server address '127.0.0.1:" + port + "': port " + port + " is not from 1 to 65535\n");
  }
}

}  // namespace
}  // namespace lmd::testing

namespace lmd::testing {
namespace {

class LmdctlLogTest : public LmdctlTest {
 protected:
  void SetUp() override {
    LaserLog log = DefaultDemoLog();
    log.scans.resize(std::min<size_t>(log.scans.size(), 60));  // ~30 m of travel: a short ingest
    ASSERT_TRUE(WriteCarmenLog(dir_.path() + "/robot.log", log).ok());
  }
};

// A step of 1 nm once made ingest build maps for ever. A bad --step or
// --length is a usage error (exit 2, as every other bad option value; it
// was 1), for ingest and query alike, refused before the log is read.
TEST_F(LmdctlLogTest, AStepTooSmallIsRefusedNamingTheRange) {
  const std::string log = " --log " + dir_.path() + "/robot.log";
  for (const std::string& command : {"ingest --collection fleet --step 1e-9" + log,
                                     "query --collection fleet --map 1 --step 0" + log,
                                     std::string("ingest --collection fleet --length 1000 --log /nonexistent.log")}) {
    CliRun run = RunLmdctl("--server 127.0.0.1:1 " + command, dir_);
    EXPECT_EQ(run.exit_code, 2) << command;
    EXPECT_EQ(CountLines(run.err), 1) << command << ": " << run.err;
    EXPECT_NE(run.err.find(" must be a number of metres from "), std::string::npos) << run.err;
  }
}

// --heading-drift states on every map built from the log how far its poses
// may turn per metre (deg on the command line, rad on the wire); more than
// lmdd takes is a usage error.
TEST_F(LmdctlLogTest, IngestStatesTheOdometrysHeadingDriftOnEveryMap) {
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  const std::string log = " --log " + dir_.path() + "/robot.log";
  CliRun ingest = RunLmdctl(base + "ingest --collection fleet --heading-drift 0.5" + log, dir_);
  ASSERT_EQ(ingest.exit_code, 0) << ingest.err;
  v1::GetMapRequest get;
  get.set_collection("fleet");
  get.set_map_id("robot-0");
  v1::GetMapResponse got;
  ASSERT_TRUE(server.client().GetMap(get, &got).ok());
  EXPECT_NEAR(got.map().map().heading_drift_rad_per_m(), 0.5 * M_PI / 180, 1e-9);

  // A points file with its poses, inserted as such a map.
  const std::string file = dir_.path() + "/walked.txt";
  std::FILE* out = std::fopen(file.c_str(), "w");
  ASSERT_NE(out, nullptr);
  std::fputs("pose 0 0 0\npose 2 0 0\n0 1\n1 1\n2 1\n0 -1\n", out);
  std::fclose(out);
  CliRun insert = RunLmdctl(base + "insert --collection fleet --id walked --heading-drift 1 --file " + file, dir_);
  ASSERT_EQ(insert.exit_code, 0) << insert.err;
  get.set_map_id("walked");
  ASSERT_TRUE(server.client().GetMap(get, &got).ok());
  EXPECT_NEAR(got.map().map().heading_drift_rad_per_m(), M_PI / 180, 1e-9);
  // Read back into a points file and inserted again, it keeps its drift.
  const std::string back = dir_.path() + "/back.txt";
  ASSERT_EQ(RunLmdctl(base + "get --collection fleet --id walked --out " + back, dir_).exit_code, 0);
  ASSERT_EQ(RunLmdctl(base + "insert --collection fleet --id again --file " + back, dir_).exit_code, 0);
  get.set_map_id("again");
  ASSERT_TRUE(server.client().GetMap(get, &got).ok());
  EXPECT_NEAR(got.map().map().heading_drift_rad_per_m(), M_PI / 180, 1e-9);

  CliRun too_much = RunLmdctl(base + "ingest --collection fleet --heading-drift 40" + log, dir_);
  EXPECT_EQ(too_much.exit_code, 2);
  EXPECT_EQ(CountLines(too_much.err), 1) << too_much.err;
  EXPECT_NE(too_much.err.find("--heading-drift must be a number of degrees per metre from 0 to 28"), std::string::npos)
      << too_much.err;
}

TEST_F(LmdctlLogTest, IngestPrintsOneIdPerAcknowledgedMapAndTheyAreQueryable) {
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  CliRun ingest = RunLmdctl(base + "--json ingest --collection fleet --log " + dir_.path() + "/robot.log", dir_);
  ASSERT_EQ(ingest.exit_code, 0) << ingest.err;
  const int maps = CountLines(ingest.out);
  ASSERT_GT(maps, 5);
  EXPECT_EQ(ingest.out.rfind("{\"id\":\"robot-0\"", 0), 0u) << ingest.out;

  CliRun listed = RunLmdctl(base + "--json maps --collection fleet", dir_);
  ASSERT_EQ(listed.exit_code, 0) << listed.err;
  EXPECT_EQ(CountLines(listed.out), maps);
  EXPECT_NE(listed.out.find("{\"id\":\"robot-0\","), std::string::npos) << listed.out;

  CliRun query = RunLmdctl(base + "--json query --collection fleet --top-k 3 --log " + dir_.path() +
                               "/robot.log --map 4", dir_);
  ASSERT_EQ(query.exit_code, 0) << query.err;
  EXPECT_NE(query.out.find("\"map_id\":\"robot-4\""), std::string::npos) << query.out;
  CliRun others = RunLmdctl(base + "--json query --collection fleet --top-k 3 --exclude robot-4,robot-3 --log " +
                                dir_.path() + "/robot.log --map 4", dir_);
  ASSERT_EQ(others.exit_code, 0) << others.err;
  EXPECT_GT(CountLines(others.out), 0);
  EXPECT_EQ(others.out.find("\"map_id\":\"robot-4\""), std::string::npos) << others.out;
  EXPECT_EQ(others.out.find("\"map_id\":\"robot-3\""), std::string::npos) << others.out;
  // --verify: how many hits lmdd verifies (each verified hit says so); 0 is a usage error.
  CliRun deep = RunLmdctl(base + "--json query --collection fleet --top-k 3 --verify 1 --log " + dir_.path() +
                              "/robot.log --map 4", dir_);
  ASSERT_EQ(deep.exit_code, 0) << deep.err;
  EXPECT_EQ(CountOccurrences(deep.out, "\"verified\":true"), 1) << deep.out;
  EXPECT_EQ(RunLmdctl(base + "query --collection fleet --verify 0 --log " + dir_.path() + "/robot.log --map 4", dir_)
                .exit_code,
            2);

  CliRun render = RunLmdctl(base + "render --collection fleet --log " + dir_.path() + "/robot.log --map 4 --out " +
                                dir_.path() + "/r.svg", dir_);
  ASSERT_EQ(render.exit_code, 0) << render.err;
  std::ifstream svg(dir_.path() + "/r.svg");
  std::string first_line;
  std::getline(svg, first_line);
  EXPECT_NE(first_line.find("<svg"), std::string::npos) << first_line;
}

// Off a terminal lmdctl draws no progress (it once printed a line every
// 10 %): a script's stderr holds an error line and nothing else.
TEST_F(LmdctlLogTest, IngestDrawsNoProgressOffATerminal) {
  TestServer server(data_.path());
  CliRun ingest =
      RunLmdctl("--server " + server.address() + " ingest --collection fleet --log " + dir_.path() + "/robot.log", dir_);
  ASSERT_EQ(ingest.exit_code, 0) << ingest.err;
  EXPECT_NE(ingest.out.find("ingested "), std::string::npos) << ingest.out;
  EXPECT_EQ(ingest.err, "");
}

// render once said "(method bow gives none)" when the default method found
// no hit: it says there is no hit, or names the method it used.
TEST_F(LmdctlLogTest, RenderWithoutAPoseSaysWhyNamingTheMethodUsed) {
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  const std::string log = dir_.path() + "/robot.log";
  ASSERT_EQ(RunLmdctl(base + "ingest --collection fleet --log " + log, dir_).exit_code, 0);
  std::ofstream(dir_.path() + "/room.txt") << "0 0\n1 0\n1 1\n0 1\n";  // too small a map to match anything
  ASSERT_EQ(RunLmdctl(base + "insert --collection rooms --file " + dir_.path() + "/room.txt", dir_).exit_code, 0);
  CliRun none = RunLmdctl(base + "render --collection rooms --log " + log + " --map 4 --out " + dir_.path() +
                              "/none.svg", dir_);
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_EQ(CountLines(none.err), 1) << none.err;
  EXPECT_NE(none.err.find("no map of 'rooms' matches: nothing to render"), std::string::npos) << none.err;
  CliRun bow = RunLmdctl(base + "render --collection fleet --method bow --log " + log + " --map 4 --out " +
                             dir_.path() + "/bow.svg", dir_);
  EXPECT_EQ(bow.exit_code, 1);
  EXPECT_NE(bow.err.find("the top hit of method bow has no pose to render"), std::string::npos) << bow.err;
}

TEST_F(LmdctlLogTest, PriorsAndSequencesReachLmddAndItsVerdictIsPrinted) {
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  const std::string log = dir_.path() + "/robot.log";
  ASSERT_EQ(RunLmdctl(base + "ingest --anchor --collection fleet --log " + log, dir_).exit_code, 0);
  Result<LaserLog> read = ReadCarmenLog(log);
  ASSERT_TRUE(read.ok());
  const std::vector<LocalMap> maps = BuildLocalMaps(*read);
  ASSERT_GT(maps.size(), 12u);
  const Pose2 truth = maps[12].truth.global_frame;
  auto prior = [&](double dx) {
    char text[96];
    std::snprintf(text, sizeof text, " --prior %.3f,%.3f,%.2f,2", truth.x + dx, truth.y, truth.theta * 180 / M_PI + 5);
    return std::string(text);
  };
  CliRun near = RunLmdctl(base + "--json query --collection fleet --top-k 2 --log " + log + " --map 12" + prior(0.8),
                          dir_);
  ASSERT_EQ(near.exit_code, 0) << near.err;
  EXPECT_NE(near.out.find("\"prior_used\":true,\"prior_failed\":false"), std::string::npos) << near.out;
  EXPECT_NE(near.out.find("\"map_id\":\"robot-12\""), std::string::npos) << near.out;
  EXPECT_NE(near.out.find("\"pose_covariance\":{\"xx\":"), std::string::npos) << near.out;
  CliRun shown = RunLmdctl(base + "query --collection fleet --log " + log + " --map 12" + prior(0.8), dir_);
  ASSERT_EQ(shown.exit_code, 0) << shown.err;
  EXPECT_NE(shown.out.find("the first hit's pose is known to "), std::string::npos) << shown.out;
  CliRun far = RunLmdctl(base + "query --collection fleet --log " + log + " --map 12" + prior(200), dir_);
  ASSERT_EQ(far.exit_code, 0) << far.err;
  EXPECT_NE(far.out.find("the prior failed"), std::string::npos) << far.out;
  EXPECT_EQ(far.out.find("robot-"), std::string::npos) << far.out;  // no hit far from every map

  CliRun sequence = RunLmdctl(base + "--json query --collection fleet --sequence 2 --log " + log + " --map 12", dir_);
  ASSERT_EQ(sequence.exit_code, 0) << sequence.err;
  EXPECT_NE(sequence.out.find("\"sequence_maps\":2"), std::string::npos) << sequence.out;

  for (const std::string bad : {" --map 12 --prior 1,2", " --map 12 --prior 1,nan,0", " --map 3 --sequence 2",
                                " --map 12 --sequence 2 --prior 1,2,3"}) {
    CliRun run = RunLmdctl(base + "query --collection fleet --log " + log + bad, dir_);
    EXPECT_EQ(run.exit_code, 2) << bad;
    EXPECT_EQ(CountLines(run.err), 1) << bad << ": " << run.err;
  }
}

// README command 1's job: robot 2 relocalises from sequences, then tracks
// with priors; every figure is checked against the simulator's truth. A
// sure answer must never be wrong, and once sure robot 2 must stay right.
TEST_F(LmdctlTest, TheDemoRelocalisesRobotTwoAndIsNeverSureAndWrong) {
  TestServer server(data_.path());
  CliRun demo = RunLmdctl("--server " + server.address() + " demo --out " + dir_.path(), dir_);
  ASSERT_EQ(demo.exit_code, 0) << demo.err;
  int right = 0, sent = 0, sure = 0, sure_wrong = 0;
  const size_t at = demo.out.find("summary: ");
  ASSERT_NE(at, std::string::npos) << demo.out;
  ASSERT_EQ(std::sscanf(demo.out.c_str() + at, "summary: %d/%d", &right, &sent), 2) << demo.out;
  const size_t verdicts = demo.out.find("lmdd was sure of ", at);
  ASSERT_NE(verdicts, std::string::npos);
  ASSERT_EQ(std::sscanf(demo.out.c_str() + verdicts, "lmdd was sure of %d, %d", &sure, &sure_wrong), 2);
  EXPECT_GT(sent, 10);
  EXPECT_GT(sure, 0);
  EXPECT_EQ(sure_wrong, 0) << demo.out;
  // Every miss has its reason, and each reason is counted once.
  int no_hit = 0, new_place = 0, unsure = 0, turned = 0, sure_wrong_again = 0;
  const size_t misses = demo.out.find("misses: ", at);
  ASSERT_NE(misses, std::string::npos) << demo.out;
  ASSERT_EQ(std::sscanf(demo.out.c_str() + misses,
                        "misses: %d with no hit, %d at places robot 1 never mapped, %d wrong poses lmdd was not sure "
                        "of (%d of them turned by 45 deg or more: look-alike corridors), %d sure and wrong",
                        &no_hit, &new_place, &unsure, &turned, &sure_wrong_again),
            5)
      << demo.out;
  EXPECT_EQ(right + no_hit + new_place + unsure + sure_wrong_again, sent) << demo.out;
  EXPECT_LE(turned, unsure);
  EXPECT_EQ(sure_wrong_again, sure_wrong);
  // After the first sure fix robot 2 tracks with priors: no map after it is lost again.
  const size_t first_prior = demo.out.find(" prior, ");
  ASSERT_NE(first_prior, std::string::npos) << demo.out;
  EXPECT_EQ(demo.out.find("lost:", first_prior), std::string::npos) << demo.out;
  std::ifstream site(dir_.path() + "/site.svg");
  std::string first_line;
  std::getline(site, first_line);
  EXPECT_NE(first_line.find("<svg"), std::string::npos);
}

TEST_F(LmdctlLogTest, QueryNeedsExactlyOneSourceOfTheMap) {
  CliRun run = RunLmdctl("query --collection fleet", dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--file POINTS or as --log FILE --map K"), std::string::npos) << run.err;
  run = RunLmdctl("ingest --collection fleet --log /nonexistent.log", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(CountLines(run.err), 1) << run.err;
}

// ingest once stored a bag's maps and ignored --log beside it; like query
// it refuses two sources (and none) with one line.
TEST_F(LmdctlLogTest, IngestNeedsExactlyOneSourceOfTheMaps) {
  const std::string ingest = "--server 127.0.0.1:1 ingest --collection fleet";
  for (const std::string& sources : {" --log " + dir_.path() + "/robot.log --bag " + dir_.path() + "/robot.mcap",
                                    std::string(), " --file " + dir_.path() + "/room.txt"}) {
    CliRun run = RunLmdctl(ingest + sources, dir_);
    EXPECT_EQ(run.exit_code, 2) << sources;
    EXPECT_EQ(CountLines(run.err), 1) << sources << ": " << run.err;
    EXPECT_NE(run.err.find("give the maps to ingest as --log FILE or as --bag PATH"), std::string::npos) << run.err;
  }
}

}  // namespace
}  // namespace lmd::testing
