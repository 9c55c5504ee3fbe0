// Tokens and TLS: every call checked, the right status for each failure.
#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>

#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

class TokenTest : public ::testing::Test {
 protected:
  void SetUp() override {
    tokens_ = dir_.path() + "/tokens";
    std::ofstream(tokens_) << "# token collection right\n"
                              "writer-secret site write\n"
                              "reader-secret site read\n"
                              "admin-secret * write\n";
    config_.tokens_file = tokens_;
    server_ = std::make_unique<TestServer>(data_.path(), config_);
  }

  std::unique_ptr<client::LmdClient> ClientWith(const std::string& token) {
    client::ClientOptions options;
    options.target = server_->address();
    options.token = token;
    return std::move(client::LmdClient::Create(options)).value();
  }

  TempDir dir_;
  TempDir data_;
  std::string tokens_;
  server::ServerConfig config_;
  std::unique_ptr<TestServer> server_;
};

TEST_F(TokenTest, MissingOrUnknownTokenIsUnauthenticated) {
  v1::InsertMapsResponse ignored;
  grpc::Status status = ClientWith("")->InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &ignored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  status = ClientWith("guess")->InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &ignored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  v1::ListCollectionsResponse collections;
  EXPECT_EQ(ClientWith("")->ListCollections(&collections).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(TokenTest, ReadTokenCannotWriteButCanRead) {
  v1::InsertMapsResponse ignored;
  ASSERT_TRUE(ClientWith("writer-secret")->InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &ignored).ok());
  const grpc::Status denied =
      ClientWith("reader-secret")->InsertMaps(OneMapRequest("site", "b", SquareRoomMap()), &ignored);
  EXPECT_EQ(denied.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(denied.error_message().find("may not write"), std::string::npos);
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("a");
  v1::GetMapResponse got;
  EXPECT_TRUE(ClientWith("reader-secret")->GetMap(get, &got).ok());
  v1::DeleteMapRequest del;
  del.set_collection("site");
  del.set_map_id("a");
  EXPECT_EQ(ClientWith("reader-secret")->DeleteMap(del).error_code(), grpc::StatusCode::PERMISSION_DENIED);
}

TEST_F(TokenTest, TokenIsConfinedToItsCollections) {
  v1::InsertMapsResponse ignored;
  ASSERT_TRUE(ClientWith("admin-secret")->InsertMaps(OneMapRequest("other", "x", SquareRoomMap()), &ignored).ok());
  ASSERT_TRUE(ClientWith("admin-secret")->InsertMaps(OneMapRequest("site", "y", SquareRoomMap()), &ignored).ok());
  EXPECT_EQ(ClientWith("writer-secret")->InsertMaps(OneMapRequest("other", "z", SquareRoomMap()), &ignored).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(ClientWith("reader-secret")->ListCollections(&collections).ok());
  ASSERT_EQ(collections.collections_size(), 1);
  EXPECT_EQ(collections.collections(0).name(), "site");
  v1::BackupRequest backup;
  backup.set_directory(dir_.path() + "/backup");
  v1::BackupResponse backed_up;
  EXPECT_EQ(ClientWith("writer-secret")->Backup(backup, &backed_up).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(ClientWith("admin-secret")->Backup(backup, &backed_up).ok());
}

TEST_F(TokenTest, ABadCollectionNameIsInvalidEvenWithTokens) {
  v1::InsertMapsResponse ignored;
  grpc::Status status = ClientWith("writer-secret")->InsertMaps(OneMapRequest("", "a", SquareRoomMap()), &ignored);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("collection is empty"), std::string::npos) << status.error_message();
  v1::StatsRequest stats;
  stats.set_collection("bad/name");
  v1::StatsResponse got;
  EXPECT_EQ(ClientWith("admin-secret")->Stats(stats, &got).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  // A missing token still comes first.
  EXPECT_EQ(ClientWith("")->Stats(stats, &got).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST(TokensFileTest, MalformedFileStopsTheServerFromStarting) {
  TempDir dir;
  std::ofstream(dir.path() + "/tokens") << "only-a-token\n";
  server::ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.data_dir = dir.path() + "/data";
  config.tokens_file = dir.path() + "/tokens";
  auto started = server::LmdServer::Start(config);
  ASSERT_FALSE(started.ok());
  EXPECT_NE(started.status().message().find("tokens:1"), std::string::npos) << started.status().message();
}

// A self-signed CA and a server certificate for "lmd-test", made with openssl.
bool MakeTestCertificates(const std::string& dir) {
  const std::string command =
      "cd " + dir +
      " && openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=lmd-test-ca -keyout ca.key -out ca.pem"
      " && openssl req -newkey rsa:2048 -nodes -subj /CN=lmd-test -keyout server.key -out server.csr"
      " && printf 'subjectAltName=DNS:lmd-test\\n' > ext.cnf"
      " && openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days 1"
      "    -extfile ext.cnf -out server.pem";
  return std::system((command + " >/dev/null 2>&1").c_str()) == 0;
}

TEST(TlsTest, RoundTripOverTlsAndPlaintextClientIsRefused) {
  TempDir dir;
  ASSERT_TRUE(MakeTestCertificates(dir.path())) << "openssl could not make test certificates";
  server::ServerConfig config;
  config.tls_cert_file = dir.path() + "/server.pem";
  config.tls_key_file = dir.path() + "/server.key";
  TestServer server(dir.path() + "/data", config);
  ASSERT_TRUE(server.ok());

  client::ClientOptions options;
  options.target = server.address();
  options.tls_root_ca_file = dir.path() + "/ca.pem";
  options.tls_server_name = "lmd-test";
  options.max_attempts = 1;
  auto tls_client = std::move(client::LmdClient::Create(options)).value();
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(tls_client->InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &inserted).ok());
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("a");
  v1::GetMapResponse got;
  ASSERT_TRUE(tls_client->GetMap(get, &got).ok());
  EXPECT_EQ(got.map().map().x_size(), 40);

  options.tls_root_ca_file.clear();  // plaintext to a TLS server
  options.deadline = std::chrono::seconds(2);
  auto plain_client = std::move(client::LmdClient::Create(options)).value();
  EXPECT_FALSE(plain_client->GetMap(get, &got).ok());
}

}  // namespace
}  // namespace lmd::testing
