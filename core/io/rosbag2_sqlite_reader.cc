#include "core/io/rosbag2_sqlite_reader.h"

#include <sqlite3.h>

#include <algorithm>
#include <cstring>
#include <map>

namespace lmd {
namespace {

// file: URI for `path` (RFC 3986 escapes for the characters SQLite's URI parser treats specially).
std::string FileUri(const std::string& path) {
  std::string uri = "file:";
  for (char c : path) {
    if (c == '%' || c == '?' || c == '#' || c == ' ') {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", static_cast<unsigned char>(c));
      uri += buf;
    } else {
      uri += c;
    }
  }
  return uri + "?immutable=1";
}

class Statement {
 public:
  Statement() = default;
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt** out() { return &stmt_; }
  sqlite3_stmt* get() const { return stmt_; }

 private:
  sqlite3_stmt* stmt_ = nullptr;
};

class SqliteReader : public BagReader {
 public:
  SqliteReader(sqlite3* db, std::string name) : db_(db), name_(std::move(name)) {}
  ~SqliteReader() override { sqlite3_close(db_); }

  const std::string& path() const override { return name_; }
  std::string format() const override { return "rosbag2 SQLite3"; }
  const std::vector<BagTopic>& topics() const override { return topics_.topics(); }

  Status Load() {
    Statement topics;
    if (sqlite3_prepare_v2(db_, "SELECT id, name, type, serialization_format FROM topics ORDER BY id", -1,
                           topics.out(), nullptr) != SQLITE_OK) {
      return Failed("no rosbag2 'topics' table");
    }
    int rc;
    while ((rc = sqlite3_step(topics.get())) == SQLITE_ROW) {
      // One topic per row (rosbag2 makes names unique): the table index is the row's.
      ids_.push_back(sqlite3_column_int64(topics.get(), 0));
      rows_.push_back(topics_.Add(Text(topics.get(), 1), Text(topics.get(), 2), Text(topics.get(), 3), 0));
    }
    if (rc != SQLITE_DONE) return Failed("reading the topics table");
    Statement counts;
    if (sqlite3_prepare_v2(db_, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id", -1, counts.out(),
                           nullptr) != SQLITE_OK) {
      return Failed("no rosbag2 'messages' table");
    }
    while ((rc = sqlite3_step(counts.get())) == SQLITE_ROW) {
      const int64_t id = sqlite3_column_int64(counts.get(), 0);
      for (size_t i = 0; i < ids_.size(); ++i) {
        if (ids_[i] == id) topics_.AddMessages(rows_[i], static_cast<uint64_t>(sqlite3_column_int64(counts.get(), 1)));
      }
    }
    if (rc != SQLITE_DONE) return Failed("counting messages");
    return Status::Ok();
  }

  Status ReadMessages(const std::vector<size_t>& wanted,
                      const std::function<Status(const BagMessage&)>& on_message) override {
    std::string sql = "SELECT id, topic_id, timestamp, data FROM messages WHERE topic_id IN (";
    std::map<int64_t, size_t> topic_of;
    for (size_t i = 0; i < ids_.size(); ++i) {
      if (std::find(wanted.begin(), wanted.end(), rows_[i]) == wanted.end()) continue;
      topic_of[ids_[i]] = rows_[i];
      sql += (topic_of.size() > 1 ? "," : "") + std::to_string(ids_[i]);
    }
    if (topic_of.empty()) return Status::Ok();
    sql += ") ORDER BY id";  // recording order, as MCAP and ROS 1 files keep it
    Statement messages;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, messages.out(), nullptr) != SQLITE_OK) {
      return Failed("querying messages");
    }
    uint64_t number = 0;
    int rc;
    while ((rc = sqlite3_step(messages.get())) == SQLITE_ROW) {
      BagMessage m;
      const int64_t row = sqlite3_column_int64(messages.get(), 0);
      m.topic = topic_of[sqlite3_column_int64(messages.get(), 1)];
      m.log_time_ns = sqlite3_column_int64(messages.get(), 2);
      const void* blob = sqlite3_column_blob(messages.get(), 3);
      const int bytes = sqlite3_column_bytes(messages.get(), 3);
      m.data = blob == nullptr ? std::string_view() : std::string_view(static_cast<const char*>(blob), bytes);
      ++number;
      m.where = "row id " + std::to_string(row);
      Status s = on_message(m);
      if (!s.ok()) return s;
    }
    if (rc != SQLITE_DONE) return Failed("reading message " + std::to_string(number + 1));
    return Status::Ok();
  }

 private:
  static std::string Text(sqlite3_stmt* stmt, int column) {
    const unsigned char* text = sqlite3_column_text(stmt, column);
    return text == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(text));
  }

  Status Failed(const std::string& what) const {
    const int code = sqlite3_errcode(db_);
    const std::string msg = name_ + ": SQLite: " + what + ": " + sqlite3_errmsg(db_);
    if (code == SQLITE_CORRUPT || code == SQLITE_NOTADB) return Status::Corruption(msg);
    return Status::InvalidArgument(msg);
  }

  sqlite3* db_;
  std::string name_;
  std::vector<int64_t> ids_;    // topics table rows: their ids
  std::vector<size_t> rows_;    //   and their topic indices
  TopicTable topics_;
};

Result<std::unique_ptr<BagReader>> Finish(sqlite3* db, int rc, const std::string& name) {
  if (rc != SQLITE_OK) {
    const std::string msg = name + ": SQLite: cannot open: " + (db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
    sqlite3_close(db);
    return Status::IoError(msg);
  }
  auto reader = std::make_unique<SqliteReader>(db, name);
  Status s = reader->Load();
  if (!s.ok()) return s;
  return std::unique_ptr<BagReader>(std::move(reader));
}

}  // namespace

bool HasSqliteMagic(std::string_view head) {
  return head.size() >= 16 && std::memcmp(head.data(), "SQLite format 3\0", 16) == 0;
}

Result<std::unique_ptr<BagReader>> OpenRosbag2Sqlite(const std::string& path) {
  sqlite3* db = nullptr;
  const int rc = sqlite3_open_v2(FileUri(path).c_str(), &db, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
  return Finish(db, rc, path);
}

Result<std::unique_ptr<BagReader>> OpenRosbag2SqliteBytes(std::string bytes, const std::string& name) {
  if (!HasSqliteMagic(bytes)) return Status::InvalidArgument(name + ": not an SQLite database (bad magic)");
  sqlite3* db = nullptr;
  int rc = sqlite3_open_v2(":memory:", &db, SQLITE_OPEN_READWRITE, nullptr);
  if (rc == SQLITE_OK) {
    // SQLite owns a copy (freed when the database closes).
    auto* copy = static_cast<unsigned char*>(sqlite3_malloc64(bytes.size()));
    if (copy == nullptr) {
      sqlite3_close(db);
      return Status::ResourceExhausted(name + ": out of memory");
    }
    std::memcpy(copy, bytes.data(), bytes.size());
    rc = sqlite3_deserialize(db, "main", copy, static_cast<sqlite3_int64>(bytes.size()),
                             static_cast<sqlite3_int64>(bytes.size()),
                             SQLITE_DESERIALIZE_READONLY | SQLITE_DESERIALIZE_FREEONCLOSE);
  }
  return Finish(db, rc, name);
}

}  // namespace lmd
