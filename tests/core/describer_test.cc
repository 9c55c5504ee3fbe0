#include "core/describe/describer.h"

#include <chrono>
#include <cmath>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "core/viewpoint/viewpoint.h"
#include "tests/core/toy_world.h"

namespace lmd {
namespace {

LocalMap ToyMap() { return testing::ScanWorld(testing::RoomAndCorridor(), testing::RoomVisit()); }

// Appearance word of each feature keyed by its position rounded to 1 cm.
std::map<std::pair<long, long>, uint32_t> WordsByPosition(const Lmd& lmd) {
  std::map<std::pair<long, long>, uint32_t> m;
  for (const Feature& f : lmd.features) m[{std::lround(f.x * 100), std::lround(f.y * 100)}] = f.appearance_word;
  return m;
}

TEST(DescriberTest, PaperSettingsAreTheEightOfThePaper) {
  const double r[8] = {1, 6, 12, 1, 3, 6, 3, 6};
  const int a[8] = {1, 3, 6, 6, 6, 6, 1, 1};
  for (int i = 1; i <= 8; ++i) {
    EXPECT_EQ(PaperDescriptorSetting(i).radius_m, r[i - 1]);
    EXPECT_EQ(PaperDescriptorSetting(i).sectors, a[i - 1]);
  }
  EXPECT_EQ(PaperDescriptorSetting(0).radius_m, 1.0);
}

TEST(DescriberTest, InnerWordsDescribeTheSmallerNeighbourhood) {
  const LocalMap map = ToyMap();
  const Frame frame = PlanViewpoint(map);
  const DescriberOptions product = WithInnerWords(ProductDescriberOptions());
  ASSERT_GT(product.inner_radius_m, 0.0);
  const Lmd with = Describe(map, frame, product);
  DescriberOptions none = product;
  none.inner_radius_m = 0.0;
  const Lmd without = Describe(map, frame, none);
  ASSERT_GT(with.features.size(), 20u);
  ASSERT_EQ(with.features.size(), without.features.size());
  size_t differ = 0;
  for (size_t i = 0; i < with.features.size(); ++i) {
    // Same interest points and outer words; the inner word is extra.
    EXPECT_EQ(with.features[i].appearance_word, without.features[i].appearance_word);
    EXPECT_EQ(with.features[i].x, without.features[i].x);
    EXPECT_EQ(without.features[i].inner_word, kNoWord);
    ASSERT_NE(with.features[i].inner_word, kNoWord);
    EXPECT_LT(with.features[i].inner_word, 1u << product.word_bits);
    differ += with.features[i].inner_word != with.features[i].appearance_word;
  }
  EXPECT_GT(differ, with.features.size() / 2);  // a 3 m context is not the 6 m one
  // An inner radius not below R, or words too wide to tag, give none.
  DescriberOptions wide = product;
  wide.inner_radius_m = product.setting.radius_m;
  EXPECT_EQ(Describe(map, frame, wide).features[0].inner_word, kNoWord);
  DescriberOptions bits16 = product;
  bits16.word_bits = 16;
  EXPECT_EQ(Describe(map, frame, bits16).features[0].inner_word, kNoWord);
}

TEST(DescriberTest, IdenticalInputGivesIdenticalDescriptor) {
  const LocalMap map = ToyMap();
  const Frame frame = PlanViewpoint(map);
  const Lmd a = Describe(map, frame), b = Describe(map, frame);
  ASSERT_GT(a.features.size(), 20u);
  ASSERT_EQ(a.features.size(), b.features.size());
  for (size_t i = 0; i < a.features.size(); ++i) {
    EXPECT_EQ(a.features[i].appearance_word, b.features[i].appearance_word);
    EXPECT_EQ(a.features[i].change_word, b.features[i].change_word);
    EXPECT_EQ(a.features[i].x, b.features[i].x);
  }
  EXPECT_EQ(a.frame.origin.x, frame.origin.x);
  const DescriberOptions inner = WithInnerWords(ProductDescriberOptions());
  const Lmd c = Describe(map, frame, inner), d = Describe(map, frame, inner);
  ASSERT_EQ(c.features.size(), d.features.size());
  for (size_t i = 0; i < c.features.size(); ++i) EXPECT_EQ(c.features[i].inner_word, d.features[i].inner_word);
}

TEST(DescriberTest, WordsUseTheirBitWidthsAndDiffer) {
  const LocalMap map = ToyMap();
  const Frame frame = PlanViewpoint(map);
  for (int s = 1; s <= 8; ++s) {
    DescriberOptions options;
    options.setting = PaperDescriptorSetting(s);
    const Lmd lmd = Describe(map, frame, options);
    std::map<uint32_t, int> words;
    for (const Feature& f : lmd.features) {
      EXPECT_LT(f.appearance_word, 1u << 10);
      EXPECT_EQ(f.change_word >> 60, 0u);
      ++words[f.appearance_word];
    }
    EXPECT_GE(words.size(), 3u) << "setting " << s;  // words discriminate
  }
}

TEST(DescriberTest, SmallNoiseKeepsMostWords) {
  const LocalMap map = ToyMap();
  const Frame frame = PlanViewpoint(map);
  LocalMap noisy = map;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);  // 5 mm
  for (Point2& p : noisy.points) p.x += noise(rng), p.y += noise(rng);
  const auto a = WordsByPosition(Describe(map, frame));
  const auto b_lmd = Describe(noisy, frame);
  // Match features by interest cell: same cell -> compare words.
  size_t same = 0, compared = 0;
  std::map<std::pair<long, long>, uint32_t> b_cells;
  for (const Feature& f : b_lmd.features) b_cells[{std::lround(std::floor(f.x / 0.5)), std::lround(std::floor(f.y / 0.5))}] = f.appearance_word;
  for (const auto& [pos, word] : a) {
    const std::pair<long, long> cell{std::lround(std::floor(pos.first / 50.0)), std::lround(std::floor(pos.second / 50.0))};
    auto it = b_cells.find(cell);
    if (it == b_cells.end()) continue;
    ++compared;
    same += it->second == word;
  }
  ASSERT_GE(compared, a.size() * 8 / 10);  // a few points cross interest-cell borders
  EXPECT_GE(static_cast<double>(same) / compared, 0.7) << same << " of " << compared;
}

TEST(DescriberTest, QuarterTurnOfTheFrameKeepsTheWords) {
  // The planned heading is only known modulo 90 deg: the canonical sector
  // origin must give the same words whichever quarter turn the frame has.
  const LocalMap map = ToyMap();
  const Frame frame = PlanViewpoint(map);
  for (int s : {1, 2, 3, 6}) {
    DescriberOptions options;
    options.setting = PaperDescriptorSetting(s);
    const Lmd a = Describe(map, frame, options);
    const Lmd b = Describe(map, {frame.origin, frame.heading + M_PI / 2}, options);
    ASSERT_EQ(a.features.size(), b.features.size());
    // Feature at (x, y) in frame a is at (y, -x) in frame b.
    std::map<std::pair<long, long>, const Feature*> in_b;
    for (const Feature& f : b.features) in_b[{std::lround(f.x * 100), std::lround(f.y * 100)}] = &f;
    size_t same = 0, same_change = 0;
    for (const Feature& f : a.features) {
      auto it = in_b.find({std::lround(f.y * 100), std::lround(-f.x * 100)});
      ASSERT_NE(it, in_b.end());
      same += it->second->appearance_word == f.appearance_word;
      same_change += it->second->change_word == f.change_word;
    }
    EXPECT_GE(same, a.features.size() * 95 / 100) << "setting " << s;
    EXPECT_GE(same_change, a.features.size() * 95 / 100) << "setting " << s;
  }
}

TEST(DescriberTest, FeaturesAreBoundedAndInThePlannedFrame) {
  const LocalMap map = ToyMap();
  const Frame frame = PlanViewpoint(map);
  DescriberOptions options;
  options.max_features = 25;
  const Lmd lmd = Describe(map, frame, options);
  EXPECT_EQ(lmd.features.size(), 25u);
  for (const Feature& f : lmd.features) {
    // Every feature is a map point expressed in the frame.
    const Point2 own = FromFrame(frame, {f.x, f.y});
    double best = 1e9;
    for (const Point2& p : map.points) best = std::min(best, std::hypot(p.x - own.x, p.y - own.y));
    EXPECT_LT(best, 1e-3);
  }
  EXPECT_TRUE(Describe(LocalMap{}, frame).features.empty());
}

TEST(DescriberTest, DescribingTheToyMapTakesMilliseconds) {
  const LocalMap map = ToyMap();
  const Frame frame = PlanViewpoint(map);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 20; ++i) Describe(map, frame);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / 20;
  EXPECT_LT(ms, 20.0);  // generous: a few ms in release builds
}

}  // namespace
}  // namespace lmd
