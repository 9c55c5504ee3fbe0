#include "core/eval/truth_audit.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/eval/ground_truth.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/simulate.h"

namespace lmd {
namespace {

const std::vector<LocalMap>& DemoMaps() {
  static const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  return maps;
}

// The demo maps that show map q's place (half its points within 0.3 m of
// theirs) from more than 10 m of travel away, prepared as lmdd stores them.
struct Place {
  std::vector<size_t> ids;
  std::vector<PreparedPlace> maps;
};
Place PlaceOf(size_t q, const LocalizeOptions& options) {
  Place place;
  const LocalMap& query = DemoMaps()[q];
  for (size_t j = 0; j < DemoMaps().size(); ++j) {
    const LocalMap& db = DemoMaps()[j];
    if (std::abs(db.truth.travel_start - query.truth.travel_start) <= 10.0 || db.points.empty()) continue;
    if (PlaceOverlap(query, db) < 0.5) continue;
    place.ids.push_back(j);
    place.maps.push_back(PreparePlace(db, options));
  }
  return place;
}

// What the log says of the query's frame in each map of its place, when the
// log's pose of the query is its true pose moved by `log_error` (own frame).
std::vector<PlaceMap> AsTheLogSays(size_t q, const Place& place, const Pose2& log_error) {
  std::vector<PlaceMap> out;
  const Pose2 logged = Compose(DemoMaps()[q].truth.global_frame, log_error);
  for (size_t k = 0; k < place.ids.size(); ++k) {
    out.push_back({place.maps[k].map.get(), Compose(Inverse(DemoMaps()[place.ids[k]].truth.global_frame), logged)});
  }
  return out;
}

// The maps of a place, matched with a map from its log pose, agree on where
// it is: with a right log pose they leave it there (within a few cm); with
// one off by 2.2 m and 2 deg they move it back by that much.
TEST(TruthAuditTest, TheMapsOfAPlaceMoveAMapWhoseLogPoseIsOffByThatMuch) {
  const LocalizeOptions options;
  const Pose2 error{1.8, -1.2, 2 * M_PI / 180};
  const Pose2 correction = Inverse(error);
  size_t judged = 0, stayed = 0, moved_back = 0;
  for (size_t q = 20; q < DemoMaps().size() && judged < 6; q += 23) {
    const Place place = PlaceOf(q, options);
    if (place.ids.size() < 4) continue;
    const LocalQuery query = PrepareLocalQuery(DemoMaps()[q], options);
    const std::optional<PlaceMove> right = MoveByItsPlace(query, AsTheLogSays(q, place, {}), options);
    const std::optional<PlaceMove> off = MoveByItsPlace(query, AsTheLogSays(q, place, error), options);
    if (!right) continue;  // fewer than three maps of the place fit it
    ++judged;
    // The same maps fit it wherever within +-3 m the log puts it.
    ASSERT_TRUE(off) << q;
    EXPECT_GE(right->agreeing, 3u);
    EXPECT_LE(right->agreeing, right->matched);
    stayed += std::hypot(right->move.x, right->move.y) < 0.05 && std::abs(right->move.theta) < 0.3 * M_PI / 180;
    moved_back += std::hypot(off->move.x - correction.x, off->move.y - correction.y) < 0.05 &&
                  std::abs(std::remainder(off->move.theta - correction.theta, 2 * M_PI)) < 0.3 * M_PI / 180;
  }
  ASSERT_GE(judged, 3u);
  EXPECT_GE(stayed, judged - 1) << "of " << judged;
  EXPECT_GE(moved_back, judged - 1) << "of " << judged;
}

// With fewer than three maps of the place that fit, nothing is said.
TEST(TruthAuditTest, FewerThanThreeMapsOfAPlaceSayNothing) {
  const LocalizeOptions options;
  const LocalMap& query_map = DemoMaps()[40];
  const LocalQuery query = PrepareLocalQuery(query_map, options);
  // The map itself twice: both fit, but two maps are not enough.
  const PreparedPlace self = PreparePlace(query_map, options);
  const std::vector<PlaceMap> two = {{self.map.get(), Pose2{}}, {self.map.get(), Pose2{}}};
  EXPECT_FALSE(MoveByItsPlace(query, two, options));
  std::vector<PlaceMap> three = two;
  three.push_back({self.map.get(), Pose2{}});
  const std::optional<PlaceMove> said = MoveByItsPlace(query, three, options);
  ASSERT_TRUE(said);
  EXPECT_EQ(said->agreeing, 3u);
  EXPECT_LT(std::hypot(said->move.x, said->move.y), 0.02);
}

}  // namespace
}  // namespace lmd
