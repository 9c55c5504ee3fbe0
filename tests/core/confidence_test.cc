#include "core/localize/confidence.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/align/prepared_map.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

// Points every 0.1 m (the builder's dedup cell) from a to b.
void AddWall(std::vector<Point2>* points, const Point2& a, const Point2& b) {
  const double length = std::hypot(b.x - a.x, b.y - a.y);
  const int n = static_cast<int>(std::round(length / 0.1));
  for (int i = 0; i <= n; ++i) {
    const double t = n == 0 ? 0.0 : static_cast<double>(i) / n;
    points->push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
  }
}

void AddRoomWalls(std::vector<Point2>* points) {
  AddWall(points, {0, 0}, {10, 0});
  AddWall(points, {10, 0}, {10, 6});
  AddWall(points, {10, 6}, {0, 6});
  AddWall(points, {0, 6}, {0, 0});
}

// A 10 x 6 m room the robot crossed along y = 3: without scans, the cells
// within 0.6 m of the trajectory are its free space (occupancy_grid.h).
LocalMap Room() {
  LocalMap map;
  map.id = "room";
  AddRoomWalls(&map.points);
  for (double x = 1.0; x <= 9.0; x += 0.5) map.trajectory.push_back({x, 3.0, 0.0});
  return map;
}

// The same room with a partition wall where the room above was crossed (a
// look-alike that contradicts it), crossed along y = 1.5.
LocalMap PartitionedRoom() {
  LocalMap map;
  map.id = "partitioned";
  AddRoomWalls(&map.points);
  AddWall(&map.points, {2, 3}, {8, 3});
  for (double x = 1.0; x <= 9.0; x += 0.5) map.trajectory.push_back({x, 1.5, 0.0});
  return map;
}

// The map seen from a frame placed at `pose` in its own frame (points and
// trajectory): the returned map's own frame is `pose` in `map`'s.
LocalMap MovedCopy(const LocalMap& map, const Pose2& pose) {
  LocalMap out;
  out.id = map.id + "-moved";
  const Pose2 inv = Inverse(pose);
  for (const Point2& p : map.points) out.points.push_back(TransformPoint(inv, p));
  for (const Pose2& p : map.trajectory) out.trajectory.push_back(Compose(inv, p));
  return out;
}

struct Maps {
  PreparedMap room = PrepareMap(Room());
  PreparedMap partitioned = PrepareMap(PartitionedRoom());
  Pose2 copy_frame{2.0, -1.0, 0.7};  // the copy's own frame in the room's
  PreparedMap copy = PrepareMap(MovedCopy(Room(), copy_frame));
};

const Maps& TheMaps() {
  static const Maps* maps = new Maps();
  return *maps;
}

const Pose2 kQueryPose{4.0, 2.5, 0.3};  // the query's own frame in the room's

double Logistic(const LogisticFit& f, double best, double margin, bool sure) {
  const double z = f.bias + f.score_weight * best + f.margin_weight * margin + (sure ? f.sure_weight : 0.0);
  return 1.0 / (1.0 + std::exp(-z));
}

// --- Disagreement ---------------------------------------------------------

TEST(ConfidenceTest, TheHandMadeMapsHaveFreeSpace) {
  EXPECT_GT(TheMaps().room.occupancy.Count(CellState::kFree), 0u);
  EXPECT_TRUE(InFreeSpace(TheMaps().room, {5.0, 3.0}));
  EXPECT_FALSE(InFreeSpace(TheMaps().room, {5.0, 1.0}));  // 2 m from the trajectory: unknown
}

TEST(ConfidenceTest, AMapAtItsOwnPoseDoesNotDisagreeWithItself) {
  EXPECT_EQ(Disagreement(TheMaps().room, TheMaps().room, Pose2{}), 0.0);
  // Nor with a copy of it in another frame, placed where it belongs.
  EXPECT_EQ(Disagreement(TheMaps().room, TheMaps().copy, TheMaps().copy_frame), 0.0);
}

TEST(ConfidenceTest, WallsInTheOtherMapsFreeSpaceAreDisagreement) {
  const Maps& m = TheMaps();
  // The partition (6 m of 38 m of wall) lies in the room's free space.
  const double d = Disagreement(m.room, m.partitioned, Pose2{});
  EXPECT_GT(d, 0.1);
  EXPECT_LT(d, 0.3);
  // The larger of the two directions: the same either way round.
  EXPECT_DOUBLE_EQ(Disagreement(m.partitioned, m.room, Pose2{}), d);
  // The room's own walls, shifted 3 m so that its bottom wall crosses its free space.
  EXPECT_GT(Disagreement(m.room, m.room, {0.0, 3.0, 0.0}), 0.05);
}

// Only points the other map observed (near its points or in its free space)
// count: a map that reaches far beyond the other does not dilute the
// contradiction where they overlap.
TEST(ConfidenceTest, WhatTheOtherMapNeverObservedDoesNotDiluteAContradiction) {
  const Maps& m = TheMaps();
  LocalMap longer = PartitionedRoom();
  AddWall(&longer.points, {10.5, 0}, {40, 0});  // a 30 m corridor east of the room: 3 times the room's walls
  AddWall(&longer.points, {10.5, 6}, {40, 6});
  AddWall(&longer.points, {40, 0}, {40, 6});
  const PreparedMap extended = PrepareMap(longer);
  const double local = Disagreement(m.room, m.partitioned, Pose2{});
  EXPECT_NEAR(Disagreement(m.room, extended, Pose2{}), local, 0.02);
  EXPECT_GT(Disagreement(m.room, extended, Pose2{}), ConfidenceOptions{}.max_disagreement);
}

TEST(ConfidenceTest, MapsThatDoNotOverlapCannotDisagree) {
  const Maps& m = TheMaps();
  EXPECT_EQ(Disagreement(m.room, m.partitioned, {100.0, 0.0, 0.0}), 0.0);
  EXPECT_EQ(Disagreement(m.room, m.partitioned, {0.0, -50.0, 1.0}), 0.0);
}

// Maps without scans or trajectory have no free space: nothing can
// contradict them, and they contradict nothing.
TEST(ConfidenceTest, MapsWithoutFreeSpaceNeverDisagree) {
  const PreparedMap room = PreparePoints(Room().points), partitioned = PreparePoints(PartitionedRoom().points);
  EXPECT_EQ(Disagreement(room, partitioned, Pose2{}), 0.0);
  EXPECT_EQ(Disagreement(room, room, {0.0, 3.0, 0.0}), 0.0);
}

// --- Judge ------------------------------------------------------------------

TEST(JudgeTest, ALoneStrongHitIsSure) {
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &TheMaps().room, false, std::nullopt}};
  const Verdict v = Judge(&hits);
  EXPECT_TRUE(v.sure);
  EXPECT_DOUBLE_EQ(v.best_score, 0.9);
  EXPECT_EQ(v.rival_score, 0.0);
  EXPECT_EQ(v.agreeing, 0u);
  EXPECT_TRUE(hits[0].agrees_with_best);  // the best agrees with itself
  // The documented logistic, the margin being the whole score.
  EXPECT_NEAR(v.confidence, Logistic(ConfidenceOptions{}.calibration, 0.9, 0.9, true), 1e-12);
  EXPECT_GT(v.confidence, 0.99);
}

TEST(JudgeTest, NoHitsIsNeverSure) {
  std::vector<JudgedHit> none;
  const Verdict v = Judge(&none);
  EXPECT_FALSE(v.sure);
  EXPECT_EQ(v.best_score, 0.0);
  EXPECT_EQ(v.confidence, 0.0);
  std::vector<JudgedHit> unmapped = {{0.9, kQueryPose, nullptr, false, std::nullopt}};
  EXPECT_FALSE(Judge(&unmapped).sure);
}

TEST(JudgeTest, BelowMinScoreIsNeverSure) {
  for (double score : {0.0, 0.3, 0.59}) {
    std::vector<JudgedHit> hits = {{score, kQueryPose, &TheMaps().room, false, std::nullopt}};
    const Verdict v = Judge(&hits);
    EXPECT_FALSE(v.sure) << score;  // the margin (the whole score, no rival) is not enough
    EXPECT_DOUBLE_EQ(v.best_score, score);
  }
  std::vector<JudgedHit> at = {{0.6, kQueryPose, &TheMaps().room, false, std::nullopt}};
  EXPECT_TRUE(Judge(&at).sure);  // min_score itself is enough
  ConfidenceOptions strict;
  strict.min_score = 0.95;
  std::vector<JudgedHit> strong = {{0.9, kQueryPose, &TheMaps().room, false, std::nullopt}};
  EXPECT_FALSE(Judge(&strong, strict).sure);
}

TEST(JudgeTest, ADisagreeingHitWithinTheMarginIsARival) {
  const Maps& m = TheMaps();
  ASSERT_GT(Disagreement(m.room, m.partitioned, Pose2{}), ConfidenceOptions{}.max_disagreement);
  // The query fits both rooms at the same pose: the partition would cross the room's free space.
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &m.room, false, std::nullopt}, {0.8, kQueryPose, &m.partitioned, false, std::nullopt}};
  const Verdict v = Judge(&hits);
  EXPECT_FALSE(v.sure);
  EXPECT_DOUBLE_EQ(v.best_score, 0.9);
  EXPECT_DOUBLE_EQ(v.rival_score, 0.8);
  EXPECT_EQ(v.agreeing, 0u);
  EXPECT_TRUE(hits[0].agrees_with_best);
  EXPECT_FALSE(hits[1].agrees_with_best);
  EXPECT_NEAR(v.confidence, Logistic(ConfidenceOptions{}.calibration, 0.9, 0.1, false), 1e-12);
}

// The score and margin thresholds alone (ConfidenceOptions::
// min_global_probability 0); the global line has a test below.
ConfidenceOptions ThresholdsOnly() {
  ConfidenceOptions options;
  options.min_global_probability = 0.0;
  return options;
}

// A rival at the highest harmless score leaves the answer sure, one just
// above it does not: with the margin alone, and with the global line
// (which asks for more where the best score is lower).
TEST(JudgeTest, TheHighestHarmlessRivalIsWhereTheVerdictTurns) {
  for (const ConfidenceOptions& options : {ConfidenceOptions{}, ThresholdsOnly()}) {
    for (double best : {0.65, 0.75, 0.85, 0.95}) {
      const double harmless = HighestHarmlessRival(best, options);
      ASSERT_GT(harmless, 0.0) << best;
      EXPECT_LE(harmless, best - options.min_margin + 1e-12) << best;
      std::vector<JudgedHit> hits = {{best, kQueryPose, &TheMaps().room, false, std::nullopt}};
      EXPECT_TRUE(Judge(&hits, options, harmless - 1e-9).sure) << best;
      EXPECT_FALSE(Judge(&hits, options, harmless + 1e-3).sure) << best;
    }
  }
  // The global line asks for more than the margin below a best score of about 0.96.
  EXPECT_LT(HighestHarmlessRival(0.65, ConfidenceOptions{}), HighestHarmlessRival(0.65, ThresholdsOnly()) - 0.1);
  ConfidenceOptions never;
  never.min_global_probability = 1.0;
  EXPECT_LT(HighestHarmlessRival(0.9, never), 0.0);
}

TEST(JudgeTest, ADisagreeingHitBeyondTheMarginLeavesItSure) {
  const Maps& m = TheMaps();
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &m.room, false, std::nullopt}, {0.65, kQueryPose, &m.partitioned, false, std::nullopt}};
  const Verdict v = Judge(&hits, ThresholdsOnly());
  EXPECT_TRUE(v.sure);  // margin 0.25 >= 0.2
  EXPECT_DOUBLE_EQ(v.rival_score, 0.65);
  EXPECT_FALSE(hits[1].agrees_with_best);
  // The best rival counts: one more within the margin overturns it.
  hits.push_back({0.85, kQueryPose, &m.partitioned, false, std::nullopt});
  const Verdict w = Judge(&hits, ThresholdsOnly());
  EXPECT_FALSE(w.sure);
  EXPECT_DOUBLE_EQ(w.rival_score, 0.85);
}

// Another map of the same place, with the query at the pose that puts the
// two maps' walls together, supports the best hit: it is no rival however
// close its score.
TEST(JudgeTest, AnAgreeingHitCountsAndIsNoRival) {
  const Maps& m = TheMaps();
  const Pose2 in_copy = Compose(Inverse(m.copy_frame), kQueryPose);  // the query's pose in the copy
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &m.room, false, std::nullopt}, {0.89, in_copy, &m.copy, false, std::nullopt}};
  const Verdict v = Judge(&hits);
  EXPECT_TRUE(v.sure);
  EXPECT_EQ(v.agreeing, 1u);
  EXPECT_EQ(v.rival_score, 0.0);
  EXPECT_TRUE(hits[1].agrees_with_best);
  // The same map at a pose 3 m off puts its walls through the room: a rival.
  std::vector<JudgedHit> shifted = {{0.9, kQueryPose, &m.room, false, std::nullopt},
                                    {0.89, Compose(in_copy, {0.0, -3.0, 0.0}), &m.copy, false, std::nullopt}};
  const Verdict w = Judge(&shifted);
  EXPECT_FALSE(w.sure);
  EXPECT_EQ(w.agreeing, 0u);
  EXPECT_DOUBLE_EQ(w.rival_score, 0.89);
  EXPECT_FALSE(shifted[1].agrees_with_best);
}

// Anchored hits that agree with the best (within same_place_m) but put the
// query, by their median, farther from the best hit's pose than a sure
// answer promises: the pose is not known that well, so it is not sure.
// One such hit, or hits that do not fit (below min_score), say nothing.
TEST(JudgeTest, AgreeingAnchoredMapsThatPutTheQueryElsewhereMakeItNotSure) {
  const Maps& m = TheMaps();
  const Pose2 site{10.0, 5.0, 0.3};  // the best hit's pose of the query in the site frame
  auto hits_at = [&](const std::vector<std::pair<Pose2, double>>& others) {
    std::vector<JudgedHit> hits = {{0.9, kQueryPose, &m.room, false, site}};
    for (const auto& [off, score] : others) hits.push_back({score, kQueryPose, &m.room, false, Compose(site, off)});
    return hits;
  };
  const Pose2 near{0.05, -0.03, 0.2 * M_PI / 180}, far{0.4, 0.1, 0.0}, turned{0.0, 0.0, 2.0 * M_PI / 180};
  std::vector<JudgedHit> close = hits_at({{near, 0.85}, {near, 0.8}});
  const Verdict a = Judge(&close);
  EXPECT_TRUE(a.sure);
  EXPECT_EQ(a.agreeing, 2u);
  EXPECT_NEAR(a.pose_spread_m, std::hypot(near.x, near.y), 1e-9);
  for (const Pose2& off : {far, turned}) {
    std::vector<JudgedHit> spread = hits_at({{off, 0.85}, {off, 0.8}, {near, 0.8}});
    const Verdict b = Judge(&spread);
    EXPECT_EQ(b.agreeing, 3u);  // one place (same_place_m), no rival
    EXPECT_DOUBLE_EQ(b.rival_score, 0.0);
    EXPECT_FALSE(b.sure) << off.x << " " << off.theta;
  }
  std::vector<JudgedHit> one = hits_at({{far, 0.85}});
  EXPECT_TRUE(Judge(&one).sure);
  std::vector<JudgedHit> weak = hits_at({{far, 0.5}, {far, 0.5}});
  EXPECT_TRUE(Judge(&weak).sure);
  ConfidenceOptions off;
  off.max_pose_spread_m = 0;
  std::vector<JudgedHit> unchecked = hits_at({{far, 0.85}, {far, 0.8}});
  EXPECT_TRUE(Judge(&unchecked, off).sure);
}

// Identical rooms of one building put no wall in each other's free space:
// maps of both agree with a best hit that has no anchor. Where the anchored
// ones among them name places apart in the site, the place is not known.
TEST(JudgeTest, AgreeingMapsAnchoredAtTwoPlacesMakeItNotSure) {
  const Maps& m = TheMaps();
  const Pose2 in_copy = Compose(Inverse(m.copy_frame), kQueryPose);
  const Pose2 here{10.0, 5.0, 0.3}, nearby{10.4, 5.2, 0.32}, twin{40.0, 5.0, 0.3 + M_PI / 2};
  auto judged = [&](const Pose2& first, const Pose2& second) {
    std::vector<JudgedHit> hits = {{0.95, kQueryPose, &m.room, false, std::nullopt},
                                   {0.93, in_copy, &m.copy, false, first},
                                   {0.9, kQueryPose, &m.room, false, second}};
    const Verdict v = Judge(&hits);
    EXPECT_TRUE(hits[1].agrees_with_best && hits[2].agrees_with_best);
    return v;
  };
  const Verdict one_place = judged(here, nearby);
  EXPECT_TRUE(one_place.sure);
  EXPECT_EQ(one_place.agreeing, 2u);
  const Verdict two_places = judged(here, twin);
  EXPECT_FALSE(two_places.sure);
  EXPECT_EQ(two_places.agreeing, 2u);
  EXPECT_DOUBLE_EQ(two_places.rival_score, 0.0);
  // With the best anchored, a map anchored elsewhere disagrees: a rival.
  std::vector<JudgedHit> anchored_best = {{0.95, kQueryPose, &m.room, false, here},
                                          {0.9, kQueryPose, &m.room, false, twin}};
  const Verdict rival = Judge(&anchored_best);
  EXPECT_FALSE(rival.sure);
  EXPECT_DOUBLE_EQ(rival.rival_score, 0.9);
}

// Where the best hit has no anchor, the answer's place in the site rests on
// the anchored hits: the one that agrees with the best must lead the
// anchored hits elsewhere, and its own map's other pose, as a sure answer's
// best must (a twin room's map may agree with the best as well as the
// place's own, and fit better where it saw more of the room).
TEST(JudgeTest, TheSitePlaceIsClearWhereItsAnchoredHitLeadsThoseElsewhere) {
  const Maps& m = TheMaps();
  const Pose2 in_copy = Compose(Inverse(m.copy_frame), kQueryPose);
  const Pose2 here{10.0, 5.0, 0.3}, nearby{10.4, 5.2, 0.32}, twin{40.0, 5.0, 0.3 + M_PI / 2};
  auto judged = [&](double named, const Pose2& other_at, double other) {
    // The best (no anchor) a little above the named hit, which it compares.
    std::vector<JudgedHit> hits = {{named + 0.08, kQueryPose, &m.room, false, std::nullopt},
                                   {named, in_copy, &m.copy, false, here},
                                   {other, kQueryPose, &m.partitioned, false, other_at}};
    Judge(&hits, ThresholdsOnly());
    return hits;
  };
  auto clear = [&](double named, const Pose2& other_at, double other, double named_other_pose = 0.0) {
    const std::vector<JudgedHit> hits = judged(named, other_at, other);
    EXPECT_EQ(SiteNamingHit(hits), 1);
    return SitePlaceClear(hits, SiteNamingHit(hits), named_other_pose, ThresholdsOnly());
  };
  EXPECT_TRUE(clear(0.9, twin, 0.65));       // leads the twin by 0.25
  EXPECT_FALSE(clear(0.9, twin, 0.75));      // by 0.15
  EXPECT_TRUE(clear(0.9, nearby, 0.85));     // the same place
  EXPECT_FALSE(clear(0.9, twin, 0.5, 0.8));  // its own map fits the query elsewhere too
  EXPECT_FALSE(clear(0.55, twin, 0.0));      // explains too little of the query to name a place
  // No anchored hit agrees with the best: nothing names the place.
  std::vector<JudgedHit> unplaced = {{0.98, kQueryPose, &m.room, false, std::nullopt},
                                     {0.7, kQueryPose, &m.partitioned, false, twin}};
  Judge(&unplaced, ThresholdsOnly());
  EXPECT_EQ(SiteNamingHit(unplaced), -1);
  EXPECT_FALSE(SitePlaceClear(unplaced, -1, 0.0, ThresholdsOnly()));
  // An anchored best names the place itself, and a verdict Judge made sure
  // stays clear: a hit elsewhere further below than agreement_window is no
  // rival, whatever margin the global line would ask of it.
  std::vector<JudgedHit> anchored_best = {{0.7, kQueryPose, &m.room, false, here},
                                          {0.38, kQueryPose, &m.room, false, twin}};
  const Verdict judged_sure = Judge(&anchored_best);
  EXPECT_TRUE(judged_sure.sure);
  EXPECT_EQ(SiteNamingHit(anchored_best), 0);
  EXPECT_EQ(SitePlaceClear(anchored_best, 0, 0.0, ConfidenceOptions{}), judged_sure.sure);
}

TEST(JudgeTest, ASelfRivalWithinTheMarginMakesItNotSure) {
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &TheMaps().room, false, std::nullopt}};
  const Verdict close = Judge(&hits, ThresholdsOnly(), 0.75);
  EXPECT_FALSE(close.sure);
  EXPECT_DOUBLE_EQ(close.rival_score, 0.75);
  const Verdict far = Judge(&hits, ThresholdsOnly(), 0.65);
  EXPECT_TRUE(far.sure);
  EXPECT_DOUBLE_EQ(far.rival_score, 0.65);
  // The larger of the self rival and the disagreeing hits is the rival.
  std::vector<JudgedHit> two = {{0.9, kQueryPose, &TheMaps().room, false, std::nullopt},
                                {0.8, kQueryPose, &TheMaps().partitioned, false, std::nullopt}};
  EXPECT_DOUBLE_EQ(Judge(&two, {}, 0.5).rival_score, 0.8);
  EXPECT_DOUBLE_EQ(Judge(&two, {}, 0.85).rival_score, 0.85);
}

TEST(JudgeTest, ConfidenceGrowsWithTheMarginAndTheScore) {
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &TheMaps().room, false, std::nullopt}};
  double previous = 0.0;
  for (double rival : {0.89, 0.85, 0.75, 0.7, 0.6, 0.4, 0.0}) {
    const Verdict v = Judge(&hits, {}, rival);
    EXPECT_GT(v.confidence, previous) << rival;
    EXPECT_LT(v.confidence, 1.0);
    previous = v.confidence;
  }
  previous = 0.0;
  for (double best : {0.5, 0.6, 0.7, 0.8, 0.9, 1.0}) {  // the same margin 0.1
    std::vector<JudgedHit> one = {{best, kQueryPose, &TheMaps().room, false, std::nullopt}};
    const Verdict v = Judge(&one, {}, best - 0.1);
    EXPECT_GT(v.confidence, previous) << best;
    previous = v.confidence;
  }
}

// Scores exact in binary (0.75 - 0.5 is 0.25 exactly), so that the margin
// can sit on the threshold.
TEST(JudgeTest, TheMarginAndScoreThresholdsAreTheOptions) {
  std::vector<JudgedHit> hits = {{0.75, kQueryPose, &TheMaps().room, false, std::nullopt}};
  ConfidenceOptions options = ThresholdsOnly();
  options.min_margin = 0.25;
  EXPECT_TRUE(Judge(&hits, options, 0.5).sure);  // margin >= min_margin
  options.min_margin = 0.375;
  EXPECT_FALSE(Judge(&hits, options, 0.5).sure);
  options.min_margin = 0.05;
  EXPECT_FALSE(Judge(&hits, ThresholdsOnly(), 0.625).sure);  // default 0.2
  EXPECT_TRUE(Judge(&hits, options, 0.625).sure);
  options.min_score = 0.75;
  EXPECT_TRUE(Judge(&hits, options, 0.5).sure);  // min_score itself is enough
  options.min_score = 0.875;
  EXPECT_FALSE(Judge(&hits, options, 0.5).sure);
}

// The confidence follows the final verdict: an answer a later test made
// unsure (SetConfidence after it) is less likely right than the same scores
// sure; no hits, none.
TEST(JudgeTest, TheConfidenceFollowsTheFinalVerdict) {
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &TheMaps().room, false, std::nullopt}};
  const ConfidenceOptions options;
  Verdict v = Judge(&hits, options);
  ASSERT_TRUE(v.sure);
  const double sure = v.confidence;
  v.sure = false;  // as a slide of the pose or a prior's radius would
  SetConfidence(&v, true, options);
  EXPECT_LT(v.confidence, sure);
  EXPECT_NEAR(v.confidence, Logistic(options.calibration, 0.9, 0.9, false), 1e-12);
  SetConfidence(&v, false, options);
  EXPECT_EQ(v.confidence, 0.0);
}

// Score and margin over their thresholds are not enough where the global
// line says such answers are often wrong.
TEST(JudgeTest, SureNeedsTheGlobalLineToo) {
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &TheMaps().room, false, std::nullopt}};
  const ConfidenceOptions defaults;
  const Verdict modest = Judge(&hits, {}, 0.65);  // margin 0.25: the line's 0.89
  EXPECT_LT(defaults.global_fit.Probability(0.9, 0.25, false), 0.9);
  EXPECT_FALSE(modest.sure);
  ConfidenceOptions lenient;
  lenient.min_global_probability = 0.85;
  EXPECT_TRUE(Judge(&hits, lenient, 0.65).sure);
  hits[0].score = 0.95;  // the line's 0.97
  EXPECT_TRUE(Judge(&hits, {}, 0.65).sure);
}

// The promise (0.2 m, 1 deg) must lie promise_sigmas standard deviations
// out: along the position's least known direction, whatever the axes, and
// in heading.
TEST(JudgeTest, APoseIsKnownToThePromiseOnlyAtEnoughSigmas) {
  const ConfidenceOptions options;
  const double degree = M_PI / 180;
  const auto covariance = [](double sx, double sy, double s_theta) {
    return Eigen::Vector3d(sx * sx, sy * sy, s_theta * s_theta).asDiagonal().toDenseMatrix();
  };
  EXPECT_TRUE(PoseKnownToPromise(covariance(0.03, 0.03, 0.3 * degree), options));
  EXPECT_FALSE(PoseKnownToPromise(covariance(0.03, 0.03, 0.4 * degree), options));  // 2.81 x 0.4 > 1 deg
  EXPECT_FALSE(PoseKnownToPromise(covariance(0.03, 0.08, 0.3 * degree), options));  // 2.81 x 8 cm > 0.2 m
  // 8 cm along the diagonal, 1 cm across it: each axis alone reads 5.7 cm.
  Eigen::Matrix3d diagonal = covariance(0.08, 0.01, 0.3 * degree);
  const double c = std::cos(M_PI / 4), s = std::sin(M_PI / 4);
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  turn.topLeftCorner<2, 2>() << c, -s, s, c;
  diagonal = turn * diagonal * turn.transpose();
  EXPECT_LT(options.promise_sigmas * std::sqrt(diagonal(0, 0)), options.max_pose_spread_m);
  EXPECT_FALSE(PoseKnownToPromise(diagonal, options));
  ConfidenceOptions unchecked;
  unchecked.promise_sigmas = 0;
  EXPECT_TRUE(PoseKnownToPromise(covariance(1.0, 1.0, 10 * degree), unchecked));
  // A covariance that is not finite knows nothing.
  Eigen::Matrix3d broken = covariance(0.03, 0.03, 0.3 * degree);
  broken(0, 1) = broken(1, 0) = std::nan("");
  EXPECT_FALSE(PoseKnownToPromise(broken, options));
}

// Hits far below the best (best - agreement_window) are not compared: no
// rival, and no place hit either.
TEST(JudgeTest, HitsBelowTheAgreementWindowAreNotCompared) {
  const Maps& m = TheMaps();
  const Pose2 in_copy = Compose(Inverse(m.copy_frame), kQueryPose);
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &m.room, false, std::nullopt},
                                 {0.55, kQueryPose, &m.partitioned, false, std::nullopt},
                                 {0.55, in_copy, &m.copy, false, std::nullopt}};
  ConfidenceOptions tight;
  tight.min_margin = 0.5;  // a rival at 0.55 would now overturn the verdict
  const Verdict v = Judge(&hits, tight);
  EXPECT_TRUE(v.sure);
  EXPECT_EQ(v.rival_score, 0.0);
  EXPECT_EQ(v.agreeing, 0u);
  EXPECT_FALSE(hits[1].agrees_with_best);
  EXPECT_FALSE(hits[2].agrees_with_best);
  // Within a wider window both are compared: one rival, one agreeing.
  tight.agreement_window = 0.4;
  const Verdict w = Judge(&hits, tight);
  EXPECT_FALSE(w.sure);
  EXPECT_DOUBLE_EQ(w.rival_score, 0.55);
  EXPECT_EQ(w.agreeing, 1u);
  EXPECT_TRUE(hits[2].agrees_with_best);
}

// confidence.h: Judge "sets each hit's agrees_with_best" (an output field).
// A hit judged again after its place in the ranking changed must not keep an
// earlier answer.
TEST(JudgeTest, EveryHitsAgreementIsSetEvenWhenNotCompared) {
  const Maps& m = TheMaps();
  const Pose2 in_copy = Compose(Inverse(m.copy_frame), kQueryPose);
  std::vector<JudgedHit> hits = {{0.9, kQueryPose, &m.room, false, std::nullopt}, {0.85, in_copy, &m.copy, false, std::nullopt}};
  Judge(&hits);
  ASSERT_TRUE(hits[1].agrees_with_best);
  hits[1].score = 0.4;  // rescored far below the best: no longer a place hit
  const Verdict v = Judge(&hits);
  EXPECT_EQ(v.agreeing, 0u);
  EXPECT_FALSE(hits[1].agrees_with_best);
}

}  // namespace
}  // namespace lmd
