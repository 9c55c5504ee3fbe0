#include "server/descriptor_cache.h"

#include <gtest/gtest.h>

namespace lmd::server {
namespace {

std::shared_ptr<const DescribedMap> WithFeatures(size_t n) {
  auto described = std::make_shared<DescribedMap>();
  described->lmd.emplace().features.resize(n);
  return described;
}

TEST(DescriptorCacheTest, FindsWhatWasPutByContent) {
  DescriptorCache cache(4);
  const auto key = DescriptorCache::KeyOf("map bytes 1");
  cache.Put(key, WithFeatures(7));
  ASSERT_NE(cache.Find(DescriptorCache::KeyOf("map bytes 1")), nullptr);
  EXPECT_EQ(cache.Find(key)->lmd->features.size(), 7u);
  EXPECT_EQ(cache.Find(DescriptorCache::KeyOf("map bytes 2")), nullptr);
}

TEST(DescriptorCacheTest, DropsTheLeastRecentlyUsedBeyondCapacity) {
  DescriptorCache cache(2);
  cache.Put(DescriptorCache::KeyOf("a"), WithFeatures(1));
  cache.Put(DescriptorCache::KeyOf("b"), WithFeatures(2));
  ASSERT_NE(cache.Find(DescriptorCache::KeyOf("a")), nullptr);  // a is now the most recent
  cache.Put(DescriptorCache::KeyOf("c"), WithFeatures(3));
  EXPECT_NE(cache.Find(DescriptorCache::KeyOf("a")), nullptr);
  EXPECT_EQ(cache.Find(DescriptorCache::KeyOf("b")), nullptr);
  EXPECT_NE(cache.Find(DescriptorCache::KeyOf("c")), nullptr);
}

TEST(DescriptorCacheTest, AnEntryWithTheDescriptorReplacesOneWithout) {
  DescriptorCache cache(2);
  const auto key = DescriptorCache::KeyOf("queried, then stored");
  cache.Put(key, std::make_shared<DescribedMap>());  // a query's: no descriptor
  ASSERT_FALSE(cache.Find(key)->lmd);
  cache.Put(key, WithFeatures(5));
  ASSERT_TRUE(cache.Find(key)->lmd);
  EXPECT_EQ(cache.Find(key)->lmd->features.size(), 5u);
  cache.Put(key, std::make_shared<DescribedMap>());  // a later query's does not undo it
  EXPECT_TRUE(cache.Find(key)->lmd);
}

TEST(DescriptorCacheTest, ZeroCapacityKeepsNothing) {
  DescriptorCache cache(0);
  cache.Put(DescriptorCache::KeyOf("a"), WithFeatures(1));
  EXPECT_EQ(cache.Find(DescriptorCache::KeyOf("a")), nullptr);
}

}  // namespace
}  // namespace lmd::server
