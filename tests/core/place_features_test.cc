#include "core/place/place_features.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/sim/simulate.h"
#include "core/viewpoint/orientation.h"

namespace lmd {
namespace {

const std::vector<LocalMap>& DemoMaps() {
  static const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  return maps;
}

// A map with plenty of structure: the demo map with the most points.
const LocalMap& RichMap() {
  const std::vector<LocalMap>& maps = DemoMaps();
  return *std::max_element(maps.begin(), maps.end(), [](const LocalMap& a, const LocalMap& b) {
    return a.points.size() < b.points.size();
  });
}

PlaceCode RandomCode(std::mt19937_64& rng) { return {rng(), rng()}; }

bool SameFeatures(const PlaceFeatures& a, const PlaceFeatures& b) {
  if (a.heading != b.heading || a.features.size() != b.features.size()) return false;
  for (size_t i = 0; i < a.features.size(); ++i) {
    const PlaceFeature &fa = a.features[i], &fb = b.features[i];
    if (fa.x != fb.x || fa.y != fb.y || fa.code != fb.code) return false;
  }
  return true;
}

// The map's points turned by k quarter turns about its own origin.
std::vector<Point2> Turned(const std::vector<Point2>& points, int k) {
  std::vector<Point2> out;
  for (const Point2& p : points) out.push_back(TurnQuarters(p, k));
  return out;
}

// The index of the feature of `features` at `p` (within 1 mm), or -1.
int FeatureAt(const PlaceFeatures& features, const Point2& p) {
  for (size_t i = 0; i < features.features.size(); ++i) {
    if (std::hypot(features.features[i].x - p.x, features.features[i].y - p.y) < 1e-3) return static_cast<int>(i);
  }
  return -1;
}

TEST(PlaceFeaturesTest, RotateCodeByFourQuarterTurnsIsTheIdentity) {
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 100; ++trial) {
    const PlaceCode code = RandomCode(rng);
    EXPECT_EQ(RotateCode(code, 0), code);
    EXPECT_EQ(RotateCode(code, 4), code);
    EXPECT_EQ(RotateCode(RotateCode(RotateCode(RotateCode(code, 1), 1), 1), 1), code);
  }
}

TEST(PlaceFeaturesTest, RotateCodeIsAGroupActionOfTheQuarterTurns) {
  std::mt19937_64 rng(2);
  for (int trial = 0; trial < 100; ++trial) {
    const PlaceCode code = RandomCode(rng);
    for (int a = 0; a < 4; ++a) {
      EXPECT_EQ(RotateCode(RotateCode(code, a), 4 - a), code) << a;  // k then 4 - k: back where it was
      EXPECT_EQ(RotateCode(code, a - 4), RotateCode(code, a)) << a;  // k mod 4, negative k too
      EXPECT_EQ(RotateCode(code, a + 8), RotateCode(code, a)) << a;
      for (int b = 0; b < 4; ++b) EXPECT_EQ(RotateCode(RotateCode(code, a), b), RotateCode(code, a + b)) << a << b;
    }
    // A quarter turn changes a random code (it is not the identity) but only permutes its bits.
    EXPECT_NE(RotateCode(code, 1), code);
    EXPECT_EQ(HammingDistance(RotateCode(code, 1), PlaceCode{0, 0}), HammingDistance(code, PlaceCode{0, 0}));
  }
}

// The 128 bits are 32 groups of 4 (one random vector under the 4 quarter
// turns): a turn moves bit j of a group to bit j + k of the same group.
TEST(PlaceFeaturesTest, RotateCodeMovesEachBitWithinItsGroupOfFour) {
  for (int bit = 0; bit < 128; ++bit) {
    PlaceCode code{0, 0};
    code[bit / 64] = uint64_t{1} << (bit % 64);
    const int group = bit / 4, j = bit % 4;
    for (int k = 0; k < 4; ++k) {
      const int moved = 4 * group + (j + k) % 4;
      PlaceCode want{0, 0};
      want[moved / 64] = uint64_t{1} << (moved % 64);
      EXPECT_EQ(RotateCode(code, k), want) << "bit " << bit << " k " << k;
    }
  }
}

TEST(PlaceFeaturesTest, HammingDistanceCountsDifferingBits) {
  EXPECT_EQ(HammingDistance({0, 0}, {0, 0}), 0);
  EXPECT_EQ(HammingDistance({~uint64_t{0}, ~uint64_t{0}}, {0, 0}), 128);
  EXPECT_EQ(HammingDistance({0b1011, 0}, {0b0001, uint64_t{1} << 63}), 3);
}

TEST(PlaceFeaturesTest, TurnQuartersTurnsCounterClockwiseModuloFour) {
  const Point2 p{2.0, 0.5};
  for (int k = -5; k <= 9; ++k) {
    const double a = k * M_PI / 2;
    const Point2 q = TurnQuarters(p, k);
    EXPECT_NEAR(q.x, std::cos(a) * p.x - std::sin(a) * p.y, 1e-12) << k;
    EXPECT_NEAR(q.y, std::sin(a) * p.x + std::cos(a) * p.y, 1e-12) << k;
  }
  // Exact (no trigonometry): one quarter turn is (x, y) -> (-y, x).
  EXPECT_EQ(TurnQuarters(p, 1).x, -0.5);
  EXPECT_EQ(TurnQuarters(p, 1).y, 2.0);
}

// Turning a map's points by a quarter turn about its origin (heading kept)
// turns its compass frame by the same quarter turn: every interest point
// moves to its turned position and its code is RotateCode of the original.
// Not exactly for every feature: the turned points go through cos/sin of the
// heading again (last-bit differences), the cells and sectors are half open
// (a point on a boundary falls on the other side once turned), and the
// projection dot products are summed in another order (a bit whose dot
// product is ~0 may flip). Those touch few features and few bits.
TEST(PlaceFeaturesTest, TurningTheMapRotatesTheCodesOfTheTurnedFeatures) {
  PlaceFeatureOptions options;
  options.max_features = 0;  // thinning follows cell order, which a turn changes
  for (const LocalMap* map : {&RichMap(), &DemoMaps()[0], &DemoMaps()[100], &DemoMaps()[200]}) {
    const double heading = EstimateDominantOrientation(map->points);
    const PlaceFeatures original = DescribePlace(map->points, heading, options);
    ASSERT_GT(original.features.size(), 30u) << map->id;
    for (int k = 1; k < 4; ++k) {
      const PlaceFeatures turned = DescribePlace(Turned(map->points, k), heading, options);
      EXPECT_EQ(turned.heading, heading);
      EXPECT_EQ(turned.features.size(), original.features.size()) << map->id << " k " << k;
      size_t found = 0, equal = 0, close = 0;
      double unrotated_distance = 0.0;
      for (const PlaceFeature& f : original.features) {
        const int at = FeatureAt(turned, TurnQuarters({f.x, f.y}, k));
        if (at < 0) continue;
        ++found;
        const PlaceCode& code = turned.features[at].code;
        const int d = HammingDistance(code, RotateCode(f.code, k));
        equal += d == 0 ? 1 : 0;
        close += d <= 4 ? 1 : 0;
        unrotated_distance += HammingDistance(code, f.code);
      }
      const double n = static_cast<double>(original.features.size());
      EXPECT_GE(found, 0.95 * n) << map->id << " k " << k;
      EXPECT_GE(equal, 0.9 * n) << map->id << " k " << k;
      EXPECT_GE(close, 0.95 * n) << map->id << " k " << k;
      // The turn matters: the unturned code is far (random codes: 64 bits apart).
      EXPECT_GT(unrotated_distance / static_cast<double>(std::max<size_t>(found, 1)), 20.0) << map->id << " k " << k;
    }
  }
}

TEST(PlaceFeaturesTest, DescribingIsDeterministic) {
  const LocalMap& map = RichMap();
  const PlaceFeatures first = DescribePlace(map.points, 0.3);
  PlaceFeatureOptions other;
  other.shells = 6;  // another projection in between
  other.projection_seed = 7;
  const PlaceFeatures between = DescribePlace(map.points, 0.3, other);
  const PlaceFeatures again = DescribePlace(map.points, 0.3);
  EXPECT_TRUE(SameFeatures(first, again));
  EXPECT_FALSE(SameFeatures(first, between));  // the options do matter
}

TEST(PlaceFeaturesTest, NoPointsGiveNoFeatures) {
  const PlaceFeatures none = DescribePlace({}, 0.4);
  EXPECT_TRUE(none.features.empty());
  EXPECT_DOUBLE_EQ(none.heading, 0.4);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(DescribePlace({{nan, 1.0}, {1.0, inf}, {-inf, nan}}, 0.4).features.empty());
}

TEST(PlaceFeaturesTest, NonFinitePointsAreIgnored) {
  const LocalMap& map = RichMap();
  std::vector<Point2> noisy = map.points;
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  noisy.insert(noisy.begin() + 10, {nan, 0.0});
  noisy.push_back({1.0, inf});
  noisy.push_back({-inf, -inf});
  EXPECT_TRUE(SameFeatures(DescribePlace(noisy, 0.2), DescribePlace(map.points, 0.2)));
}

// One interest point per occupied interest cell of the compass frame, each a
// map point (turned into the compass frame): the point nearest the cell centre.
TEST(PlaceFeaturesTest, OneFeaturePerOccupiedCellAtAMapPoint) {
  const LocalMap& map = RichMap();
  const double heading = 0.25;
  PlaceFeatureOptions options;
  options.max_features = 0;
  const PlaceFeatures features = DescribePlace(map.points, heading, options);
  const double c = std::cos(-heading), s = std::sin(-heading), cell = options.interest_cell_m;
  std::set<std::pair<int64_t, int64_t>> occupied;
  std::vector<Point2> compass;
  for (const Point2& p : map.points) {
    compass.push_back({c * p.x - s * p.y, s * p.x + c * p.y});
    occupied.insert({static_cast<int64_t>(std::floor(compass.back().x / cell)),
                     static_cast<int64_t>(std::floor(compass.back().y / cell))});
  }
  EXPECT_EQ(features.features.size(), occupied.size());
  std::set<std::pair<int64_t, int64_t>> cells;
  for (const PlaceFeature& f : features.features) {
    const auto key = std::make_pair(static_cast<int64_t>(std::floor(f.x / cell)), static_cast<int64_t>(std::floor(f.y / cell)));
    EXPECT_TRUE(cells.insert(key).second) << "two features in cell " << key.first << " " << key.second;
    const Point2 centre{(key.first + 0.5) * cell, (key.second + 0.5) * cell};
    double nearest = 1e9, own = 1e9;
    for (const Point2& p : compass) {
      if (std::floor(p.x / cell) != key.first || std::floor(p.y / cell) != key.second) continue;
      nearest = std::min(nearest, std::hypot(p.x - centre.x, p.y - centre.y));
      own = std::min(own, std::hypot(p.x - f.x, p.y - f.y));
    }
    EXPECT_LT(own, 1e-5);  // a map point (float precision)
    EXPECT_NEAR(std::hypot(f.x - centre.x, f.y - centre.y), nearest, 1e-5);
  }
}

TEST(PlaceFeaturesTest, MaxFeaturesThinsTheInterestPointsEvenly) {
  const LocalMap& map = RichMap();
  PlaceFeatureOptions all;
  all.max_features = 0;
  const PlaceFeatures uncapped = DescribePlace(map.points, 0.1, all);
  ASSERT_GT(uncapped.features.size(), 100u);
  PlaceFeatureOptions capped = all;
  capped.max_features = 37;
  const PlaceFeatures thinned = DescribePlace(map.points, 0.1, capped);
  ASSERT_EQ(thinned.features.size(), 37u);
  // A subset of the uncapped features, code and all (descriptors read every
  // point), spread over the whole map: every n-th in cell order.
  std::vector<int> at;
  for (const PlaceFeature& f : thinned.features) {
    const int i = FeatureAt(uncapped, {f.x, f.y});
    ASSERT_GE(i, 0);
    EXPECT_EQ(uncapped.features[i].code, f.code);
    at.push_back(i);
  }
  EXPECT_TRUE(std::is_sorted(at.begin(), at.end()));
  const double stride = static_cast<double>(uncapped.features.size()) / 37.0;
  for (size_t i = 1; i < at.size(); ++i) EXPECT_NEAR(at[i] - at[i - 1], stride, 1.0);
  // A cap above the count changes nothing.
  capped.max_features = uncapped.features.size();
  EXPECT_TRUE(SameFeatures(DescribePlace(map.points, 0.1, capped), uncapped));
  // The default caps at 400.
  EXPECT_LE(DescribePlace(map.points, 0.1).features.size(), 400u);
}

// The code describes each interest point's neighbourhood: the features of
// one map are mostly told apart by their codes.
TEST(PlaceFeaturesTest, FeaturesOfOnePlaceHaveDifferentCodes) {
  const PlaceFeatures features = DescribePlace(RichMap().points, 0.0);
  std::set<PlaceCode> codes;
  for (const PlaceFeature& f : features.features) codes.insert(f.code);
  EXPECT_GT(codes.size(), features.features.size() / 2);
}

// ---------------------------------------------------------------------------
// Binary form.

PlaceFeatures SampleFeatures(size_t n) {
  std::mt19937_64 rng(9);
  PlaceFeatures f;
  f.heading = 0.7;
  for (size_t i = 0; i < n; ++i) {
    PlaceFeature pf;
    pf.x = static_cast<float>(static_cast<int>(rng() % 2000) - 1000) * 0.013f;
    pf.y = static_cast<float>(static_cast<int>(rng() % 2000) - 1000) * 0.017f;
    pf.code = RandomCode(rng);
    f.features.push_back(pf);
  }
  return f;
}

// Overwrites the float32 at byte `offset` (little-endian) with `value`.
void PutFloatAt(std::string* bytes, size_t offset, float value) {
  uint32_t v;
  std::memcpy(&v, &value, 4);
  for (int i = 0; i < 4; ++i) (*bytes)[offset + i] = static_cast<char>((v >> (8 * i)) & 0xff);
}

TEST(PlaceFeaturesTest, EncodeDecodeRoundTripsEveryField) {
  const PlaceFeatures features = SampleFeatures(20);
  const std::string bytes = EncodePlaceFeatures(features);
  EXPECT_EQ(bytes.size(), 1u + 1u + 4u + 24u * 20u);  // version, varint 20, heading, features
  EXPECT_EQ(static_cast<uint8_t>(bytes[0]), kPlaceFeatureVersion);
  const Result<PlaceFeatures> back = DecodePlaceFeatures(bytes);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->heading, static_cast<double>(static_cast<float>(features.heading)));  // float32 on disk
  ASSERT_EQ(back->features.size(), features.features.size());
  for (size_t i = 0; i < features.features.size(); ++i) {
    EXPECT_EQ(back->features[i].x, features.features[i].x);
    EXPECT_EQ(back->features[i].y, features.features[i].y);
    EXPECT_EQ(back->features[i].code, features.features[i].code);
  }
  EXPECT_EQ(EncodePlaceFeatures(*back), bytes);
}

TEST(PlaceFeaturesTest, EncodeDecodeRoundTripsNoFeaturesAndLongCounts) {
  const Result<PlaceFeatures> none = DecodePlaceFeatures(EncodePlaceFeatures(SampleFeatures(0)));
  ASSERT_TRUE(none.ok()) << none.status().ToString();
  EXPECT_TRUE(none->features.empty());
  EXPECT_FLOAT_EQ(static_cast<float>(none->heading), 0.7f);
  // 300 features: a two-byte varint count.
  const std::string bytes = EncodePlaceFeatures(SampleFeatures(300));
  EXPECT_EQ(bytes.size(), 1u + 2u + 4u + 24u * 300u);
  const Result<PlaceFeatures> many = DecodePlaceFeatures(bytes);
  ASSERT_TRUE(many.ok()) << many.status().ToString();
  EXPECT_EQ(many->features.size(), 300u);
}

TEST(PlaceFeaturesTest, DecodeRefusesEmptyAndOtherVersions) {
  const Result<PlaceFeatures> empty = DecodePlaceFeatures("");
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.status().code(), Status::Code::kCorruption);
  std::string bytes = EncodePlaceFeatures(SampleFeatures(3));
  for (uint8_t version : {uint8_t{0}, static_cast<uint8_t>(kPlaceFeatureVersion + 1), uint8_t{255}}) {
    bytes[0] = static_cast<char>(version);
    const Result<PlaceFeatures> other = DecodePlaceFeatures(bytes);
    ASSERT_FALSE(other.ok()) << int{version};
    EXPECT_EQ(other.status().code(), Status::Code::kCorruption);
  }
}

TEST(PlaceFeaturesTest, DecodeRefusesEveryTruncationAndTrailingBytes) {
  const std::string bytes = EncodePlaceFeatures(SampleFeatures(3));
  for (size_t n = 0; n < bytes.size(); ++n) {
    const Result<PlaceFeatures> cut = DecodePlaceFeatures(bytes.substr(0, n));
    ASSERT_FALSE(cut.ok()) << n << " of " << bytes.size() << " bytes";
    EXPECT_EQ(cut.status().code(), Status::Code::kCorruption);
  }
  for (const std::string& tail : {std::string(1, '\0'), std::string(23, 'x'), std::string(24, '\0')}) {
    const Result<PlaceFeatures> longer = DecodePlaceFeatures(bytes + tail);
    ASSERT_FALSE(longer.ok()) << tail.size() << " trailing bytes";
    EXPECT_EQ(longer.status().code(), Status::Code::kCorruption);
  }
}

TEST(PlaceFeaturesTest, DecodeRefusesACountThatDisagreesWithTheBytes) {
  std::string bytes = EncodePlaceFeatures(SampleFeatures(3));
  ASSERT_EQ(bytes[1], 3);  // the one-byte varint count
  for (char count : {char{0}, char{2}, char{4}, char{127}}) {
    bytes[1] = count;
    const Result<PlaceFeatures> wrong = DecodePlaceFeatures(bytes);
    ASSERT_FALSE(wrong.ok()) << int{count};
    EXPECT_EQ(wrong.status().code(), Status::Code::kCorruption);
  }
  // A count near 2^63 (a nine-byte varint): refused before anything is allocated.
  std::string huge(1, static_cast<char>(kPlaceFeatureVersion));
  huge += std::string(8, static_cast<char>(0xff)) + std::string(1, 0x7f);
  huge += std::string(4 + 24, '\0');
  const Result<PlaceFeatures> refused = DecodePlaceFeatures(huge);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), Status::Code::kCorruption);
  // A varint that never ends.
  const Result<PlaceFeatures> endless =
      DecodePlaceFeatures(std::string(1, static_cast<char>(kPlaceFeatureVersion)) + std::string(20, static_cast<char>(0x80)));
  EXPECT_FALSE(endless.ok());
}

TEST(PlaceFeaturesTest, DecodeRefusesNonFiniteHeadingsAndPositions) {
  const std::string bytes = EncodePlaceFeatures(SampleFeatures(3));
  const size_t heading_at = 2, first_feature_at = 6;
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    std::string heading = bytes;
    PutFloatAt(&heading, heading_at, bad);
    const Result<PlaceFeatures> h = DecodePlaceFeatures(heading);
    ASSERT_FALSE(h.ok());
    EXPECT_EQ(h.status().code(), Status::Code::kCorruption);
    for (size_t field : {size_t{0}, size_t{4}}) {  // x, y of the last feature
      std::string position = bytes;
      PutFloatAt(&position, first_feature_at + 2 * 24 + field, bad);
      const Result<PlaceFeatures> p = DecodePlaceFeatures(position);
      ASSERT_FALSE(p.ok()) << field;
      EXPECT_EQ(p.status().code(), Status::Code::kCorruption);
    }
  }
  // The same offsets with finite values decode: the test writes where the fields are.
  std::string fine = bytes;
  PutFloatAt(&fine, heading_at, 0.5f);
  PutFloatAt(&fine, first_feature_at + 2 * 24, -3.25f);
  const Result<PlaceFeatures> decoded = DecodePlaceFeatures(fine);
  ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
  EXPECT_EQ(decoded->heading, 0.5);
  EXPECT_EQ(decoded->features[2].x, -3.25f);
}

// Corrupted records (bytes overwritten, cut short): Decode refuses them or
// returns finite values that the record's bytes account for, and never crashes.
TEST(PlaceFeaturesTest, DecodeOfCorruptedBytesNeverCrashes) {
  std::mt19937_64 rng(4);
  const std::string valid = EncodePlaceFeatures(SampleFeatures(4));
  int refused = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::string bytes = valid;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) bytes[rng() % bytes.size()] = static_cast<char>(rng() & 0xff);
    if (rng() % 3 == 0) bytes.resize(rng() % (bytes.size() + 1));
    const Result<PlaceFeatures> decoded = DecodePlaceFeatures(bytes);
    if (!decoded.ok()) {
      ++refused;
      continue;
    }
    EXPECT_TRUE(std::isfinite(decoded->heading));
    EXPECT_LE(1 + 1 + 4 + 24 * decoded->features.size(), bytes.size());
    for (const PlaceFeature& f : decoded->features) EXPECT_TRUE(std::isfinite(f.x) && std::isfinite(f.y));
  }
  EXPECT_GT(refused, 0);
}

}  // namespace
}  // namespace lmd
