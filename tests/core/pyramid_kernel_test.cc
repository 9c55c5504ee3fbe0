#include "core/index/pyramid_kernel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "tests/core/synthetic_lmd.h"

namespace lmd {
namespace {

using testing::RandomLmd;
using testing::TransformedCopy;

int64_t Floor(int64_t a, int64_t b) { return static_cast<int64_t>(std::floor(static_cast<double>(a) / b)); }

// The kernel's definition (pyramid_kernel.h), written as plainly as possible.
KernelScore Reference(const PreparedLmdQuery& q, const std::vector<PoseFeature>& db) {
  KernelScore best;
  for (int o = 0; o < 4; ++o) {
    std::map<std::pair<int64_t, int64_t>, std::vector<std::pair<int64_t, int64_t>>> bins;
    for (size_t i = 0; i < q.features.size(); ++i) {
      for (const PoseFeature& d : db) {
        if (d.word != q.features[i].word) continue;
        const int64_t dx = d.x - q.rx[o][i], dy = d.y - q.ry[o][i];
        if (std::abs(dx) > q.max_offset || std::abs(dy) > q.max_offset) continue;
        bins[{Floor(dx, q.offset_bin), Floor(dy, q.offset_bin)}].push_back({dx, dy});
      }
    }
    if (bins.empty()) continue;
    const std::vector<std::pair<int64_t, int64_t>>* mode = nullptr;
    for (const auto& kv : bins)
      if (mode == nullptr || kv.second.size() > mode->size()) mode = &kv.second;  // ties: first (smallest) bin
    int64_t sx = 0, sy = 0;
    for (const auto& d : *mode) sx += d.first, sy += d.second;
    const int64_t c = static_cast<int64_t>(mode->size());
    const int64_t tx = Floor(2 * sx + c, 2 * c), ty = Floor(2 * sy + c, 2 * c);
    double raw = 0;
    for (int l = 0; l <= q.levels; ++l) {
      const int64_t cw = q.cell0 >> l;
      std::map<std::tuple<uint32_t, int64_t, int64_t>, int> hq, hd;
      for (size_t i = 0; i < q.features.size(); ++i)
        ++hq[{q.features[i].word, Floor(q.rx[o][i] + tx, cw), Floor(q.ry[o][i] + ty, cw)}];
      for (const PoseFeature& d : db) ++hd[{d.word, Floor(d.x, cw), Floor(d.y, cw)}];
      int inter = 0;
      for (const auto& kv : hq) {
        auto it = hd.find(kv.first);
        if (it != hd.end()) inter += std::min(kv.second, it->second);
      }
      raw += inter * (l == 0 ? std::pow(2.0, -q.levels) : std::pow(2.0, -(q.levels - l + 1)));
    }
    const double score = NormalizeScore(raw, q.features.size(), db.size(), q.normalization);
    if (score > best.score) best = {score, o, static_cast<int32_t>(tx), static_cast<int32_t>(ty)};
  }
  return best;
}

TEST(PyramidKernelTest, MatchesItsDefinitionOnRandomMaps) {
  std::mt19937_64 rng(31);
  IndexOptions io;
  KernelScratch scratch;
  int nonzero = 0;
  for (int trial = 0; trial < 60; ++trial) {
    // Few words (4 bits) so that words repeat within a map, as frequent
    // "wall" words do; small maps so that cells are shared.
    const int bits = trial % 3 == 0 ? 10 : 3;
    const Lmd db = RandomLmd(rng, 20 + trial, 6.0, bits);
    const Lmd query = trial % 2 ? TransformedCopy(db, trial % 4, 0.3, -0.2, rng, 0.05, 0.8)
                                : RandomLmd(rng, 30, 6.0, bits);
    RetrieveOptions ro;
    // 20 m: more offset bins than the kernel counts in an array (it sorts).
    ro.max_offset_m = trial % 5 == 0 ? 2.0 : trial % 5 == 1 ? 20.0 : 0.5;
    ro.offset_bin_m = trial % 7 == 0 ? 0.25 : 0.5;
    const PreparedLmdQuery q = PrepareLmdQuery(*ToPoseFeatures(query, io), io, ro);
    const std::vector<PoseFeature> d = *ToPoseFeatures(db, io);
    const KernelScore got = ScoreLmdMap(q, d.data(), d.size(), &scratch);
    const KernelScore want = Reference(q, d);
    EXPECT_EQ(got.score, want.score) << "trial " << trial;
    EXPECT_EQ(got.orientation, want.orientation) << "trial " << trial;
    EXPECT_EQ(got.offset_x, want.offset_x) << "trial " << trial;
    EXPECT_EQ(got.offset_y, want.offset_y) << "trial " << trial;
    nonzero += want.score > 0;
  }
  EXPECT_GE(nonzero, 40);
}

TEST(PyramidKernelTest, OrientationMaskScoresOnlyTheChosenOrientations) {
  std::mt19937_64 rng(32);
  IndexOptions io;
  RetrieveOptions ro;
  KernelScratch scratch;
  const Lmd db = RandomLmd(rng, 60, 6.0, 4);
  const Lmd query = TransformedCopy(db, 1, 0.2, 0.1, rng, 0.05, 0.8);  // true orientation: 1
  const PreparedLmdQuery q = PrepareLmdQuery(*ToPoseFeatures(query, io), io, ro);
  const std::vector<PoseFeature> d = *ToPoseFeatures(db, io);
  const KernelScore all = ScoreLmdMap(q, d.data(), d.size(), &scratch);
  ASSERT_GT(all.score, 0.0);
  for (int o = 0; o < 4; ++o) {
    const KernelScore one = ScoreLmdMap(q, d.data(), d.size(), &scratch, 1u << o);
    EXPECT_LE(one.score, all.score) << o;
    if (one.score > 0) {
      EXPECT_EQ(one.orientation, o);
    }
    if (o == all.orientation) {
      EXPECT_EQ(one.score, all.score);
      EXPECT_EQ(one.offset_x, all.offset_x);
      EXPECT_EQ(one.offset_y, all.offset_y);
    }
  }
  const KernelScore without_best = ScoreLmdMap(q, d.data(), d.size(), &scratch, 0xFu & ~(1u << all.orientation));
  EXPECT_LT(without_best.score, all.score);
  EXPECT_EQ(ScoreLmdMap(q, d.data(), d.size(), &scratch, 0u).score, 0.0);
}

TEST(PyramidKernelTest, InnerWordsAreTaggedPoseFeaturesThatMatchOnlyInnerWords) {
  IndexOptions io;
  RetrieveOptions ro;
  KernelScratch scratch;
  Lmd query, inner_match, outer_only;
  query.features = {{7, 1.0f, 1.0f, 0, 21}, {9, 2.0f, 0.5f, 0}};
  // Word 21 as an inner word at the same place: a match. Word 21 as an outer
  // word (and 7 as an inner word): no match, the tag keeps the two apart.
  inner_match.features = {{300, 1.0f, 1.0f, 0, 21}};
  outer_only.features = {{21, 1.0f, 1.0f, 0, 7}};
  EXPECT_EQ(PoseFeatureCount(query), 3u);
  const std::vector<PoseFeature> qf = *ToPoseFeatures(query, io);
  ASSERT_EQ(qf.size(), 3u);
  EXPECT_EQ(qf.back().word, 21u | kInnerWordTag);  // sorted by word: the tagged one last
  EXPECT_EQ(qf.back().x, qf.front().x);
  const PreparedLmdQuery q = PrepareLmdQuery(qf, io, ro);
  const auto a = *ToPoseFeatures(inner_match, io);
  const auto b = *ToPoseFeatures(outer_only, io);
  EXPECT_GT(ScoreLmdMap(q, a.data(), a.size(), &scratch).score, 0.0);
  EXPECT_EQ(ScoreLmdMap(q, b.data(), b.size(), &scratch).score, 0.0);
  // Words at or above the tag cannot carry an inner word.
  Lmd wide;
  wide.features = {{kInnerWordTag, 0.0f, 0.0f, 0, 1}};
  EXPECT_EQ(ToPoseFeatures(wide, io).status().code(), Status::Code::kInvalidArgument);
  wide.features = {{1, 0.0f, 0.0f, 0, kInnerWordTag}};
  EXPECT_EQ(ToPoseFeatures(wide, io).status().code(), Status::Code::kInvalidArgument);
}

TEST(PyramidKernelTest, LevelZeroIsOneCellNotTheWholeMap) {
  // Same word 6 m apart after alignment: different 5 m cells, so no match
  // at any level; 1 m apart inside one 5 m cell: level 0 only.
  IndexOptions io;
  RetrieveOptions ro;
  ro.max_offset_m = 0.0;
  KernelScratch scratch;
  Lmd query, near_db, far_db;
  query.features = {{7, 1.0f, 1.0f, 0}, {9, 0.2f, 0.2f, 0}};
  near_db.features = {{7, 3.0f, 1.0f, 0}, {9, 0.2f, 0.2f, 0}};  // word 9 anchors offset 0
  far_db.features = {{7, 7.0f, 1.0f, 0}, {9, 0.2f, 0.2f, 0}};
  const PreparedLmdQuery q = PrepareLmdQuery(*ToPoseFeatures(query, io), io, ro);
  const auto near = *ToPoseFeatures(near_db, io);
  const auto far = *ToPoseFeatures(far_db, io);
  // Word 9 matches at all levels (raw 1); word 7 adds I^0/4 only when near.
  EXPECT_DOUBLE_EQ(ScoreLmdMap(q, near.data(), near.size(), &scratch).score, 1.25 / 2.0);
  EXPECT_DOUBLE_EQ(ScoreLmdMap(q, far.data(), far.size(), &scratch).score, 1.0 / 2.0);
}

}  // namespace
}  // namespace lmd

namespace lmd {
namespace {

TEST(PyramidKernelTest, FloorDividerEqualsFloorDivision) {
  for (int32_t d : {1, 2, 3, 7, 10, 25, 50, 100, 255, 4096, 29999}) {
    const FloorDivider div(d);
    for (int32_t x = -300000; x <= 300000; x += (x > -2000 && x < 2000) ? 1 : 97) {
      ASSERT_EQ(div(x), static_cast<int32_t>(std::floor(static_cast<double>(x) / d))) << x << " / " << d;
    }
  }
}

}  // namespace
}  // namespace lmd
