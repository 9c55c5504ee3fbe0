#include "core/describe/lmd_codec.h"

#include <random>

#include <gtest/gtest.h>

namespace lmd {
namespace {

Lmd Sample() {
  Lmd lmd;
  lmd.frame = {{1.25, -3.5}, 0.3};
  std::mt19937_64 rng(3);
  for (int i = 0; i < 50; ++i) {
    Feature f;
    f.appearance_word = static_cast<uint32_t>(rng() & 1023);
    f.x = static_cast<float>(static_cast<int>(rng() % 4000) - 2000) * 0.01f;
    f.y = static_cast<float>(static_cast<int>(rng() % 4000) - 2000) * 0.01f;
    f.change_word = rng() & ((uint64_t{1} << 60) - 1);
    lmd.features.push_back(f);
  }
  return lmd;
}

TEST(LmdCodecTest, RoundTripKeepsFrameWordsAndQuantisedPositions) {
  const Lmd lmd = Sample();
  const std::string bytes = EncodeLmd(lmd);
  EXPECT_EQ(bytes.size(), 1 + 1 + 12 + 14 * lmd.features.size());
  const Result<Lmd> back = DecodeLmd(bytes);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_FLOAT_EQ(static_cast<float>(back->frame.origin.x), 1.25f);
  EXPECT_FLOAT_EQ(static_cast<float>(back->frame.heading), 0.3f);
  ASSERT_EQ(back->features.size(), lmd.features.size());
  for (size_t i = 0; i < lmd.features.size(); ++i) {
    EXPECT_EQ(back->features[i].appearance_word, lmd.features[i].appearance_word);
    EXPECT_EQ(back->features[i].change_word, lmd.features[i].change_word);
    EXPECT_NEAR(back->features[i].x, lmd.features[i].x, kLmdPositionQuantumM / 2 + 1e-5);
    EXPECT_NEAR(back->features[i].y, lmd.features[i].y, kLmdPositionQuantumM / 2 + 1e-5);
  }
  EXPECT_EQ(EncodeLmd(*back), bytes);  // stable once quantised
}

TEST(LmdCodecTest, InnerWordsRoundTripInVersionTwo) {
  Lmd lmd = Sample();
  for (size_t i = 0; i < lmd.features.size(); ++i) {
    if (i % 5 != 0) lmd.features[i].inner_word = static_cast<uint32_t>((i * 977) & 0x7fff);  // every 5th: none
  }
  const std::string bytes = EncodeLmd(lmd);
  EXPECT_EQ(bytes[0], 2);
  EXPECT_EQ(bytes.size(), 1 + 1 + 12 + 16 * lmd.features.size());
  const Result<Lmd> back = DecodeLmd(bytes);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->features.size(), lmd.features.size());
  for (size_t i = 0; i < lmd.features.size(); ++i) {
    EXPECT_EQ(back->features[i].inner_word, lmd.features[i].inner_word) << i;
    EXPECT_EQ(back->features[i].appearance_word, lmd.features[i].appearance_word) << i;
    EXPECT_EQ(back->features[i].change_word, lmd.features[i].change_word) << i;
  }
  EXPECT_EQ(EncodeLmd(*back), bytes);
  // Without inner words the record stays version 1 and decodes to "none".
  const std::string v1 = EncodeLmd(Sample());
  EXPECT_EQ(v1[0], 1);
  EXPECT_EQ(DecodeLmd(v1)->features[0].inner_word, kNoWord);
}

TEST(LmdCodecTest, EmptyDescriptorRoundTrips) {
  const Result<Lmd> back = DecodeLmd(EncodeLmd(Lmd{}));
  ASSERT_TRUE(back.ok());
  EXPECT_TRUE(back->features.empty());
}

TEST(LmdCodecTest, RejectsTruncationTrailingBytesAndWrongVersion) {
  const std::string bytes = EncodeLmd(Sample());
  for (size_t n = 0; n < bytes.size(); ++n) {
    EXPECT_EQ(DecodeLmd(bytes.substr(0, n)).status().code(), Status::Code::kCorruption) << n;
  }
  EXPECT_EQ(DecodeLmd(bytes + "x").status().code(), Status::Code::kCorruption);
  std::string v2 = bytes;  // version 1 bytes read as version 2: 16 bytes per feature
  v2[0] = 2;
  EXPECT_EQ(DecodeLmd(v2).status().code(), Status::Code::kCorruption);
  std::string v3 = bytes;
  v3[0] = 3;
  EXPECT_EQ(DecodeLmd(v3).status().code(), Status::Code::kCorruption);
  std::string huge = bytes.substr(0, 1) + std::string("\xff\xff\xff\xff\xff\xff\xff\xff\x7f", 9) + bytes.substr(2);
  EXPECT_EQ(DecodeLmd(huge).status().code(), Status::Code::kCorruption);
}

TEST(LmdCodecTest, RandomBytesNeverCrashTheDecoder) {
  std::mt19937_64 rng(11);
  const std::string valid = EncodeLmd(Sample());
  size_t ok = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string s;
    if (i % 2 == 0) {  // pure garbage
      s.resize(rng() % 64);
      for (char& c : s) c = static_cast<char>(rng());
      if (!s.empty() && i % 4 == 0) s[0] = static_cast<char>(kLmdCodecVersion);
    } else {  // a valid record with a few bytes flipped
      s = valid;
      for (int k = 0; k < 3; ++k) s[rng() % s.size()] = static_cast<char>(rng());
    }
    const Result<Lmd> r = DecodeLmd(s);
    if (r.ok()) {
      ++ok;
      EXPECT_EQ(EncodeLmd(*r).size(), s.size());
    } else {
      EXPECT_EQ(r.status().code(), Status::Code::kCorruption);
    }
  }
  EXPECT_LT(ok, 20000u);
}

}  // namespace
}  // namespace lmd
