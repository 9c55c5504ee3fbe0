#include "core/change/change_detector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/change/lof.h"
#include "core/index/index.h"
#include "tests/core/synthetic_lmd.h"

namespace lmd {
namespace {

using testing::RandomLmd;
using testing::TransformedCopy;

// Change words that vary smoothly in space, as shape-context codes do: one
// random base word per 3 m block, a few bits flipped per feature.
uint64_t FlipBits(uint64_t w, int bits, std::mt19937_64& rng) {
  for (int b = 0; b < bits; ++b) w ^= uint64_t{1} << (rng() % 60);
  return w;
}

Lmd StructuredLmd(std::mt19937_64& rng, int n) {
  Lmd lmd = RandomLmd(rng, n, 10.0);
  for (Feature& f : lmd.features) {
    const uint64_t block = static_cast<uint64_t>(std::floor(f.x / 3.0) + 100) * 1000 +
                           static_cast<uint64_t>(std::floor(f.y / 3.0) + 100);
    std::mt19937_64 block_rng(block * 7919 + 17);
    f.change_word = FlipBits(block_rng() & ((uint64_t{1} << 60) - 1), 2, rng);
  }
  return lmd;
}

struct Task {
  Lmd db;
  Lmd query;
  Point2 region_own;  // centre of the added region, query own frame
};

// A db map and a rotated, shifted, noisy view of it in which `added` features
// appear in a 1.5 m square (none when added = 0).
Task MakeTask(std::mt19937_64& rng, int added) {
  Task t;
  t.db = StructuredLmd(rng, 80);
  const int k = static_cast<int>(rng() % 4);
  std::uniform_real_distribution<double> shift(-1.0, 1.0), where(-7.0, 7.0), in(-0.75, 0.75);
  t.query = TransformedCopy(t.db, k, shift(rng), shift(rng), rng, 0.05, 0.9);
  for (Feature& f : t.query.features) f.change_word = FlipBits(f.change_word, 1, rng);
  t.query.frame = {{2.0, -1.0}, 0.4};
  const double cx = where(rng), cy = where(rng);
  for (int a = 0; a < added; ++a) {
    Feature f;
    f.appearance_word = static_cast<uint32_t>(rng() % 1024);
    f.x = static_cast<float>(cx + in(rng));
    f.y = static_cast<float>(cy + in(rng));
    f.change_word = rng() & ((uint64_t{1} << 60) - 1);
    t.query.features.push_back(f);
  }
  const double c = std::cos(0.4), s = std::sin(0.4);
  t.region_own = {2.0 + c * cx - s * cy, -1.0 + s * cx + c * cy};
  return t;
}

// Masks of `task` against its db map found through an index holding it
// among random maps.
std::vector<ChangeMask> Detect(const Task& task, std::mt19937_64& rng, const ChangeDetectorOptions& options = {}) {
  auto index = Index::Create();
  EXPECT_TRUE(index.ok());
  EXPECT_TRUE(index->Add(7, task.db).ok());
  std::vector<Lmd> others;
  for (int m = 0; m < 20; ++m) others.push_back(StructuredLmd(rng, 80));
  for (int m = 0; m < 20; ++m) EXPECT_TRUE(index->Add(100 + m, others[m]).ok());
  RetrieveOptions retrieve;
  retrieve.max_offset_m = 1.0;  // the tasks shift the view by up to 1 m per axis
  auto hits = index->Retrieve(task.query, retrieve);
  EXPECT_TRUE(hits.ok());
  if (!hits.ok() || hits->empty()) return {};
  EXPECT_EQ((*hits)[0].map_id, 7u);
  std::vector<ChangeCandidate> candidates;
  for (const MapHit& h : *hits) candidates.push_back({h, h.map_id == 7 ? &task.db : &others[h.map_id - 100]});
  candidates.resize(std::min<size_t>(candidates.size(), 3));
  auto masks = DetectChanges(task.query, candidates, options);
  EXPECT_TRUE(masks.ok());
  return masks.ok() ? *masks : std::vector<ChangeMask>{};
}

TEST(LofTest, IsolatedPointsGetHighFactorsAndClusterPointsAboutOne) {
  std::vector<Point2> points;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 7; ++j) points.push_back({0.5 * i, 0.5 * j});
  points.push_back({10.0, 10.0});
  points.push_back({1.5, 5.0});
  const std::vector<double> lof = LocalOutlierFactors(points, 10);
  ASSERT_EQ(lof.size(), points.size());
  for (int i = 0; i < 49; ++i) EXPECT_LT(lof[i], 1.6) << i;
  EXPECT_GT(lof[49], 5.0);
  EXPECT_GT(lof[50], 1.6);
  EXPECT_NEAR(lof[24], 1.0, 0.1);  // grid centre
}

TEST(LofTest, DegenerateInputsStayFinite) {
  EXPECT_TRUE(LocalOutlierFactors({}, 10).empty());
  EXPECT_EQ(LocalOutlierFactors({{1, 1}}, 10), std::vector<double>{1.0});
  const std::vector<double> same = LocalOutlierFactors({{1, 1}, {1, 1}, {1, 1}}, 10);
  for (double v : same) EXPECT_DOUBLE_EQ(v, 1.0);
}

TEST(ChangeDetectorTest, AddedFeaturesAreFoundWithinTheTopTenMasks) {
  std::mt19937_64 rng(21);
  int found = 0;
  const int tasks = 20;
  for (int t = 0; t < tasks; ++t) {
    const Task task = MakeTask(rng, 5);
    const std::vector<ChangeMask> masks = Detect(task, rng);
    for (size_t m = 0; m < masks.size() && m < 10; ++m) {
      bool hit = false;
      for (const Point2& p : masks[m].points)
        hit |= std::fabs(p.x - task.region_own.x) < 1.2 && std::fabs(p.y - task.region_own.y) < 1.2;
      if (hit) {
        ++found;
        break;
      }
    }
  }
  EXPECT_GE(found, tasks * 7 / 10);  // 16 of 20 at the time of writing
}

TEST(ChangeDetectorTest, UnchangedCopyYieldsFewMasks) {
  std::mt19937_64 rng(22);
  size_t masks_from_top_map = 0;
  for (int t = 0; t < 10; ++t) {
    const Task task = MakeTask(rng, 0);
    for (const ChangeMask& m : Detect(task, rng)) masks_from_top_map += m.db_map_id == 7;
  }
  EXPECT_LE(masks_from_top_map, 10u);  // <= 1 per task on average (72 features each)
}

TEST(ChangeDetectorTest, MasksAreRankedByMapScoreThenByNovelty) {
  std::mt19937_64 rng(23);
  const Task task = MakeTask(rng, 5);
  ChangeDetectorOptions options;
  options.merge_radius_m = 0.0;  // one mask per change feature
  const std::vector<ChangeMask> masks = Detect(task, rng, options);
  ASSERT_GE(masks.size(), 2u);
  for (size_t m = 0; m < masks.size(); ++m) {
    EXPECT_EQ(masks[m].rank, m);
    EXPECT_EQ(masks[m].points.size(), 1u);
    EXPECT_GT(masks[m].score, options.threshold);
    if (m == 0) continue;
    EXPECT_GE(masks[m - 1].map_score, masks[m].map_score);
    if (masks[m - 1].map_score == masks[m].map_score) {
      EXPECT_GE(masks[m - 1].score, masks[m].score);
    }
  }
}

TEST(ChangeDetectorTest, FeatureWithNoDbFeatureNearbyIsAStrongChangeInTheOwnFrame) {
  Lmd db;
  db.features.push_back({1, 0.0f, 0.0f, 0x123});
  db.features.push_back({2, 1.0f, 0.0f, 0x456});
  Lmd query;
  query.frame = {{5.0, 5.0}, M_PI / 2};
  query.features.push_back({1, 0.0f, 0.0f, 0x123});
  query.features.push_back({2, 1.0f, 0.0f, 0x456});
  query.features.push_back({3, 20.0f, 0.0f, 0x789});
  ChangeDetectorOptions options;
  options.lof_threshold = std::numeric_limits<double>::infinity();  // keep the far feature
  MapHit hit;
  hit.map_id = 3;
  hit.score = 0.9;
  auto masks = DetectChanges(query, {{hit, &db}}, options);
  ASSERT_TRUE(masks.ok());
  ASSERT_EQ(masks->size(), 1u);
  const ChangeMask& m = (*masks)[0];
  EXPECT_EQ(m.db_map_id, 3u);
  EXPECT_DOUBLE_EQ(m.map_score, 0.9);
  EXPECT_DOUBLE_EQ(m.score, options.empty_window_score);
  ASSERT_EQ(m.points.size(), 1u);
  EXPECT_NEAR(m.points[0].x, 5.0, 1e-9);  // own = origin + R(90 deg) * (20, 0)
  EXPECT_NEAR(m.points[0].y, 25.0, 1e-9);
}

TEST(ChangeDetectorTest, RejectsBadOptionsAndMissingDescriptors) {
  Lmd query;
  MapHit hit;
  ChangeDetectorOptions options;
  EXPECT_EQ(DetectChanges(query, {{hit, nullptr}}, options).status().code(), Status::Code::kInvalidArgument);
  for (auto mutate : std::vector<void (*)(ChangeDetectorOptions&)>{
           [](ChangeDetectorOptions& o) { o.lof_k = 0; },
           [](ChangeDetectorOptions& o) { o.threshold = -1; },
           [](ChangeDetectorOptions& o) { o.window_half_m = 0; },
           [](ChangeDetectorOptions& o) { o.spatial_weight = -0.5; },
           [](ChangeDetectorOptions& o) { o.min_denominator = 0; },
           [](ChangeDetectorOptions& o) { o.merge_radius_m = std::nan(""); }}) {
    ChangeDetectorOptions bad;
    mutate(bad);
    EXPECT_EQ(DetectChanges(query, {}, bad).status().code(), Status::Code::kInvalidArgument);
  }
  EXPECT_TRUE(DetectChanges(query, {}, options).ok());
}

}  // namespace
}  // namespace lmd
