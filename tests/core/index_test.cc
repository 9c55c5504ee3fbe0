#include "core/index/index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/index/exhaustive.h"
#include "core/index/postings.h"
#include "tests/core/synthetic_lmd.h"

namespace lmd {
namespace {

using testing::RandomLmd;
using testing::TransformedCopy;

Index MakeIndex(const IndexOptions& options = {}) {
  auto index = Index::Create(options);
  EXPECT_TRUE(index.ok()) << index.status().ToString();
  return std::move(index).value();
}

// A collection of places, each stored as several noisy views, plus queries
// that are new views of some places.
struct Collection {
  std::vector<Lmd> places;
  std::vector<Lmd> maps;
  std::vector<Lmd> queries;
};

// Views are shifted by up to 0.5 m per axis (the default max offset).
Collection MakeCollection(uint64_t seed, int places, int views, int queries, int features) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> shift(-0.5, 0.5);
  Collection c;
  for (int p = 0; p < places; ++p) c.places.push_back(RandomLmd(rng, features));
  for (int p = 0; p < places; ++p)
    for (int v = 0; v < views; ++v)
      c.maps.push_back(TransformedCopy(c.places[p], static_cast<int>(rng() % 4), shift(rng), shift(rng), rng, 0.1, 0.7));
  for (int q = 0; q < queries; ++q)
    c.queries.push_back(TransformedCopy(c.places[rng() % places], static_cast<int>(rng() % 4), shift(rng),
                                        shift(rng), rng, 0.1, 0.7));
  return c;
}

void ExpectSameHits(const std::vector<MapHit>& a, const std::vector<MapHit>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].map_id, b[i].map_id) << "rank " << i;
    EXPECT_EQ(a[i].score, b[i].score) << "rank " << i;  // bit-identical
    EXPECT_EQ(a[i].orientation, b[i].orientation) << "rank " << i;
    EXPECT_EQ(a[i].offset.x, b[i].offset.x) << "rank " << i;
    EXPECT_EQ(a[i].offset.y, b[i].offset.y) << "rank " << i;
    EXPECT_EQ(a[i].rank, i);
    EXPECT_EQ(b[i].rank, i);
  }
}

// Every query gets the same hits from the inverted file as from the
// exhaustive scorer (and at least one hit when `expect_hits`).
void ExpectInvertedFileAgrees(const Index& index, const std::vector<Lmd>& queries, const RetrieveOptions& options,
                              bool expect_hits) {
  for (const Lmd& q : queries) {
    auto inverted = index.Retrieve(q, options);
    auto exhaustive = RetrieveExhaustive(index, q, options);
    ASSERT_TRUE(inverted.ok() && exhaustive.ok());
    if (expect_hits) {
      ASSERT_FALSE(inverted->empty());
    }
    ExpectSameHits(*inverted, *exhaustive);
  }
}

TEST(IndexTest, InvertedFileAndExhaustiveScorerAgreeOnRandomCollections) {
  for (uint64_t seed : {1, 2, 3}) {
    Collection c = MakeCollection(seed, 60, 4, 15, 80);
    Index index = MakeIndex();
    for (size_t m = 0; m < c.maps.size(); ++m) ASSERT_TRUE(index.Add(1000 + m * 7, c.maps[m]).ok());
    for (Normalization norm : {Normalization::kSqrt, Normalization::kMin, Normalization::kNone}) {
      for (Method method : {Method::kLmd, Method::kBow}) {
        for (size_t k : {1, 10, 300}) {
          RetrieveOptions options;
          options.top_k = k;
          options.method = method;
          options.normalization = norm;
          ExpectInvertedFileAgrees(index, c.queries, options, true);
        }
      }
    }
  }
}

// A limit on maps scored: the top k still filled, never more maps scored than
// exact retrieval scores, hits with their exact scores, and a limit at what
// exact retrieval scores changes nothing.
TEST(IndexTest, MaxMapsScoredBoundsPassTwoAndScoresExactly) {
  Collection c = MakeCollection(5, 60, 4, 15, 80);
  Index index = MakeIndex();
  for (size_t m = 0; m < c.maps.size(); ++m) ASSERT_TRUE(index.Add(m, c.maps[m]).ok());
  RetrieveOptions exact;
  exact.top_k = 10;
  size_t limited_differs = 0;
  for (const Lmd& q : c.queries) {
    RetrieveStats exact_stats;
    auto all = index.Retrieve(q, exact, &exact_stats);
    ASSERT_TRUE(all.ok());
    RetrieveOptions limited = exact;
    limited.max_maps_scored = 12;
    RetrieveStats stats;
    auto some = index.Retrieve(q, limited, &stats);
    ASSERT_TRUE(some.ok());
    EXPECT_LE(stats.maps_scored, exact_stats.maps_scored);
    EXPECT_EQ(some->size(), all->size());  // the limit applies once the top k is full
    auto scores = RetrieveExhaustive(index, q, [&] { RetrieveOptions o = exact; o.top_k = c.maps.size(); return o; }());
    ASSERT_TRUE(scores.ok());
    for (const MapHit& hit : *some) {
      const auto same = std::find_if(scores->begin(), scores->end(), [&](const MapHit& h) { return h.map_id == hit.map_id; });
      ASSERT_NE(same, scores->end());
      EXPECT_EQ(same->score, hit.score);
    }
    limited_differs += some->size() != all->size() || !std::equal(some->begin(), some->end(), all->begin(),
                                                                  [](const MapHit& a, const MapHit& b) { return a.map_id == b.map_id; });
    limited.max_maps_scored = exact_stats.maps_scored;
    auto same = index.Retrieve(q, limited);
    ASSERT_TRUE(same.ok());
    ExpectSameHits(*same, *all);
  }
  EXPECT_GT(limited_differs, 0u) << "the limit never bit: the test checks nothing";
}

// A word on every map several times (a straight-wall word): with
// bound_skip_postings_per_map below its postings per map, pass 1 skips its
// lists but adds their most possible gain to every bound. A marker word once
// per map near its origin keeps every map a candidate, so the hits must be
// the exhaustive scorer's, while far fewer postings are read.
TEST(IndexTest, BoundSkipLeavesCommonWordsOutOfPassOneOnly) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> pos(-4.0, 4.0);
  constexpr uint32_t kWallWord = 7, kMarkerWord = 11;
  constexpr int kViews = 4;
  std::vector<Lmd> places;
  for (int p = 0; p < 40; ++p) {
    Lmd place = RandomLmd(rng, 40);
    for (int i = 0; i < 30; ++i) {
      Feature wall;
      wall.appearance_word = kWallWord;
      wall.x = static_cast<float>(pos(rng));
      wall.y = static_cast<float>(pos(rng));
      place.features.push_back(wall);
    }
    Feature marker;
    marker.appearance_word = kMarkerWord;
    place.features.push_back(marker);
    places.push_back(place);
  }
  Index index = MakeIndex();
  for (size_t p = 0; p < places.size(); ++p)
    for (int v = 0; v < kViews; ++v)
      ASSERT_TRUE(index.Add(p * kViews + v, TransformedCopy(places[p], 0, 0.1 * v, -0.1 * v, rng, 0.05)).ok());
  RetrieveOptions exact;
  exact.top_k = 10;
  RetrieveOptions skip = exact;
  skip.bound_skip_postings_per_map = 3.0;  // the wall word has about 24 postings per map
  for (size_t p = 0; p < places.size(); p += 5) {
    const Lmd query = TransformedCopy(places[p], static_cast<int>(p % 4), 0.2, 0.3, rng, 0.05);
    RetrieveStats exact_stats, skip_stats;
    auto all = index.Retrieve(query, exact, &exact_stats);
    auto fewer = index.Retrieve(query, skip, &skip_stats);
    ASSERT_TRUE(all.ok() && fewer.ok());
    EXPECT_LT(skip_stats.postings_read * 2, exact_stats.postings_read) << "place " << p;
    EXPECT_EQ(skip_stats.maps_touched, index.size());
    auto exhaustive = RetrieveExhaustive(index, query, exact);
    ASSERT_TRUE(exhaustive.ok());
    ExpectSameHits(*fewer, *exhaustive);
    ExpectSameHits(*all, *exhaustive);
    EXPECT_EQ((*fewer)[0].map_id / kViews, p);
  }
  skip.bound_skip_postings_per_map = -1;
  EXPECT_EQ(index.Retrieve(places[0], skip).status().code(), Status::Code::kInvalidArgument);
}

// Maps made of common words only (a small store of one square room): the
// skip would leave no candidate, so every list is read and the hits are the
// exhaustive scorer's.
TEST(IndexTest, BoundSkipReadsEveryListWhenTooFewMapsRemain) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> pos(-3.0, 3.0);
  Lmd room;
  for (int i = 0; i < 40; ++i) {
    Feature wall;
    wall.appearance_word = static_cast<uint32_t>(i % 4);  // 10 postings per map for each of 4 words
    wall.x = static_cast<float>(pos(rng));
    wall.y = static_cast<float>(pos(rng));
    room.features.push_back(wall);
  }
  Index index = MakeIndex();
  for (uint64_t id = 0; id < 3; ++id) ASSERT_TRUE(index.Add(id, TransformedCopy(room, 0, 0.1, 0.0, rng, 0.05)).ok());
  RetrieveOptions skip;
  skip.top_k = 5;
  skip.bound_skip_postings_per_map = 3.0;
  RetrieveStats stats;
  auto hits = index.Retrieve(room, skip, &stats);
  auto exhaustive = RetrieveExhaustive(index, room, skip);
  ASSERT_TRUE(hits.ok() && exhaustive.ok());
  EXPECT_EQ(hits->size(), 3u);
  EXPECT_EQ(stats.maps_touched, 3u);
  ExpectSameHits(*hits, *exhaustive);
}

// Pass 1 reads the posting lists in blocks of slots (index.cc): a collection
// spanning several blocks, whose freed slots are then reused out of order,
// must still give the exhaustive scorer's hits.
TEST(IndexTest, InvertedFileAndExhaustiveScorerAgreeAcrossSlotBlocksAndReusedSlots) {
  Collection c = MakeCollection(21, 3000, 4, 12, 16);
  Index index = MakeIndex();
  for (size_t m = 0; m < c.maps.size(); ++m) ASSERT_TRUE(index.Add(m, c.maps[m]).ok());
  RetrieveOptions options;
  options.top_k = 20;
  ExpectInvertedFileAgrees(index, c.queries, options, true);
  for (size_t m = 5; m < c.maps.size(); m += 97) ASSERT_TRUE(index.Remove(m));
  // Re-added in reverse under new ids: the freed slots are taken last-freed first.
  for (size_t m = c.maps.size(); m-- > 5;) {
    if ((m - 5) % 97 == 0) {
      ASSERT_TRUE(index.Add(100000 + m, c.maps[m]).ok());
    }
  }
  ExpectInvertedFileAgrees(index, c.queries, options, true);
}

TEST(IndexTest, InvertedFileAndExhaustiveScorerAgreeForAnyPyramidAndOffsetBox) {
  Collection c = MakeCollection(12, 30, 3, 6, 60);
  for (int levels : {0, 1, 3, 4}) {
    for (double cell : {2.4, 6.4}) {
      IndexOptions io;
      io.pyramid_levels = levels;
      io.pyramid_cell_m = cell;
      Index index = MakeIndex(io);
      for (size_t m = 0; m < c.maps.size(); ++m) ASSERT_TRUE(index.Add(m, c.maps[m]).ok());
      for (double max_offset : {0.0, 0.5, 2.0, 6.0}) {
        RetrieveOptions options;
        options.max_offset_m = max_offset;
        options.offset_bin_m = 0.25;
        ExpectInvertedFileAgrees(index, c.queries, options, false);
      }
    }
  }
}

TEST(IndexTest, InvertedFileAgreesWithExhaustiveWhenMapsShareNoPlace) {
  // All maps random: many near-equal low scores, where ties and the pruning
  // bound matter most.
  std::mt19937_64 rng(9);
  Index index = MakeIndex();
  for (uint64_t m = 0; m < 400; ++m) ASSERT_TRUE(index.Add(m, RandomLmd(rng, 60, 8.0, 6)).ok());
  RetrieveOptions options;
  for (int q = 0; q < 10; ++q) {
    const Lmd query = RandomLmd(rng, 60, 8.0, 6);
    auto inverted = index.Retrieve(query, options);
    auto exhaustive = RetrieveExhaustive(index, query, options);
    ASSERT_TRUE(inverted.ok() && exhaustive.ok());
    EXPECT_EQ(inverted->size(), 10u);
    ExpectSameHits(*inverted, *exhaustive);
  }
}

TEST(IndexTest, StopWordsAreDroppedFromQueriesAlikeByBothScorers) {
  // Word 5 on half of every map's features: a "wall" word.
  Collection c = MakeCollection(14, 40, 3, 8, 60);
  for (std::vector<Lmd>* set : {&c.maps, &c.queries})
    for (Lmd& m : *set)
      for (size_t i = 0; i < m.features.size(); i += 2) m.features[i].appearance_word = 5;
  Index index = MakeIndex();
  for (size_t m = 0; m < c.maps.size(); ++m) ASSERT_TRUE(index.Add(m, c.maps[m]).ok());
  EXPECT_EQ(index.StopWords(0.3), std::vector<uint32_t>{5});
  EXPECT_TRUE(index.StopWords(0.6).empty());
  EXPECT_TRUE(index.StopWords(1.0).empty());
  for (double share : {0.3, 1.0}) {
    for (Method method : {Method::kLmd, Method::kBow}) {
      RetrieveOptions options;
      options.max_word_share = share;
      options.method = method;
      ExpectInvertedFileAgrees(index, c.queries, options, false);
    }
  }
  // A query made only of the stop word finds nothing once it is stopped.
  Lmd walls = c.queries[0];
  for (Feature& f : walls.features) f.appearance_word = 5;
  RetrieveOptions options;
  EXPECT_FALSE(index.Retrieve(walls, options)->empty());
  options.max_word_share = 0.3;
  EXPECT_TRUE(index.Retrieve(walls, options)->empty());
  options.max_word_share = 0;
  EXPECT_FALSE(index.Retrieve(walls, options).ok());
  // Removing maps updates the word statistics.
  for (size_t m = 0; m < c.maps.size(); ++m) ASSERT_TRUE(index.Remove(m));
  EXPECT_TRUE(index.StopWords(0.01).empty());
}

TEST(IndexTest, StoredMapIsItsOwnTopHit) {
  Collection c = MakeCollection(4, 50, 3, 0, 80);
  Index index = MakeIndex();
  for (size_t m = 0; m < c.maps.size(); ++m) ASSERT_TRUE(index.Add(m, c.maps[m]).ok());
  for (size_t m = 0; m < c.maps.size(); m += 7) {
    auto hits = index.Retrieve(c.maps[m]);
    ASSERT_TRUE(hits.ok());
    ASSERT_FALSE(hits->empty());
    EXPECT_EQ((*hits)[0].map_id, m);
    EXPECT_EQ((*hits)[0].orientation, 0);
    EXPECT_DOUBLE_EQ((*hits)[0].score, 1.0);  // identical maps, sqrt normalisation
    EXPECT_EQ((*hits)[0].offset.x, 0.0);
    EXPECT_EQ((*hits)[0].offset.y, 0.0);
  }
}

TEST(IndexTest, RotatedAndShiftedCopyGetsOrientationAndOffset) {
  std::mt19937_64 rng(5);
  Index index = MakeIndex();
  const Lmd db = RandomLmd(rng, 120);
  ASSERT_TRUE(index.Add(42, db).ok());
  for (uint64_t m = 0; m < 100; ++m) ASSERT_TRUE(index.Add(100 + m, RandomLmd(rng, 120)).ok());
  RetrieveOptions options;
  options.max_offset_m = 2.0;
  for (int k : {0, 1, 2, 3}) {
    const double tx = 0.8 - 0.5 * k, ty = -1.3 + 0.7 * k;
    const Lmd query = TransformedCopy(db, k, tx, ty, rng, 0.03, 0.8);
    auto hits = index.Retrieve(query, options);
    ASSERT_TRUE(hits.ok());
    ASSERT_FALSE(hits->empty());
    EXPECT_EQ((*hits)[0].map_id, 42u) << "k=" << k;
    EXPECT_EQ((*hits)[0].orientation, k);
    EXPECT_NEAR((*hits)[0].offset.x, tx, 0.1);
    EXPECT_NEAR((*hits)[0].offset.y, ty, 0.1);
    EXPECT_GT((*hits)[0].score, 0.5);
  }
}

TEST(IndexTest, OffsetsBeyondMaxOffsetAreNotFound) {
  std::mt19937_64 rng(6);
  Index index = MakeIndex();
  const Lmd db = RandomLmd(rng, 120);
  ASSERT_TRUE(index.Add(1, db).ok());
  RetrieveOptions options;
  options.max_offset_m = 1.0;
  auto near = index.Retrieve(TransformedCopy(db, 0, 0.9, 0.0, rng), options);
  auto far = index.Retrieve(TransformedCopy(db, 0, 3.0, 0.0, rng), options);
  ASSERT_TRUE(near.ok() && far.ok());
  ASSERT_FALSE(near->empty());
  EXPECT_NEAR((*near)[0].offset.x, 0.9, 0.051);
  EXPECT_TRUE(far->empty() || (*far)[0].score < 0.2);
}

TEST(IndexTest, RemovingAMapRemovesEveryPostingOfIt) {
  std::mt19937_64 rng(7);
  Index index = MakeIndex();
  std::vector<Lmd> maps;
  for (uint64_t m = 0; m < 30; ++m) {
    maps.push_back(RandomLmd(rng, 50));
    ASSERT_TRUE(index.Add(m, maps.back()).ok());
  }
  const size_t before = index.PostingCount();
  EXPECT_EQ(before, 30u * 50u);
  EXPECT_EQ(index.CountPostingsOfMap(12), 50u);
  EXPECT_TRUE(index.Remove(12));
  EXPECT_FALSE(index.Remove(12));
  EXPECT_FALSE(index.Contains(12));
  EXPECT_EQ(index.size(), 29u);
  EXPECT_EQ(index.PostingCount(), before - 50);
  EXPECT_EQ(index.CountPostingsOfMap(12), 0u);
  for (Method method : {Method::kLmd, Method::kBow}) {
    RetrieveOptions options;
    options.method = method;
    options.top_k = 100;
    auto hits = index.Retrieve(maps[12], options);
    ASSERT_TRUE(hits.ok());
    for (const MapHit& h : *hits) EXPECT_NE(h.map_id, 12u);
  }
  // The slot is reused and the map can come back.
  ASSERT_TRUE(index.Add(12, maps[12]).ok());
  EXPECT_EQ(index.PostingCount(), before);
  auto hits = index.Retrieve(maps[12]);
  ASSERT_TRUE(hits.ok());
  EXPECT_EQ((*hits)[0].map_id, 12u);
}

TEST(IndexTest, BowRanksMapsByNumberOfSharedWords) {
  std::mt19937_64 rng(8);
  const Lmd query = RandomLmd(rng, 40);
  Index index = MakeIndex();
  // Map m keeps the first 40 - 5 m query words (positions scrambled: BoW
  // ignores pose) and fills up with words the query does not have.
  for (uint64_t m = 0; m < 6; ++m) {
    Lmd map = RandomLmd(rng, 40);
    for (size_t i = 0; i < map.features.size(); ++i)
      map.features[i].appearance_word = i < 40 - 5 * m ? query.features[i].appearance_word : 2000 + i;
    ASSERT_TRUE(index.Add(m, map).ok());
  }
  RetrieveOptions options;
  options.method = Method::kBow;
  auto hits = index.Retrieve(query, options);
  ASSERT_TRUE(hits.ok());
  ASSERT_EQ(hits->size(), 6u);
  for (uint64_t m = 0; m < 6; ++m) {
    EXPECT_EQ((*hits)[m].map_id, m);
    EXPECT_DOUBLE_EQ((*hits)[m].score, (40.0 - 5.0 * m) / 40.0);
    EXPECT_EQ((*hits)[m].rank, m);
  }
}

TEST(IndexTest, LoadingPostingRecordsRestoresTheSameIndex) {
  Collection c = MakeCollection(10, 20, 3, 5, 60);
  Index original = MakeIndex();
  Index loaded = MakeIndex();
  std::vector<PostingRecord> all;
  for (size_t m = 0; m < c.maps.size(); ++m) {
    ASSERT_TRUE(original.Add(m, c.maps[m]).ok());
    auto records = PostingsOf(m, c.maps[m], original.options());
    ASSERT_TRUE(records.ok());
    // Small ids and cells near the origin: 2 + 1 + 1 + 1 key bytes, 2 per feature.
    EXPECT_EQ(PostingBytes(*records), records->size() * 5 + c.maps[m].features.size() * 2);
    for (size_t r = 1; r < records->size(); ++r) EXPECT_LT((*records)[r - 1].key, (*records)[r].key);
    all.insert(all.end(), records->begin(), records->end());
  }
  ASSERT_TRUE(LoadPostings(all, &loaded).ok());
  EXPECT_EQ(loaded.size(), original.size());
  EXPECT_EQ(loaded.PostingCount(), original.PostingCount());
  for (const Lmd& q : c.queries) ExpectSameHits(*original.Retrieve(q), *loaded.Retrieve(q));
  EXPECT_EQ(LoadPostings(all, &loaded).code(), Status::Code::kAlreadyExists);
  std::vector<PostingRecord> bad = {all[0]};
  bad[0].value.pop_back();
  EXPECT_EQ(LoadPostings(bad, &loaded).code(), Status::Code::kCorruption);
  bad = {all[0]};
  bad[0].key.push_back('\x80');  // unterminated varint
  EXPECT_EQ(LoadPostings(bad, &loaded).code(), Status::Code::kCorruption);
  bad = {all[0]};
  bad[0].value[0] = static_cast<char>(200);  // beyond the 100-unit cell
  EXPECT_EQ(LoadPostings(bad, &loaded).code(), Status::Code::kCorruption);
  // Negative cells and large ids round-trip too.
  Index one = MakeIndex();
  Lmd far = c.maps[0];
  for (Feature& f : far.features) f.x -= 700.0f;
  auto records = PostingsOf(uint64_t{1} << 40, far, one.options());
  ASSERT_TRUE(records.ok());
  ASSERT_TRUE(LoadPostings(*records, &one).ok());
  Index direct = MakeIndex();
  ASSERT_TRUE(direct.Add(uint64_t{1} << 40, far).ok());
  ExpectSameHits(*one.Retrieve(far), *direct.Retrieve(far));
  EXPECT_EQ((*one.Retrieve(far))[0].map_id, uint64_t{1} << 40);
}

TEST(IndexTest, RejectsBadOptionsAndBadFeatures) {
  IndexOptions bad_index;
  bad_index.pyramid_cell_m = 5.01;
  EXPECT_FALSE(Index::Create(bad_index).ok());
  bad_index = {};
  bad_index.pose_quantum_m = 0;
  EXPECT_FALSE(Index::Create(bad_index).ok());
  bad_index = {};
  bad_index.pyramid_levels = -1;
  EXPECT_FALSE(Index::Create(bad_index).ok());

  Index index = MakeIndex();
  std::mt19937_64 rng(11);
  const Lmd map = RandomLmd(rng, 10);
  ASSERT_TRUE(index.Add(1, map).ok());
  EXPECT_EQ(index.Add(1, map).code(), Status::Code::kAlreadyExists);
  RetrieveOptions options;
  options.top_k = 0;
  EXPECT_EQ(index.Retrieve(map, options).status().code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(RetrieveExhaustive(index, map, options).status().code(), Status::Code::kInvalidArgument);
  options = {};
  options.offset_bin_m = 0;
  EXPECT_FALSE(index.Retrieve(map, options).ok());
  options = {};
  options.max_offset_m = -1;
  EXPECT_FALSE(index.Retrieve(map, options).ok());
  Lmd nan_map = map;
  nan_map.features[3].x = std::nanf("");
  EXPECT_EQ(index.Add(2, nan_map).code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(index.Retrieve(nan_map).status().code(), Status::Code::kInvalidArgument);
  Lmd far_map = map;
  far_map.features[0].x = 1e5f;
  EXPECT_EQ(index.Add(3, far_map).code(), Status::Code::kInvalidArgument);
  Lmd wide_word = map;
  wide_word.features[0].appearance_word = 1u << 20;
  EXPECT_EQ(index.Add(4, wide_word).code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(index.size(), 1u);
}

}  // namespace
}  // namespace lmd
