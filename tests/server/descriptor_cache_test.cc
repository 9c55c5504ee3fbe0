#include "server/descriptor_cache.h"

#include <gtest/gtest.h>

namespace lmd::server {
namespace {

Lmd WithFeatures(size_t n) {
  Lmd lmd;
  lmd.features.resize(n);
  return lmd;
}

TEST(DescriptorCacheTest, FindsWhatWasPutByContent) {
  DescriptorCache cache(4);
  const auto key = DescriptorCache::KeyOf("map bytes 1");
  cache.Put(key, WithFeatures(7));
  ASSERT_TRUE(cache.Find(DescriptorCache::KeyOf("map bytes 1")).has_value());
  EXPECT_EQ(cache.Find(key)->features.size(), 7u);
  EXPECT_FALSE(cache.Find(DescriptorCache::KeyOf("map bytes 2")).has_value());
}

TEST(DescriptorCacheTest, DropsTheLeastRecentlyUsedBeyondCapacity) {
  DescriptorCache cache(2);
  cache.Put(DescriptorCache::KeyOf("a"), WithFeatures(1));
  cache.Put(DescriptorCache::KeyOf("b"), WithFeatures(2));
  ASSERT_TRUE(cache.Find(DescriptorCache::KeyOf("a")).has_value());  // a is now the most recent
  cache.Put(DescriptorCache::KeyOf("c"), WithFeatures(3));
  EXPECT_TRUE(cache.Find(DescriptorCache::KeyOf("a")).has_value());
  EXPECT_FALSE(cache.Find(DescriptorCache::KeyOf("b")).has_value());
  EXPECT_TRUE(cache.Find(DescriptorCache::KeyOf("c")).has_value());
}

TEST(DescriptorCacheTest, ZeroCapacityKeepsNothing) {
  DescriptorCache cache(0);
  cache.Put(DescriptorCache::KeyOf("a"), WithFeatures(1));
  EXPECT_FALSE(cache.Find(DescriptorCache::KeyOf("a")).has_value());
}

}  // namespace
}  // namespace lmd::server
