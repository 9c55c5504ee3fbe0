// Observability: Stats reports calls, errors and latencies per method, and
// /metrics serves them in Prometheus text format.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "server/metrics.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

// GET `path` from 127.0.0.1:port with a raw HTTP/1.0 request; the whole reply.
std::string HttpGet(int port, const std::string& path) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  inet_pton(AF_INET, "127.0.0.1", &address.sin_addr);
  std::string reply;
  if (connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0) {
    const std::string request = "GET " + path + " HTTP/1.0\r\nHost: localhost\r\n\r\n";
    if (write(fd, request.data(), request.size()) == static_cast<ssize_t>(request.size())) {
      char buffer[4096];
      for (ssize_t n; (n = read(fd, buffer, sizeof(buffer))) > 0;) reply.append(buffer, static_cast<size_t>(n));
    }
  }
  close(fd);
  return reply;
}

TEST(MetricsTest, StatsCountCallsAndErrorsPerMethod) {
  TempDir dir;
  TestServer server(dir.path());
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &inserted).ok());
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("missing");
  v1::GetMapResponse got;
  EXPECT_FALSE(server.client().GetMap(get, &got).ok());
  v1::StatsResponse stats;
  ASSERT_TRUE(server.client().Stats(v1::StatsRequest(), &stats).ok());
  std::map<std::string, v1::MethodStats> by_name;
  for (const auto& method : stats.methods()) by_name[method.method()] = method;
  ASSERT_EQ(by_name.count("InsertMaps"), 1u);
  EXPECT_EQ(by_name["InsertMaps"].calls(), 1u);
  EXPECT_EQ(by_name["InsertMaps"].errors(), 0u);
  EXPECT_GT(by_name["InsertMaps"].p50_ms(), 0.0);
  EXPECT_EQ(by_name["GetMap"].errors(), 1u);
  ASSERT_EQ(stats.collections_size(), 1);
  EXPECT_EQ(stats.collections(0).maps(), 1u);
}

// An lmdd on loopback with its /metrics endpoint, and a client.
class PrometheusTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server::ServerConfig config;
    config.metrics_listen = "127.0.0.1:0";
    config.listen = "127.0.0.1:0";
    config.data_dir = dir_.path();
    auto server = server::LmdServer::Start(config);
    ASSERT_TRUE(server.ok()) << server.status().ToString();
    server_ = std::move(server).value();
    ASSERT_GT(server_->metrics_port(), 0);
    client::ClientOptions options;
    options.target = "127.0.0.1:" + std::to_string(server_->port());
    client_ = std::move(client::LmdClient::Create(options)).value();
  }

  std::string Page(const std::string& path = "/metrics") { return HttpGet(server_->metrics_port(), path); }

  TempDir dir_;
  std::unique_ptr<server::LmdServer> server_;
  std::unique_ptr<client::LmdClient> client_;
};

TEST_F(PrometheusTest, EndpointServesCallsAndCollections) {
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(client_->InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &inserted).ok());

  const std::string page = Page();
  EXPECT_NE(page.find("200 OK"), std::string::npos) << page;
  EXPECT_NE(page.find("lmd_calls_total{method=\"InsertMaps\",code=\"OK\"} 1"), std::string::npos) << page;
  EXPECT_NE(page.find("lmd_collection_maps{collection=\"site\"} 1"), std::string::npos) << page;
  EXPECT_NE(page.find("lmd_call_duration_seconds_count{method=\"InsertMaps\"} 1"), std::string::npos) << page;
  EXPECT_NE(Page("/other").find("404"), std::string::npos);
}

// The counter's value in a Prometheus page, or -1 if it is absent.
long CounterValue(const std::string& page, const std::string& name) {
  const size_t at = page.find("\n" + name + " ");
  return at == std::string::npos ? -1 : std::stol(page.substr(at + name.size() + 2));
}

TEST_F(PrometheusTest, CountsTheWorkOfQueries) {
  v1::InsertMapsRequest insert;
  for (const char* id : {"a", "b", "c"}) *insert.add_maps() = OneMapRequest("site", id, SquareRoomMap()).maps(0);
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(client_->InsertMaps(insert, &inserted).ok());
  EXPECT_EQ(CounterValue(Page(), "lmd_queries_total"), 0);

  v1::RetrieveRequest query;
  query.set_collection("site");
  *query.mutable_map() = SquareRoomMap();
  query.set_verify_candidates(2);
  v1::RetrieveResponse response;
  ASSERT_TRUE(client_->Retrieve(query, &response).ok());
  ASSERT_TRUE(client_->Retrieve(query, &response).ok());
  const std::string page = Page();
  EXPECT_EQ(CounterValue(page, "lmd_queries_total"), 2) << page;
  EXPECT_GT(CounterValue(page, "lmd_query_features_compared_total"), 0) << page;
  EXPECT_EQ(CounterValue(page, "lmd_query_maps_matched_total"), 4) << page;  // two per query
  // The maps were prepared when they were inserted: no hit had to be prepared again.
  EXPECT_EQ(CounterValue(page, "lmd_maps_prepared_total"), 0) << page;
  EXPECT_GT(CounterValue(page, "lmd_prepared_cache_bytes"), 0) << page;
  EXPECT_GT(CounterValue(page, "process_cpu_seconds_total"), -1) << page;
  // Both answered globally, with the verdict the robot got.
  const std::string verdict = response.localization().localized() ? "sure" : "unsure";
  EXPECT_EQ(CounterValue(page, "lmd_answers_total{asked=\"global\",verdict=\"" + verdict + "\"}"), 2) << page;
  EXPECT_EQ(CounterValue(page, "lmd_priors_failed_total"), 0) << page;
}

// Answers are counted by what the robot asked and the verdict; a prior that
// matched nothing counts as failed, also when a global query answered.
TEST(MetricsTest, AnswersAreCountedByWhatWasAskedAndTheVerdict) {
  server::CallMetrics metrics;
  Verdict sure_global;
  sure_global.sure = true;
  Verdict unsure_prior;
  unsure_prior.prior_used = true;
  Verdict fell_back = unsure_prior;
  fell_back.prior_failed = fell_back.fell_back_to_global = true;
  fell_back.sure = true;
  Verdict sequence;
  sequence.sequence_maps = 2;
  for (const Verdict* v : {&sure_global, &sure_global, &unsure_prior, &fell_back, &sequence}) metrics.RecordAnswer(*v);
  const std::string page = metrics.PrometheusText({}, 1.0, {}, 0.0);
  EXPECT_EQ(CounterValue(page, "lmd_answers_total{asked=\"global\",verdict=\"sure\"}"), 2) << page;
  EXPECT_EQ(CounterValue(page, "lmd_answers_total{asked=\"prior\",verdict=\"unsure\"}"), 1) << page;
  EXPECT_EQ(CounterValue(page, "lmd_answers_total{asked=\"prior\",verdict=\"sure\"}"), 1) << page;
  EXPECT_EQ(CounterValue(page, "lmd_answers_total{asked=\"sequence\",verdict=\"unsure\"}"), 1) << page;
  EXPECT_EQ(CounterValue(page, "lmd_answers_total{asked=\"global\",verdict=\"unsure\"}"), -1) << page;
  EXPECT_EQ(CounterValue(page, "lmd_priors_failed_total"), 1) << page;
}

}  // namespace
}  // namespace lmd::testing
