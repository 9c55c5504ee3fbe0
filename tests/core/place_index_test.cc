#include "core/place/place_index.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/localmap/pose_ops.h"
#include "core/sim/simulate.h"
#include "core/viewpoint/orientation.h"

namespace lmd {
namespace {

const std::vector<LocalMap>& DemoMaps() {
  static const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  return maps;
}

// A map's place features in its own compass frame (as the localizer describes it).
PlaceFeatures Describe(const std::vector<Point2>& points) {
  return DescribePlace(points, EstimateDominantOrientation(points));
}

// Demo map i described, once per test binary.
const PlaceFeatures& DemoFeatures(size_t i) {
  static std::map<size_t, PlaceFeatures> described;
  auto it = described.find(i);
  if (it == described.end()) it = described.emplace(i, Describe(DemoMaps()[i].points)).first;
  return it->second;
}

// Every 7th demo map (43 of the ~300), spread over the whole route.
constexpr size_t kStride = 7;
std::vector<size_t> StoredIds() {
  std::vector<size_t> ids;
  for (size_t i = 0; i < DemoMaps().size(); i += kStride) ids.push_back(i);
  return ids;
}

void AddStored(PlaceIndex* index) {
  for (size_t i : StoredIds()) ASSERT_TRUE(index->Add(i, DemoFeatures(i)).ok()) << i;
}

// The map's points seen from a frame placed at `pose` in its own frame: the
// pose of the returned points' frame in `map`'s own frame is `pose`.
std::vector<Point2> MovedPoints(const LocalMap& map, const Pose2& pose) {
  std::vector<Point2> out;
  const Pose2 inv = Inverse(pose);
  for (const Point2& p : map.points) out.push_back(TransformPoint(inv, p));
  return out;
}

double Deg(double d) { return d * M_PI / 180.0; }
double TranslationError(const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double AngleErrorDeg(const Pose2& a, const Pose2& b) {
  return std::abs(NormalizeAngle(a.theta - b.theta)) * 180.0 / M_PI;
}

const std::vector<Pose2>& KnownMoves() {
  static const std::vector<Pose2> poses = {
      {1.5, -2.0, Deg(17)}, {-3.0, 1.0, Deg(100)}, {0.5, 0.5, Deg(180)}, {2.0, 3.0, Deg(-75)},
  };
  return poses;
}

std::vector<PlaceHypothesis> SearchDefault(const PlaceIndex& index, const PlaceFeatures& query,
                                           const std::function<bool(uint64_t)>& excluded = {},
                                           PlaceSearchStats* stats = nullptr) {
  return index.Search(query, PlaceSearchOptions{}, excluded, stats);
}

bool Returns(const std::vector<PlaceHypothesis>& hypotheses, uint64_t id) {
  return std::any_of(hypotheses.begin(), hypotheses.end(), [&](const PlaceHypothesis& h) { return h.map_id == id; });
}

// The votes' translation cells are 1 m, their mean is the guess; the
// compass of a moved copy is the original's to its 0.1 deg step.
TEST(PlaceIndexTest, AMovedAndTurnedCopyFindsItsMapFirstNearTheTruePose) {
  PlaceIndex index;
  AddStored(&index);
  for (size_t id : {size_t{7}, size_t{70}, size_t{140}, size_t{210}, size_t{280}}) {
    for (const Pose2& truth : KnownMoves()) {
      const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[id], truth));
      const std::vector<PlaceHypothesis> hypotheses = SearchDefault(index, query);
      ASSERT_FALSE(hypotheses.empty());
      EXPECT_EQ(hypotheses[0].map_id, id) << truth.theta;
      const Pose2 pose = HypothesisPose(hypotheses[0], query.heading);
      EXPECT_LT(TranslationError(pose, truth), 0.5) << id << " " << truth.theta;
      EXPECT_LT(AngleErrorDeg(pose, truth), 1.0) << id << " " << truth.theta;
      EXPECT_EQ(hypotheses[0].db_heading, DemoFeatures(id).heading);
    }
  }
}

// db compass = R(k * 90 deg) query compass + translation, each compass the
// own frame turned by minus its heading: HypothesisPose is that chain.
TEST(PlaceIndexTest, HypothesisPoseChainsTheCompassFramesTurnAndTranslation) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-5.0, 5.0), heading(0.0, M_PI / 2);
  for (int trial = 0; trial < 50; ++trial) {
    PlaceHypothesis h;
    h.db_heading = heading(rng);
    h.quarter_turns = trial % 4;
    h.translation = {u(rng), u(rng)};
    const double query_heading = heading(rng);
    const Pose2 pose = HypothesisPose(h, query_heading);
    EXPECT_GT(pose.theta, -M_PI - 1e-12);
    EXPECT_LE(pose.theta, M_PI + 1e-12);
    for (int i = 0; i < 3; ++i) {
      const Point2 p{u(rng), u(rng)};  // query own frame
      const Point2 query_compass = TransformPoint({0, 0, -query_heading}, p);
      const Point2 turned = TurnQuarters(query_compass, h.quarter_turns);
      const Point2 db_compass{turned.x + h.translation.x, turned.y + h.translation.y};
      const Point2 want = TransformPoint({0, 0, h.db_heading}, db_compass);
      const Point2 got = TransformPoint(pose, p);
      EXPECT_NEAR(got.x, want.x, 1e-9);
      EXPECT_NEAR(got.y, want.y, 1e-9);
    }
  }
}

TEST(PlaceIndexTest, HypothesesAreRankedByVotesAndBoundedPerMap) {
  PlaceIndex index;
  AddStored(&index);
  PlaceSearchOptions options;
  options.max_hypotheses = 15;
  options.hypotheses_per_map = 2;
  for (size_t id : {size_t{35}, size_t{154}}) {
    const std::vector<PlaceHypothesis> hypotheses = index.Search(Describe(DemoMaps()[id].points), options);
    ASSERT_EQ(hypotheses.size(), 15u);  // 43 maps: more than enough votes
    std::map<uint64_t, int> per_map;
    for (size_t r = 0; r < hypotheses.size(); ++r) {
      const PlaceHypothesis& h = hypotheses[r];
      EXPECT_GE(h.quarter_turns, 0);
      EXPECT_LT(h.quarter_turns, 4);
      EXPECT_GT(h.votes, 0.0);
      ASSERT_TRUE(index.Features(h.map_id).has_value());
      EXPECT_EQ(h.db_heading, index.Features(h.map_id)->heading);
      EXPECT_LE(++per_map[h.map_id], 2) << h.map_id;
      if (r > 0) {
        EXPECT_GE(hypotheses[r - 1].votes, h.votes);
      }
    }
    // Two hypotheses of one map are distinct: another turn or cells apart.
    for (size_t a = 0; a < hypotheses.size(); ++a) {
      for (size_t b = a + 1; b < hypotheses.size(); ++b) {
        const PlaceHypothesis &ha = hypotheses[a], &hb = hypotheses[b];
        if (ha.map_id != hb.map_id || ha.quarter_turns != hb.quarter_turns) continue;
        EXPECT_GT(std::max(std::abs(ha.translation.x - hb.translation.x), std::abs(ha.translation.y - hb.translation.y)),
                  options.vote_cell_m * 0.5);
      }
    }
  }
  options.hypotheses_per_map = 1;
  const std::vector<PlaceHypothesis> one = index.Search(Describe(DemoMaps()[35].points), options);
  std::set<uint64_t> ids;
  for (const PlaceHypothesis& h : one) EXPECT_TRUE(ids.insert(h.map_id).second) << h.map_id;
}

TEST(PlaceIndexTest, AddOfAnExistingIdFailsAndChangesNothing) {
  PlaceIndex index;
  AddStored(&index);
  const size_t maps = index.size(), features = index.FeatureCount();
  const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[70], KnownMoves()[0]));
  const std::vector<PlaceHypothesis> before = SearchDefault(index, query);
  const Status again = index.Add(70, DemoFeatures(140));  // another map's features under a stored id
  EXPECT_EQ(again.code(), Status::Code::kAlreadyExists);
  EXPECT_EQ(index.size(), maps);
  EXPECT_EQ(index.FeatureCount(), features);
  ASSERT_TRUE(index.Features(70).has_value());
  EXPECT_EQ(index.Features(70)->features.size(), DemoFeatures(70).features.size());
  EXPECT_EQ(index.Features(70)->heading, DemoFeatures(70).heading);
  const std::vector<PlaceHypothesis> after = SearchDefault(index, query);
  ASSERT_EQ(after.size(), before.size());
  for (size_t r = 0; r < after.size(); ++r) {
    EXPECT_EQ(after[r].map_id, before[r].map_id);
    EXPECT_EQ(after[r].votes, before[r].votes);
    EXPECT_EQ(after[r].quarter_turns, before[r].quarter_turns);
  }
}

TEST(PlaceIndexTest, MoreThanTheMaximumFeaturesIsInvalidArgument) {
  std::mt19937_64 rng(5);
  PlaceFeatures many;
  many.features.resize(PlaceIndex::kMaxFeaturesPerMap + 1);
  for (PlaceFeature& f : many.features) f.code = {rng(), rng()};
  PlaceIndex index;
  EXPECT_EQ(index.Add(1, many).code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(index.size(), 0u);
  EXPECT_EQ(index.FeatureCount(), 0u);
  EXPECT_FALSE(index.Features(1).has_value());
  EXPECT_TRUE(SearchDefault(index, many).empty());
  many.features.pop_back();  // exactly the maximum is accepted
  EXPECT_TRUE(index.Add(1, many).ok());
  EXPECT_EQ(index.FeatureCount(), PlaceIndex::kMaxFeaturesPerMap);
}

TEST(PlaceIndexTest, FeaturesReturnsTheStoredFeaturesOrNull) {
  PlaceIndex index;
  const PlaceFeatures& stored = DemoFeatures(14);
  ASSERT_TRUE(index.Add(99, stored).ok());
  const std::optional<PlaceFeatures> got = index.Features(99);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(index.Heading(99), stored.heading);
  EXPECT_EQ(got->heading, stored.heading);
  ASSERT_EQ(got->features.size(), stored.features.size());
  for (size_t i = 0; i < stored.features.size(); ++i) {
    EXPECT_EQ(got->features[i].x, stored.features[i].x);
    EXPECT_EQ(got->features[i].y, stored.features[i].y);
    EXPECT_EQ(got->features[i].code, stored.features[i].code);
  }
  EXPECT_FALSE(index.Features(14).has_value());
  EXPECT_FALSE(index.Heading(14).has_value());
  EXPECT_EQ(index.size(), 1u);
  EXPECT_EQ(index.FeatureCount(), stored.features.size());
  EXPECT_GT(index.MemoryBytes(), stored.features.size() * sizeof(PlaceFeature));
}

TEST(PlaceIndexTest, RemovedMapIsNeverReturned) {
  PlaceIndex index;
  AddStored(&index);
  const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[140], KnownMoves()[1]));
  ASSERT_EQ(SearchDefault(index, query)[0].map_id, 140u);
  const size_t maps = index.size(), features = index.FeatureCount();
  EXPECT_TRUE(index.Remove(140));
  EXPECT_EQ(index.size(), maps - 1);
  EXPECT_EQ(index.FeatureCount(), features - DemoFeatures(140).features.size());
  EXPECT_FALSE(index.Features(140).has_value());
  PlaceSearchOptions wide;
  wide.max_hypotheses = 1000;
  const std::vector<PlaceHypothesis> without = index.Search(query, wide);
  EXPECT_FALSE(without.empty());  // the other maps still vote
  EXPECT_FALSE(Returns(without, 140));
  EXPECT_FALSE(index.Remove(140));  // already gone
  EXPECT_FALSE(index.Remove(12345));  // never stored
  EXPECT_EQ(index.size(), maps - 1);
}

// Remove frees the map's slot; a map added later takes it, and neither the
// removed id nor the removed features come back.
TEST(PlaceIndexTest, AMapAddedAfterARemoveIsFoundUnderItsOwnId) {
  PlaceIndex index;
  AddStored(&index);
  ASSERT_TRUE(index.Remove(140));
  ASSERT_TRUE(index.Add(1000, DemoFeatures(3)).ok());  // map 3 (not stored; far from map 140), a new id
  PlaceSearchOptions wide;
  wide.max_hypotheses = 1000;
  const std::vector<PlaceHypothesis> found = index.Search(Describe(MovedPoints(DemoMaps()[3], KnownMoves()[2])), wide);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found[0].map_id, 1000u);
  EXPECT_FALSE(Returns(found, 140));
  const std::vector<PlaceHypothesis> gone = index.Search(Describe(MovedPoints(DemoMaps()[140], KnownMoves()[0])), wide);
  EXPECT_FALSE(Returns(gone, 140));
  // Re-adding the removed id works too.
  ASSERT_TRUE(index.Add(140, DemoFeatures(140)).ok());
  EXPECT_EQ(SearchDefault(index, Describe(MovedPoints(DemoMaps()[140], KnownMoves()[0])))[0].map_id, 140u);
}

// A store rebuilt in another order (lmdd's index after a restart, another
// replica) answers the same: ties are broken by the maps' content.
TEST(PlaceIndexTest, AnswersDoNotDependOnTheOrderMapsWereAdded) {
  PlaceIndex forward, backward;
  AddStored(&forward);
  std::vector<size_t> ids = StoredIds();
  ASSERT_TRUE(backward.Add(5000, DemoFeatures(1)).ok());  // takes slot 0, then frees it
  ASSERT_TRUE(backward.Remove(5000));
  for (auto it = ids.rbegin(); it != ids.rend(); ++it) ASSERT_TRUE(backward.Add(*it, DemoFeatures(*it)).ok());
  for (size_t q : {size_t{35}, size_t{154}, size_t{200}}) {
    const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[q], KnownMoves()[1]));
    const std::vector<PlaceHypothesis> a = SearchDefault(forward, query), b = SearchDefault(backward, query);
    ASSERT_EQ(a.size(), b.size()) << q;
    for (size_t r = 0; r < a.size(); ++r) {
      EXPECT_EQ(a[r].map_id, b[r].map_id) << q << " rank " << r;
      EXPECT_EQ(a[r].votes, b[r].votes) << q << " rank " << r;
      EXPECT_EQ(a[r].quarter_turns, b[r].quarter_turns) << q << " rank " << r;
      EXPECT_NEAR(a[r].translation.x, b[r].translation.x, 1e-4) << q << " rank " << r;
      EXPECT_NEAR(a[r].translation.y, b[r].translation.y, 1e-4) << q << " rank " << r;
    }
  }
}

// place_index.h: "Ranked hypotheses (most votes first; ties: smaller map id)".

TEST(PlaceIndexTest, ExcludedMapsAreNeverReturned) {
  PlaceIndex index;
  AddStored(&index);
  PlaceSearchOptions wide;
  wide.max_hypotheses = 1000;
  const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[210], KnownMoves()[3]));
  const std::vector<PlaceHypothesis> all = index.Search(query, wide);
  ASSERT_EQ(all[0].map_id, 210u);
  // Excluding the right map and every map of an even id.
  auto excluded = [](uint64_t id) { return id == 210 || id % 2 == 0; };
  const std::vector<PlaceHypothesis> rest = index.Search(query, wide, excluded);
  ASSERT_FALSE(rest.empty());
  for (const PlaceHypothesis& h : rest) EXPECT_FALSE(excluded(h.map_id)) << h.map_id;
  // The maps not excluded keep their hypotheses.
  std::vector<PlaceHypothesis> kept;
  for (const PlaceHypothesis& h : all) {
    if (!excluded(h.map_id)) kept.push_back(h);
  }
  ASSERT_EQ(rest.size(), kept.size());
  for (size_t r = 0; r < kept.size(); ++r) {
    EXPECT_EQ(rest[r].map_id, kept[r].map_id);
    EXPECT_EQ(rest[r].votes, kept[r].votes);
  }
  EXPECT_TRUE(index.Search(query, wide, [](uint64_t) { return true; }).empty());
}

TEST(PlaceIndexTest, StatsCountTheWorkOfASearch) {
  PlaceIndex index;
  AddStored(&index);
  const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[280], KnownMoves()[0]));
  PlaceSearchStats stats;
  const std::vector<PlaceHypothesis> hypotheses = SearchDefault(index, query, {}, &stats);
  // Every query feature reads its bucket in every table under each of 4 turns.
  EXPECT_EQ(stats.lookups, query.features.size() * 4 * PlaceIndex::kTables);
  EXPECT_GT(stats.votes, 0u);
  EXPECT_GE(stats.candidates, stats.votes);  // a vote is a compared stored feature
  // At most `neighbours` votes per query feature and turn.
  EXPECT_LE(stats.votes, query.features.size() * 4 * PlaceSearchOptions{}.neighbours);
  std::set<uint64_t> ids;
  for (const PlaceHypothesis& h : hypotheses) ids.insert(h.map_id);
  EXPECT_GE(stats.maps_voted, ids.size());
  EXPECT_LE(stats.maps_voted, index.size());
  // Skipping crowded buckets compares fewer stored features.
  PlaceSearchOptions thin;
  thin.max_bucket = 2;
  PlaceSearchStats thin_stats;
  index.Search(query, thin, {}, &thin_stats);
  EXPECT_EQ(thin_stats.lookups, stats.lookups);
  EXPECT_LT(thin_stats.candidates, stats.candidates);
  // An empty query does no work.
  PlaceSearchStats none;
  none.votes = 7;  // overwritten
  EXPECT_TRUE(SearchDefault(index, PlaceFeatures{}, {}, &none).empty());
  EXPECT_EQ(none.lookups, 0u);
  EXPECT_EQ(none.votes, 0u);
  EXPECT_EQ(none.maps_voted, 0u);
}

// A candidate bound stops starting query features once that many stored
// features were compared; the rarest features are read first, so the place
// still wins when the bound is a fraction of the full search's work. The
// bound grows with the collection: with min_candidates_per_map, a tiny
// fixed bound still reads that many stored features per stored map.
TEST(PlaceIndexTest, ACandidateBoundCutsTheWorkAndKeepsThePlace) {
  PlaceIndex index;
  AddStored(&index);
  const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[140], KnownMoves()[1]));
  PlaceSearchOptions unbounded;
  unbounded.max_candidates = 0;
  PlaceSearchStats full;
  index.Search(query, unbounded, {}, &full);
  EXPECT_EQ(full.features_used, query.features.size());
  PlaceSearchOptions bounded;
  bounded.max_candidates = full.candidates / 3;
  PlaceSearchStats cut;
  const std::vector<PlaceHypothesis> hypotheses = index.Search(query, bounded, {}, &cut);
  EXPECT_LT(cut.features_used, full.features_used);
  EXPECT_LT(cut.candidates, full.candidates);
  ASSERT_FALSE(hypotheses.empty());
  EXPECT_EQ(hypotheses[0].map_id, 140u);

  PlaceSearchOptions tiny;
  tiny.max_candidates = 1;
  tiny.min_candidates_per_map = 0;
  PlaceSearchStats one;
  index.Search(query, tiny, {}, &one);
  PlaceSearchOptions grown = tiny;
  grown.min_candidates_per_map = full.candidates / 3 / index.size();
  ASSERT_GT(grown.min_candidates_per_map, 0u);
  PlaceSearchStats per_map;
  const std::vector<PlaceHypothesis> grown_hypotheses = index.Search(query, grown, {}, &per_map);
  EXPECT_GE(per_map.candidates, grown.min_candidates_per_map * index.size());
  EXPECT_GT(per_map.features_used, one.features_used);
  ASSERT_FALSE(grown_hypotheses.empty());
  EXPECT_EQ(grown_hypotheses[0].map_id, 140u);
}

// `only` restricts the search to those maps: the others are never
// returned, and their stored features are not counted as compared.
TEST(PlaceIndexTest, OnlyTheNamedMapsAreSearched) {
  PlaceIndex index;
  AddStored(&index);
  const PlaceFeatures query = Describe(MovedPoints(DemoMaps()[70], KnownMoves()[0]));
  PlaceSearchStats all;
  ASSERT_EQ(SearchDefault(index, query, {}, &all).at(0).map_id, 70u);
  const std::vector<uint64_t> others = {7, 140, 210};
  PlaceSearchOptions options;
  options.only = &others;
  PlaceSearchStats some;
  const std::vector<PlaceHypothesis> hypotheses = index.Search(query, options, {}, &some);
  for (const PlaceHypothesis& h : hypotheses) EXPECT_TRUE(h.map_id == 7 || h.map_id == 140 || h.map_id == 210) << h.map_id;
  // The other maps' features are read and passed over: they count towards
  // the bound on reading, which then stops a restricted search as early.
  EXPECT_EQ(some.candidates, all.candidates);
  options.max_candidates = all.candidates / 4;
  PlaceSearchStats bounded;
  index.Search(query, options, {}, &bounded);
  EXPECT_LT(bounded.features_used, some.features_used);
  const std::vector<uint64_t> itself = {70};
  options.max_candidates = 0;
  options.only = &itself;
  const std::vector<PlaceHypothesis> found = index.Search(query, options);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found[0].map_id, 70u);
}

// A code farther than max_hamming from every stored code does not vote: a
// query of random codes (64 bits from any stored code on average) finds
// nothing at 10 bits, while the map's own features find it at 0.
TEST(PlaceIndexTest, CodesFartherThanMaxHammingDoNotVote) {
  PlaceIndex index;
  AddStored(&index);
  PlaceSearchOptions exact;
  exact.max_hamming = 0;
  const std::vector<PlaceHypothesis> self = index.Search(DemoFeatures(63), exact);
  ASSERT_FALSE(self.empty());
  EXPECT_EQ(self[0].map_id, 63u);
  EXPECT_EQ(self[0].quarter_turns, 0);
  EXPECT_LT(std::hypot(self[0].translation.x, self[0].translation.y), 0.5);
  std::mt19937_64 rng(8);
  PlaceFeatures random = DemoFeatures(63);
  for (PlaceFeature& f : random.features) f.code = {rng(), rng()};
  PlaceSearchOptions near;
  near.max_hamming = 10;
  PlaceSearchStats stats;
  EXPECT_TRUE(index.Search(random, near, {}, &stats).empty());
  EXPECT_EQ(stats.votes, 0u);
}

// Search is const: lmdd answers queries concurrently under a shared lock.
TEST(PlaceIndexTest, ConcurrentSearchesGiveTheSequentialAnswers) {
  PlaceIndex index;
  AddStored(&index);
  std::vector<PlaceFeatures> queries;
  for (size_t q : {size_t{14}, size_t{98}, size_t{182}, size_t{266}}) {
    queries.push_back(Describe(MovedPoints(DemoMaps()[q], KnownMoves()[q % 4])));
  }
  std::vector<std::vector<PlaceHypothesis>> sequential, concurrent(queries.size());
  for (const PlaceFeatures& q : queries) sequential.push_back(SearchDefault(index, q));
  std::vector<std::thread> threads;
  for (size_t i = 0; i < queries.size(); ++i) {
    threads.emplace_back([&, i] { concurrent[i] = SearchDefault(index, queries[i]); });
  }
  for (std::thread& t : threads) t.join();
  for (size_t i = 0; i < queries.size(); ++i) {
    ASSERT_EQ(concurrent[i].size(), sequential[i].size()) << i;
    for (size_t r = 0; r < sequential[i].size(); ++r) {
      EXPECT_EQ(concurrent[i][r].map_id, sequential[i][r].map_id);
      EXPECT_EQ(concurrent[i][r].votes, sequential[i][r].votes);
    }
  }
}

TEST(PlaceIndexTest, AnEmptyIndexReturnsNothing) {
  const PlaceIndex index;
  EXPECT_EQ(index.size(), 0u);
  EXPECT_EQ(index.FeatureCount(), 0u);
  EXPECT_TRUE(SearchDefault(index, DemoFeatures(0)).empty());
  EXPECT_FALSE(index.Features(0).has_value());
}

}  // namespace
}  // namespace lmd
