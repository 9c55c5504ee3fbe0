#include "server/config.h"

#include <fstream>

#include <gtest/gtest.h>

#include "server/indexing.h"
#include "tests/server/test_server.h"

namespace lmd::server {
namespace {

TEST(ConfigTest, FileSetsFieldsAndIgnoresComments) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/lmdd.conf";
  std::ofstream(path) << "# lmdd\nlisten = 127.0.0.1:6000\nmax_top_k = 50  # small\nsync_writes = true\n"
                      << "verify_candidates = 12\nprepared_map_cache_mb = 32\n"
                      << "busy_queued_calls = 4\nbusy_verify_candidates = 2\nbusy_search_candidates = 5000\n"
                      << "retain_maps_per_collection = 5000\n";
  ServerConfig config;
  ASSERT_TRUE(LoadConfigFile(path, &config).ok());
  EXPECT_EQ(config.listen, "127.0.0.1:6000");
  EXPECT_EQ(config.max_top_k, 50u);
  EXPECT_TRUE(config.sync_writes);
  EXPECT_EQ(config.verify_candidates, 12u);
  EXPECT_EQ(config.prepared_map_cache_mb, 32u);
  EXPECT_EQ(config.busy_queued_calls, 4u);
  EXPECT_EQ(config.busy_verify_candidates, 2u);
  EXPECT_EQ(config.busy_search_candidates, 5000u);
  EXPECT_EQ(config.retain_maps_per_collection, 5000u);
}

TEST(ConfigTest, UnknownKeyAndBadValueNameFileAndLine) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/lmdd.conf";
  std::ofstream(path) << "max_top_k = 5\nmax_top_kk = 5\n";
  ServerConfig config;
  Status status = LoadConfigFile(path, &config);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(status.message().find("lmdd.conf:2"), std::string::npos) << status.message();

  EXPECT_FALSE(SetConfigValue("max_top_k", "-3", &config).ok());
  EXPECT_FALSE(SetConfigValue("max_top_k", "ten", &config).ok());
  EXPECT_FALSE(SetConfigValue("sync_writes", "maybe", &config).ok());
  EXPECT_NE(SetConfigValue("prepared_map_cache_entries", "500", &config).message().find("prepared_map_cache_mb"),
            std::string::npos);
  // Settings of the old default method say they are gone (a config file naming them is refused).
  EXPECT_NE(SetConfigValue("max_maps_scored", "150", &config).message().find("removed"), std::string::npos);
  // A limit of 0 would refuse every request.
  EXPECT_FALSE(SetConfigValue("max_top_k", "0", &config).ok());
  EXPECT_FALSE(SetConfigValue("max_message_bytes", "0", &config).ok());
  EXPECT_FALSE(SetConfigValue("max_map_extent_m", "2000", &config).ok());  // beyond the pose words' reach
  EXPECT_EQ(LoadConfigFile(dir.path() + "/absent.conf", &config).code(), Status::Code::kIoError);
}

// Values that would crash lmdd (a thread per worker), make it refuse every
// call, or wrap around in a deadline are refused, naming the key and range.
TEST(ConfigTest, AbsurdConcurrencySettingsAreRefusedWithTheirRange) {
  ServerConfig config;
  Status status = SetConfigValue("worker_threads", "100000", &config);
  EXPECT_EQ(status.message(), "worker_threads must be a whole number from 0 to 1024, got '100000'");
  EXPECT_TRUE(SetConfigValue("worker_threads", "1024", &config).ok());
  EXPECT_EQ(config.worker_threads, 1024u);
  status = SetConfigValue("max_queued_calls", "0", &config);
  EXPECT_NE(status.message().find("max_queued_calls must be a whole number from 1 to"), std::string::npos)
      << status.message();
  status = SetConfigValue("cluster_replicate_timeout_ms", "3000000000", &config);
  EXPECT_EQ(status.message(), "cluster_replicate_timeout_ms must be a whole number from 1 to 60000, got '3000000000'");
}

TEST(ConfigTest, InnerWordsChooseTheStoresDescriptor) {
  ServerConfig config;
  EXPECT_FALSE(config.inner_words);
  ASSERT_TRUE(SetConfigValue("inner_words", "true", &config).ok());
  EXPECT_TRUE(config.inner_words);
  EXPECT_FALSE(SetConfigValue("inner_words", "sometimes", &config).ok());
  const IndexingConfig with = ProductIndexing(true), without = ProductIndexing(false);
  EXPECT_GT(with.describer.inner_radius_m, 0.0);
  EXPECT_EQ(without.describer.inner_radius_m, 0.0);
  EXPECT_EQ(without.describer.max_features, ProductDescriberOptions().max_features);
  EXPECT_EQ(with.describer.max_features, 64);
  // A store made with one is refused by an lmdd set to the other.
  EXPECT_NE(Fingerprint(with), Fingerprint(without));
  // Stores made before inner words existed carry this line: they still open.
  EXPECT_EQ(Fingerprint(without),
            "planner=cog projection_version=2 projection_seed=30519575635455850 R=6 A=6 shells=10 bits=13 "
            "raster=0.01 interest_cell=0.5 max_features=80 codec=1 pose_quantum=0.05 W=5 L=2");
}

TEST(ConfigTest, PaperIndexIsOnUnlessSetOff) {
  ServerConfig config;
  EXPECT_TRUE(config.paper_index);
  ASSERT_TRUE(SetConfigValue("paper_index", "false", &config).ok());
  EXPECT_FALSE(config.paper_index);
  EXPECT_FALSE(SetConfigValue("paper_index", "no thanks", &config).ok());
  EXPECT_TRUE(ProductIndexing(false).paper_index);
  const IndexingConfig off = ProductIndexing(false, false);
  EXPECT_FALSE(off.paper_index);
  // A store made without the index is refused by an lmdd that keeps one, and
  // the other way round; without it the describer's settings (inner words)
  // change nothing stored.
  EXPECT_NE(Fingerprint(off), Fingerprint(ProductIndexing(false)));
  EXPECT_EQ(Fingerprint(off), Fingerprint(ProductIndexing(true, false)));
}

TEST(ConfigTest, LoopbackAddressesAreRecognised) {
  EXPECT_TRUE(IsLoopbackAddress("127.0.0.1:50051"));
  EXPECT_TRUE(IsLoopbackAddress("localhost:1"));
  EXPECT_TRUE(IsLoopbackAddress("[::1]:50051"));
  EXPECT_FALSE(IsLoopbackAddress("0.0.0.0:50051"));
  EXPECT_FALSE(IsLoopbackAddress("10.1.2.3:50051"));
}

}  // namespace
}  // namespace lmd::server
