// Durability of lmdd as a separate process: every acknowledged insert
// survives kill -9; a backup restores into a fresh directory.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <rocksdb/db.h>

#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

// lmdd started with fork/exec; its port read from its first stdout line.
class LmddProcess {
 public:
  explicit LmddProcess(const std::string& data_dir) {
    int out[2];
    if (pipe(out) != 0) return;
    pid_ = fork();
    if (pid_ == 0) {
      dup2(out[1], STDOUT_FILENO);
      close(out[0]);
      execl(LMDD_PATH, LMDD_PATH, "--listen", "127.0.0.1:0", "--data-dir", data_dir.c_str(), "--log-level", "warn",
            static_cast<char*>(nullptr));
      _exit(127);
    }
    close(out[1]);
    FILE* stream = fdopen(out[0], "r");
    char line[256] = {0};
    if (std::fgets(line, sizeof(line), stream) != nullptr) std::sscanf(line, "lmdd listening on port %d", &port_);
    std::fclose(stream);
  }
  ~LmddProcess() { Kill(SIGKILL); }

  int port() const { return port_; }
  // Sends `signal` and reaps the process; returns its wait status.
  int Kill(int signal) {
    if (pid_ <= 0) return -1;
    kill(pid_, signal);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return status;
  }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
};

std::unique_ptr<client::LmdClient> ClientFor(int port) {
  client::ClientOptions options;
  options.target = "127.0.0.1:" + std::to_string(port);
  options.deadline = std::chrono::seconds(5);
  options.max_attempts = 1;
  return std::move(client::LmdClient::Create(options)).value();
}

TEST(DurabilityTest, EveryAcknowledgedInsertSurvivesKillDashNine) {
  TempDir dir;
  std::vector<std::string> acknowledged;
  {
    LmddProcess lmdd(dir.path());
    ASSERT_GT(lmdd.port(), 0) << "lmdd did not start";
    auto client = ClientFor(lmdd.port());
    std::atomic<bool> stop{false};
    std::thread writer([&] {
      for (int i = 0; !stop; ++i) {
        const std::string id = "m" + std::to_string(i);
        v1::InsertMapsResponse response;
        if (!client->InsertMaps(OneMapRequest("site", id, SquareRoomMap(200)), &response).ok()) return;
        acknowledged.push_back(id);  // only the writer thread touches it until join
      }
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    const int status = lmdd.Kill(SIGKILL);  // mid-ingest: the writer is still sending
    stop = true;
    writer.join();
    EXPECT_TRUE(WIFSIGNALED(status));
  }
  ASSERT_GT(acknowledged.size(), 10u) << "too few inserts before the kill to test anything";

  LmddProcess restarted(dir.path());
  ASSERT_GT(restarted.port(), 0) << "lmdd did not restart on the killed store";
  auto client = ClientFor(restarted.port());
  for (const std::string& id : acknowledged) {
    v1::GetMapRequest get;
    get.set_collection("site");
    get.set_map_id(id);
    v1::GetMapResponse got;
    ASSERT_TRUE(client->GetMap(get, &got).ok()) << "acknowledged map " << id << " lost";
    EXPECT_EQ(got.map().map().x_size(), 200);
  }
  v1::ListCollectionsResponse collections;
  ASSERT_TRUE(client->ListCollections(&collections).ok());
  ASSERT_EQ(collections.collections_size(), 1);
  // At most the one insert in flight at the kill may have landed unacknowledged.
  EXPECT_GE(collections.collections(0).maps(), acknowledged.size());
  EXPECT_LE(collections.collections(0).maps(), acknowledged.size() + 1);
}

TEST(DurabilityTest, SigtermStopsCleanly) {
  TempDir dir;
  LmddProcess lmdd(dir.path());
  ASSERT_GT(lmdd.port(), 0);
  v1::InsertMapsResponse response;
  ASSERT_TRUE(ClientFor(lmdd.port())->InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &response).ok());
  const int status = lmdd.Kill(SIGTERM);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(DurabilityTest, BackupRefusesDirectoriesItCannotOrShouldNotWrite) {
  TempDir dir;
  TestServer server(dir.path() + "/data");
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "m", SquareRoomMap()), &inserted).ok());
  v1::BackupRequest request;
  v1::BackupResponse response;
  request.set_directory(dir.path() + "/no/such/parent");
  grpc::Status status = server.client().Backup(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("not an existing directory"), std::string::npos) << status.error_message();
  request.set_directory(dir.path() + "/data/inside");
  status = server.client().Backup(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("inside lmdd's data directory"), std::string::npos) << status.error_message();
}

// A directory the client chose that the system cannot take is the client's
// to fix, said in a short message: no INTERNAL, and no 10 KB message the
// client could not even receive (gRPC refuses headers over 8 KiB).
TEST(DurabilityTest, BackupRefusesPathsTheSystemCannotTakeWithShortMessages) {
  TempDir dir;
  TestServer server(dir.path() + "/data");
  v1::BackupRequest request;
  v1::BackupResponse response;
  request.set_directory("/" + std::string(5000, 'a'));
  grpc::Status status = server.client().Backup(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("is 5001 bytes long; at most"), std::string::npos) << status.error_message();
  EXPECT_LT(status.error_message().size(), 200u);

  request.set_directory(dir.path() + "/" + std::string(300, 'b'));
  status = server.client().Backup(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("is longer than 251 bytes"), std::string::npos) << status.error_message();
  EXPECT_LT(status.error_message().size(), 300u);

  request.set_directory("/proc/lmdbk");  // mkdir fails there, even for root
  status = server.client().Backup(request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("cannot create backup directory '/proc/lmdbk': ", 0), 0u)
      << status.error_message();
  EXPECT_FALSE(std::filesystem::exists("/proc/lmdbk"));
}

TEST(DurabilityTest, BackupRestoresIntoAFreshDirectory) {
  TempDir dir;
  const std::string backup = dir.path() + "/backup";
  {
    TestServer server(dir.path() + "/data");
    v1::InsertMapsRequest request;
    for (int i = 0; i < 5; ++i) *request.add_maps() = OneMapRequest("site", "m" + std::to_string(i), SquareRoomMap(20 + i)).maps(0);
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(request, &inserted).ok());
    v1::BackupRequest backup_request;
    backup_request.set_directory(backup);
    v1::BackupResponse backed_up;
    ASSERT_TRUE(server.client().Backup(backup_request, &backed_up).ok());
    EXPECT_GT(backed_up.bytes(), 0u);
    EXPECT_EQ(server.client().Backup(backup_request, &backed_up).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    // Written after the backup: must not be in it.
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "late", SquareRoomMap()), &inserted).ok());
  }
  TestServer restored(backup);
  ASSERT_TRUE(restored.ok());
  for (int i = 0; i < 5; ++i) {
    v1::GetMapRequest get;
    get.set_collection("site");
    get.set_map_id("m" + std::to_string(i));
    v1::GetMapResponse got;
    ASSERT_TRUE(restored.client().GetMap(get, &got).ok());
    EXPECT_EQ(got.map().map().x_size(), 20 + i);
  }
  v1::GetMapRequest late;
  late.set_collection("site");
  late.set_map_id("late");
  v1::GetMapResponse got;
  EXPECT_EQ(restored.client().GetMap(late, &got).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST(DurabilityTest, UnopenableStoreIsReportedAndLeftAlone) {
  TempDir dir;
  const std::string data = dir.path() + "/data";
  { TestServer server(data); }
  std::ofstream(data + "/CURRENT", std::ios::trunc) << "garbage\n";  // a damaged store
  server::ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.data_dir = data;
  auto started = server::LmdServer::Start(config);
  ASSERT_FALSE(started.ok());
  EXPECT_NE(started.status().message().find("cannot open the store"), std::string::npos)
      << started.status().message();
  std::ifstream current(data + "/CURRENT");
  std::string content;
  std::getline(current, content);
  EXPECT_EQ(content, "garbage");  // nothing was "repaired" or deleted
}

// Every file in `dir` by name, with its bytes.
std::map<std::string, std::string> FilesIn(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    files[entry.path().filename().string()] = bytes.str();
  }
  return files;
}

// lmdd on `data_dir`, expected to refuse it.
Status StartRefused(const std::string& data_dir) {
  server::ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.data_dir = data_dir;
  auto started = server::LmdServer::Start(config);
  return started.ok() ? Status::Ok() : started.status();
}

// RocksDB would take a store that lost its CURRENT for an empty directory,
// create a new store there and delete the old one's files.
TEST(DurabilityTest, StoreWithoutCurrentIsRefusedAndLeftAlone) {
  TempDir dir;
  const std::string data = dir.path() + "/data";
  {
    TestServer server(data);
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &inserted).ok());
  }
  ASSERT_TRUE(std::filesystem::remove(data + "/CURRENT"));
  const auto before = FilesIn(data);
  const Status refused = StartRefused(data);
  EXPECT_EQ(refused.code(), Status::Code::kFailedPrecondition) << refused.ToString();
  EXPECT_NE(refused.message().find("but no CURRENT file"), std::string::npos) << refused.message();
  EXPECT_EQ(FilesIn(data), before);  // every file still there, byte for byte, and none added
}

TEST(DurabilityTest, DirectoryOfOtherFilesIsRefusedUntouched) {
  TempDir dir;
  std::ofstream(dir.path() + "/000007.log") << "not a store";
  const Status refused = StartRefused(dir.path());
  EXPECT_EQ(refused.code(), Status::Code::kFailedPrecondition) << refused.ToString();
  EXPECT_NE(refused.message().find("'000007.log'"), std::string::npos) << refused.message();
  const std::map<std::string, std::string> only_it = {{"000007.log", "not a store"}};
  EXPECT_EQ(FilesIn(dir.path()), only_it);  // no CURRENT, IDENTITY, MANIFEST, LOCK or LOG left behind
}

// RocksDB's lock and info log, all a failed first start may leave, hold no maps.
TEST(DurabilityTest, DirectoryWithOnlyLockAndLogGetsANewStore) {
  TempDir dir;
  std::ofstream(dir.path() + "/LOCK");
  std::ofstream(dir.path() + "/LOG") << "an earlier start's log\n";
  TestServer server(dir.path());
  EXPECT_TRUE(server.ok());
}

}  // namespace
}  // namespace lmd::testing

namespace lmd::testing {
namespace {

// A store whose counters disagree with its maps is refused with the reason,
// and left as it is.
TEST(DurabilityTest, InconsistentStoreIsReportedNotRepaired) {
  TempDir dir;
  {
    TestServer server(dir.path());
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server.client().InsertMaps(OneMapRequest("site", "a", SquareRoomMap()), &inserted).ok());
  }
  {  // Damage the store: remove one map's metadata behind lmdd's back.
    rocksdb::DB* db = nullptr;
    std::vector<rocksdb::ColumnFamilyDescriptor> families;
    std::vector<std::string> names;
    ASSERT_TRUE(rocksdb::DB::ListColumnFamilies({}, dir.path(), &names).ok());
    for (const auto& name : names) families.push_back({name, {}});
    std::vector<rocksdb::ColumnFamilyHandle*> handles;
    ASSERT_TRUE(rocksdb::DB::Open({}, dir.path(), families, &handles, &db).ok());
    for (size_t i = 0; i < names.size(); ++i) {
      if (names[i] == "metadata") {
        ASSERT_TRUE(db->Delete({}, handles[i], "site/a").ok());
      }
    }
    for (auto* handle : handles) db->DestroyColumnFamilyHandle(handle);
    ASSERT_TRUE(db->Close().ok());
    delete db;
  }
  server::ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.data_dir = dir.path();
  auto started = server::LmdServer::Start(config);
  ASSERT_FALSE(started.ok());
  EXPECT_NE(started.status().message().find("inconsistent: 0 maps stored, 1 counted"), std::string::npos)
      << started.status().message();
}

}  // namespace
}  // namespace lmd::testing
