// The simulator: worlds, ray casting, routes with loops, laser, logs, streams.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "core/io/carmen_reader.h"
#include "core/io/carmen_writer.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/simulate.h"

namespace lmd {
namespace {

double BruteForceRay(const World& w, const Point2& o, double angle, double max_range) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  double best = max_range;
  for (const Segment& s : w.walls()) {
    const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
    const double den = dx * ey - dy * ex;
    if (std::abs(den) < 1e-12) continue;
    const double wx = s.a.x - o.x, wy = s.a.y - o.y;
    const double t = (wx * ey - wy * ex) / den, u = (wx * dy - wy * dx) / den;
    if (t >= 0 && u >= 0 && u <= 1 && t < best) best = t;
  }
  return best;
}

TEST(SimWorld, GridRayCastingAgreesWithBruteForce) {
  const World w = DefaultDemoWorld();
  const BuildingLayout& b = w.buildings().at(0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(b.min_corner.x - 5, b.max_corner.x + 5);
  std::uniform_real_distribution<double> uy(b.min_corner.y - 5, b.max_corner.y + 5);
  std::uniform_real_distribution<double> ua(-M_PI, M_PI);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Point2 o{ux(rng), uy(rng)};
    const double a = ua(rng);
    const double fast = w.CastRay(o, a, 30.0), slow = BruteForceRay(w, o, a, 30.0);
    ASSERT_NEAR(fast, slow, 1e-9) << "ray " << i;
    hits += fast < 30.0 ? 1 : 0;
  }
  EXPECT_GT(hits, 1000);
}

TEST(SimWorld, SameSeedSameWorldOtherSeedOtherWorld) {
  WorldOptions a;
  a.seed = 5;
  const World w1 = GenerateWorld(a), w2 = GenerateWorld(a);
  ASSERT_EQ(w1.walls().size(), w2.walls().size());
  for (size_t i = 0; i < w1.walls().size(); ++i) {
    EXPECT_EQ(w1.walls()[i].a.x, w2.walls()[i].a.x);
    EXPECT_EQ(w1.walls()[i].b.y, w2.walls()[i].b.y);
  }
  WorldOptions b = a;
  b.seed = 6;
  const World w3 = GenerateWorld(b);
  bool differs = w3.walls().size() != w1.walls().size();
  for (size_t i = 0; !differs && i < w1.walls().size(); ++i) differs = w1.walls()[i].a.x != w3.walls()[i].a.x;
  EXPECT_TRUE(differs);
}

TEST(SimWorld, BuildingsHaveRoomsDoorsClutterAndObliqueWalls) {
  WorldOptions o;
  o.buildings = 4;
  const World w = GenerateWorld(o);
  ASSERT_EQ(w.buildings().size(), 4u);
  size_t oblique = 0;
  for (const Segment& s : w.walls()) {
    if (std::abs(s.a.x - s.b.x) > 1e-9 && std::abs(s.a.y - s.b.y) > 1e-9) ++oblique;
  }
  EXPECT_GT(oblique, 0u);
  EXPECT_LT(oblique * 5, w.walls().size()) << "mostly Manhattan";
  for (const BuildingLayout& b : w.buildings()) {
    EXPECT_GE(b.doors.size(), 4u);
    EXPECT_GE(b.corridor_x.size(), 3u);
  }
  // Buildings sit on separate tiles.
  EXPECT_GT(w.buildings()[1].min_corner.x, w.buildings()[0].max_corner.x);
}

TEST(SimRoute, StaysInFreeSpaceWithBoundedStepsAndTurns) {
  const World w = DefaultDemoWorld();
  RouteOptions r;
  r.length_m = 200;
  const std::vector<Pose2> route = PlanRoute(w, r);
  ASSERT_GT(route.size(), 300u);
  double travel = 0;
  for (size_t i = 1; i < route.size(); ++i) {
    const double step = std::hypot(route[i].x - route[i - 1].x, route[i].y - route[i - 1].y);
    travel += step;
    EXPECT_LE(step, r.pose_spacing_m + 1e-9);
    EXPECT_LE(std::abs(NormalizeAngle(route[i].theta - route[i - 1].theta)), r.max_turn_rad + 1e-9);
    // No wall between consecutive poses.
    if (step > 1e-9) {
      const double a = std::atan2(route[i].y - route[i - 1].y, route[i].x - route[i - 1].x);
      EXPECT_GE(w.CastRay({route[i - 1].x, route[i - 1].y}, a, 30.0), step) << "pose " << i;
    }
  }
  EXPECT_NEAR(travel, 200.0, 1.0);
  // Same seed, same route.
  const std::vector<Pose2> again = PlanRoute(w, r);
  ASSERT_EQ(again.size(), route.size());
  EXPECT_EQ(again.back().x, route.back().x);
}

TEST(SimRoute, RevisitsPlacesFromAnotherDirection) {
  const World w = DefaultDemoWorld();
  RouteOptions r;
  r.length_m = 300;
  const std::vector<Pose2> route = PlanRoute(w, r);
  std::vector<double> travel(route.size(), 0.0);
  for (size_t i = 1; i < route.size(); ++i)
    travel[i] = travel[i - 1] + std::hypot(route[i].x - route[i - 1].x, route[i].y - route[i - 1].y);
  int same_direction = 0, other_direction = 0;
  for (size_t i = 0; i < route.size(); i += 5) {
    for (size_t j = i + 1; j < route.size(); ++j) {
      if (travel[j] - travel[i] < 20.0) continue;
      if (std::hypot(route[i].x - route[j].x, route[i].y - route[j].y) > 1.0) continue;
      if (std::abs(NormalizeAngle(route[i].theta - route[j].theta)) < 0.5) {
        ++same_direction;
      } else {
        ++other_direction;
      }
    }
  }
  EXPECT_GT(same_direction, 5);
  EXPECT_GT(other_direction, 5);
}

TEST(SimLaser, EndpointsLieOnWallsAndMissesAreNoReturn) {
  const World w = DefaultDemoWorld();
  const std::vector<Pose2> route = PlanRoute(w, RouteOptions{});
  LaserOptions l;
  l.step_deg = 0.5;
  std::mt19937_64 rng(1);
  const Scan s = SimulateScan(w, route[20], l, rng);
  ASSERT_EQ(s.ranges.size(), 360u);
  EXPECT_NEAR(s.first_angle, -M_PI / 2 + M_PI / 720, 1e-6);
  size_t returns = 0;
  for (size_t i = 0; i < s.ranges.size(); ++i) {
    const double a = s.pose.theta + s.first_angle + i * s.angle_step;
    const double truth = w.CastRay({s.pose.x, s.pose.y}, a, l.max_range);
    if (truth >= l.max_range) {
      EXPECT_GE(s.ranges[i], s.max_range);
    } else {
      EXPECT_NEAR(s.ranges[i], truth, 6 * l.range_noise_m + 1e-3);
      ++returns;
    }
  }
  EXPECT_GT(returns, 300u);
}

TEST(SimLog, WrittenCarmenLogReadsBackTheSameScans) {
  const LaserLog log = DefaultDemoLog();
  ASSERT_GT(log.scans.size(), 100u);
  for (const char* name : {"lmd_sim_roundtrip.log", "lmd_sim_roundtrip.log.gz"}) {
    const std::string path = (std::filesystem::temp_directory_path() / name).string();
    ASSERT_TRUE(WriteCarmenLog(path, log).ok());
    auto back = ReadCarmenLog(path);
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    ASSERT_EQ(back->scans.size(), log.scans.size());
    for (size_t i = 0; i < log.scans.size(); i += 7) {
      const Scan& a = log.scans[i];
      const Scan& b = back->scans[i];
      EXPECT_NEAR(a.pose.x, b.pose.x, 1e-6);
      EXPECT_NEAR(a.pose.theta, b.pose.theta, 1e-6);
      EXPECT_NEAR(a.first_angle, b.first_angle, 1e-6);
      EXPECT_NEAR(a.angle_step, b.angle_step, 1e-7);
      EXPECT_EQ(a.max_range, b.max_range);
      ASSERT_EQ(a.ranges.size(), b.ranges.size());
      for (size_t k = 0; k < a.ranges.size(); ++k) EXPECT_NEAR(a.ranges[k], b.ranges[k], 6e-4);
    }
    std::remove(path.c_str());
  }
}

TEST(SimLog, NonFlaserGeometryRoundTripsAsRobotLaser) {
  const World w = DefaultDemoWorld();
  const std::vector<Pose2> route = PlanRoute(w, RouteOptions{});
  LaserOptions l;
  l.fov_deg = 270;
  l.step_deg = 0.25;
  l.max_range = 20;
  const LaserLog log = SimulateLog(w, {route.begin(), route.begin() + 5}, l, 9);
  const std::string path = (std::filesystem::temp_directory_path() / "lmd_sim_robotlaser.log").string();
  ASSERT_TRUE(WriteCarmenLog(path, log).ok());
  auto back = ReadCarmenLog(path);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->scans.size(), 5u);
  EXPECT_EQ(back->scans[0].ranges.size(), 1080u);
  EXPECT_NEAR(back->scans[0].first_angle, log.scans[0].first_angle, 1e-6);
  EXPECT_FLOAT_EQ(back->scans[0].max_range, 20.0f);
  std::remove(path.c_str());
}

TEST(SimLocalMaps, DemoHasAFewHundredMapsAndIsDeterministic) {
  const SimulationOptions o = DefaultDemoOptions();
  const std::vector<LocalMap> a = SimulateLocalMaps(o);
  EXPECT_GE(a.size(), 200u);
  EXPECT_LE(a.size(), 500u);
  const std::vector<LocalMap> b = SimulateLocalMaps(o);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); i += 13) {
    ASSERT_EQ(a[i].points.size(), b[i].points.size());
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].points.back().x, b[i].points.back().x);
  }
  EXPECT_EQ(a[0].id, "sim-0");
  SimulationOptions other = o;
  other.world.seed = 2;
  other.route.seed = 2;
  const std::vector<LocalMap> c = SimulateLocalMaps(other);
  EXPECT_TRUE(c.size() != a.size() || c[5].points.size() != a[5].points.size() ||
              c[5].truth.global_frame.x != a[5].truth.global_frame.x);
}

TEST(SimLocalMaps, StreamingSpansBuildingsAndStopsOnRequest) {
  SimulationOptions o = DefaultDemoOptions();
  o.route.length_m = 60;
  o.num_maps = 150;  // ~56 maps per building -> 3 buildings
  o.local_map.keep_scans = false;
  double last_start = -1;
  size_t n = 0;
  double min_x = 1e9, max_x = -1e9;
  const size_t delivered = SimulateLocalMapsStreaming(o, [&](LocalMap&& m) {
    EXPECT_EQ(m.id, "sim-" + std::to_string(n));
    EXPECT_GT(m.truth.travel_start, last_start);
    EXPECT_TRUE(m.scans.empty());
    last_start = m.truth.travel_start;
    min_x = std::min(min_x, m.truth.global_frame.x);
    max_x = std::max(max_x, m.truth.global_frame.x);
    ++n;
    return true;
  });
  EXPECT_EQ(delivered, 150u);
  EXPECT_EQ(n, 150u);
  EXPECT_GT(max_x - min_x, o.world.tile_m) << "maps from more than one building";
  size_t seen = 0;
  EXPECT_EQ(SimulateLocalMapsStreaming(o, [&](LocalMap&&) { return ++seen < 10; }), 10u);
}

}  // namespace
}  // namespace lmd
