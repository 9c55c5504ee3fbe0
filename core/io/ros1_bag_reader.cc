#include "core/io/ros1_bag_reader.h"

#include <algorithm>
#include <map>
#include <set>

#include "core/io/byte_cursor.h"
#include "core/io/compression.h"

namespace lmd {
namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr size_t kMagicSize = 13;
constexpr uint32_t kMaxHeaderBytes = 1 << 20;  // a record header is a few fields; this is generous

enum Op : uint8_t {
  kMessageData = 0x02, kBagHeader = 0x03, kIndexData = 0x04, kChunk = 0x05, kChunkInfo = 0x06, kConnection = 0x07,
};

// The "name=value" fields of a record header.
class Fields {
 public:
  bool Parse(std::string_view header) {
    ByteCursor in(header);
    while (!in.done()) {
      std::string_view field;
      if (!in.PrefixedU32(&field)) return false;
      const size_t eq = field.find('=');
      if (eq == std::string_view::npos) return false;
      fields_[std::string(field.substr(0, eq))] = field.substr(eq + 1);
    }
    return true;
  }
  bool Has(const char* name) const { return fields_.count(name) > 0; }
  std::string_view Get(const char* name) const {
    const auto it = fields_.find(name);
    return it == fields_.end() ? std::string_view() : it->second;
  }
  template <typename T>
  bool Number(const char* name, T* v) const {
    const std::string_view f = Get(name);
    if (f.size() != sizeof(T)) return false;
    ByteCursor c(f);
    if constexpr (sizeof(T) == 1) return c.U8(reinterpret_cast<uint8_t*>(v));
    if constexpr (sizeof(T) == 4) return c.U32(reinterpret_cast<uint32_t*>(v));
    return c.U64(reinterpret_cast<uint64_t*>(v));
  }

 private:
  std::map<std::string, std::string_view> fields_;
};

struct ChunkInfo {
  uint64_t pos = 0;
  std::set<uint32_t> connections;
};

class Ros1BagReader : public BagReader {
 public:
  Ros1BagReader(std::unique_ptr<ByteSource> source, const BagReadOptions& options)
      : source_(std::move(source)), options_(options) {}

  const std::string& path() const override { return source_->name(); }
  std::string format() const override {
    std::string f = "ROS 1 bag v2.0";
    f += compressions_.empty() ? "" : ", chunks:";
    for (const std::string& c : compressions_) f += " " + c;
    f += indexed_ ? ", indexed" : ", unindexed (walked)";
    if (cut_at_ != kNotCut) {
      f += ", cut short in the record at offset " + std::to_string(cut_at_) +
           " (the complete records before the cut salvaged)";
    }
    return f;
  }
  const std::vector<BagTopic>& topics() const override { return topics_.topics(); }

  Status Open() {
    std::string head;
    Status s = source_->Read(0, std::min<uint64_t>(source_->size(), kMagicSize), "the magic", &head);
    if (!s.ok()) return s;
    if (!HasRos1BagMagic(head)) {
      if (head.rfind("#ROSBAG V", 0) == 0) {
        return Status::InvalidArgument(path() + ": a ROS bag of another version than 2.0 ('" +
                                       head.substr(0, head.find('\n')) + "'): only v2.0 is read");
      }
      return Status::InvalidArgument(path() + ": not a ROS 1 bag (bad magic)");
    }
    Record bag_header;
    s = ReadRecord(kMagicSize, &bag_header);
    if (!s.ok()) return s;
    uint8_t op = 0;
    uint64_t index_pos = 0;
    if (!bag_header.fields.Number("op", &op) || op != kBagHeader || !bag_header.fields.Number("index_pos", &index_pos)) {
      return Error(kMagicSize, "the first record is not a bag header with an index_pos");
    }
    data_start_ = bag_header.end;
    // An index beyond the end: the file was cut short; salvage walks the records before the cut.
    if (index_pos >= source_->size() && options_.salvage_truncated) index_pos = 0;
    if (index_pos != 0) {
      if (index_pos < data_start_ || index_pos >= source_->size()) {
        return Error(kMagicSize, "bag header's index_pos " + std::to_string(index_pos) + " lies outside the file" +
                                     (index_pos >= source_->size() ? " (file cut short?)" : ""));
      }
      s = ReadIndex(index_pos);
      if (!s.ok()) return s;
      indexed_ = true;
    } else {
      s = Walk({}, nullptr);
      if (!s.ok()) return s;
    }
    return BuildTopics();
  }

  Status ReadMessages(const std::vector<size_t>& wanted,
                      const std::function<Status(const BagMessage&)>& on_message) override {
    std::set<uint32_t> conns;
    for (const auto& [id, topic] : conn_topic_) {
      if (std::find(wanted.begin(), wanted.end(), topic) != wanted.end()) conns.insert(id);
    }
    if (conns.empty()) return Status::Ok();
    if (!indexed_) return Walk(conns, &on_message);
    for (const ChunkInfo& info : chunks_) {
      bool needed = false;
      for (uint32_t c : info.connections) needed = needed || conns.count(c) > 0;
      if (!needed) continue;
      Record chunk;
      Status s = ReadRecord(info.pos, &chunk);
      if (!s.ok()) return s;
      uint8_t op = 0;
      if (!chunk.fields.Number("op", &op) || op != kChunk) {
        return Error(info.pos, "the chunk-info record points at a record that is no chunk");
      }
      s = Chunk(chunk, conns, &on_message);
      if (!s.ok()) return s;
    }
    return Status::Ok();
  }

 private:
  struct Record {
    uint64_t at = 0, end = 0;
    std::string header_bytes, data;
    Fields fields;
  };

  Status Error(uint64_t offset, const std::string& what) const {
    return Status::Corruption(path() + ": offset " + std::to_string(offset) + ": " + what);
  }

  // The record at `at` from the file: header fields and data. With
  // count_sized_index, an index-data record's data is count * 12 bytes
  // whatever its length field says (some recorders wrote a wrong one).
  Status ReadRecord(uint64_t at, Record* r, bool count_sized_index = false) {
    std::string len;
    Status s = source_->Read(at, 4, "a record's header length", &len);
    if (!s.ok()) return s;
    uint32_t header_len = 0, data_len = 0;
    ByteCursor(len).U32(&header_len);
    if (header_len > kMaxHeaderBytes) {
      return Error(at, "record header length " + std::to_string(header_len) + " is implausible");
    }
    s = source_->Read(at + 4, header_len, "a record header", &r->header_bytes);
    if (!s.ok()) return s;
    s = source_->Read(at + 4 + header_len, 4, "a record's data length", &len);
    if (!s.ok()) return s;
    ByteCursor(len).U32(&data_len);
    if (!r->fields.Parse(r->header_bytes)) return Error(at, "record header fields are malformed");
    uint8_t op = 0;
    uint32_t count = 0;
    if (count_sized_index && r->fields.Number("op", &op) && op == kIndexData && r->fields.Number("count", &count) &&
        static_cast<uint64_t>(count) * 12 <= kMaxHeaderBytes * 64ull) {
      data_len = count * 12;
    }
    s = source_->Read(at + 8 + header_len, data_len, "a record's data", &r->data);
    if (!s.ok()) return s;
    r->at = at;
    r->end = at + 8 + header_len + data_len;
    return Status::Ok();
  }

  Status Connection(const Fields& header, std::string_view data, uint64_t at) {
    uint32_t conn = 0;
    if (!header.Number("conn", &conn) || !header.Has("topic")) {
      return Error(at, "connection record without conn and topic fields");
    }
    Fields info;
    if (!info.Parse(data)) return Error(at, "connection record's connection header is malformed");
    if (connections_.count(conn) == 0) {
      connections_[conn] = {std::string(header.Get("topic")), std::string(info.Get("type"))};
    }
    return Status::Ok();
  }

  // Connection and chunk-info records from index_pos to the end.
  Status ReadIndex(uint64_t at) {
    while (at < source_->size()) {
      Record r;
      Status s = ReadRecord(at, &r);
      if (!s.ok()) return s;
      uint8_t op = 0;
      r.fields.Number("op", &op);
      if (op == kConnection) {
        s = Connection(r.fields, r.data, at);
        if (!s.ok()) return s;
      } else if (op == kChunkInfo) {
        ChunkInfo info;
        uint32_t ver = 0;
        if (!r.fields.Number("ver", &ver) || !r.fields.Number("chunk_pos", &info.pos)) {
          return Error(at, "chunk-info record without ver and chunk_pos");
        }
        if (info.pos < data_start_ || info.pos >= source_->size()) {
          return Error(at, "chunk-info record points outside the file (chunk_pos " + std::to_string(info.pos) + ")");
        }
        ByteCursor counts(r.data, r.end - r.data.size());
        while (!counts.done()) {
          uint32_t conn = 0, n = 0;
          if (!counts.U32(&conn) || !counts.U32(&n)) return Error(at, "chunk-info record's counts are truncated");
          info.connections.insert(conn);
          counts_[conn] += n;
        }
        chunks_.push_back(std::move(info));
      }
      at = r.end;
    }
    std::sort(chunks_.begin(), chunks_.end(), [](const ChunkInfo& a, const ChunkInfo& b) { return a.pos < b.pos; });
    return Status::Ok();
  }

  // The records inside one chunk.
  Status Chunk(const Record& chunk, const std::set<uint32_t>& conns,
               const std::function<Status(const BagMessage&)>* on_message) {
    const std::string compression(chunk.fields.Get("compression"));
    uint32_t size = 0;
    if (!chunk.fields.Number("size", &size)) return Error(chunk.at, "chunk record without a size field");
    Compression codec;
    if (compression == "none") codec = Compression::kNone;
    else if (compression == "lz4") codec = Compression::kLz4Frame;
    else if (compression == "bz2") codec = Compression::kBz2;
    else return Error(chunk.at, "chunk has unknown compression '" + compression + "' (known: none, lz4, bz2)");
    if (std::find(compressions_.begin(), compressions_.end(), compression) == compressions_.end()) {
      compressions_.push_back(compression);
    }
    Status s = Decompress(codec, chunk.data, size, options_.max_chunk_bytes,
                          path() + ": chunk at offset " + std::to_string(chunk.at), &buffer_);
    if (!s.ok()) return s;
    ByteCursor in(buffer_);
    while (!in.done()) {
      const size_t inner = in.pos();
      std::string_view header, data;
      Fields fields;
      uint8_t op = 0;
      if (!in.PrefixedU32(&header) || !in.PrefixedU32(&data)) {
        return Error(chunk.at, "record at byte " + std::to_string(inner) + " of the chunk runs past its end");
      }
      if (!fields.Parse(header) || !fields.Number("op", &op)) {
        return Error(chunk.at, "record at byte " + std::to_string(inner) + " of the chunk has a malformed header");
      }
      if (op == kConnection) {
        s = Connection(fields, data, chunk.at);
        if (!s.ok()) return s;
        continue;
      }
      if (op != kMessageData) continue;
      uint32_t conn = 0;
      uint64_t time = 0;
      if (!fields.Number("conn", &conn) || !fields.Number("time", &time)) {
        return Error(chunk.at, "message at byte " + std::to_string(inner) + " of the chunk lacks conn or time");
      }
      if (on_message == nullptr) {
        ++walked_counts_[conn];
        continue;
      }
      if (conns.count(conn) == 0) continue;
      BagMessage m;
      m.topic = conn_topic_.at(conn);
      m.log_time_ns = static_cast<int64_t>(time & 0xffffffffu) * 1000000000 + static_cast<int64_t>(time >> 32);
      m.data = data;
      m.where = "byte " + std::to_string(inner) + " of the chunk at offset " + std::to_string(chunk.at);
      s = (*on_message)(m);
      if (!s.ok()) return s;
    }
    return Status::Ok();
  }

  // Every record after the bag header, in file order (unindexed bags).
  Status Walk(const std::set<uint32_t>& conns, const std::function<Status(const BagMessage&)>* on_message) {
    uint64_t at = data_start_;
    while (at < source_->size()) {
      Record r;
      Status s = ReadRecord(at, &r, /*count_sized_index=*/true);
      if (!s.ok()) {
        if (options_.salvage_truncated && s.code() == Status::Code::kCorruption) {
          cut_at_ = at;
          break;
        }
        return s;
      }
      uint8_t op = 0;
      r.fields.Number("op", &op);
      if (op == kChunk) {
        s = Chunk(r, conns, on_message);
      } else if (op == kConnection) {
        s = Connection(r.fields, r.data, at);
      } else if (op == kMessageData) {
        return Error(at, "message record outside a chunk (not a rosbag v2.0 layout)");
      }
      if (!s.ok()) return s;
      at = r.end;
    }
    return Status::Ok();
  }

  Status BuildTopics() {
    if (cut_at_ != kNotCut && connections_.empty()) {
      return Error(cut_at_, "truncated (file cut short?): no complete connection record before the cut, so "
                            "nothing could be salvaged");
    }
    if (counts_.empty()) counts_ = walked_counts_;
    for (const auto& [conn, c] : connections_) {
      const auto n = counts_.find(conn);
      conn_topic_[conn] = topics_.Add(c.topic, c.type, "ros1", n == counts_.end() ? 0 : n->second);
    }
    return Status::Ok();
  }

  struct Conn {
    std::string topic, type;
  };
  static constexpr uint64_t kNotCut = ~0ull;

  std::unique_ptr<ByteSource> source_;
  BagReadOptions options_;
  uint64_t data_start_ = 0;
  bool indexed_ = false;
  uint64_t cut_at_ = kNotCut;  // where a salvaged file ends inside a record
  std::map<uint32_t, Conn> connections_;
  std::map<uint32_t, uint64_t> counts_, walked_counts_;
  std::map<uint32_t, size_t> conn_topic_;
  std::vector<ChunkInfo> chunks_;
  std::vector<std::string> compressions_;
  TopicTable topics_;
  std::string buffer_;
};

}  // namespace

bool HasRos1BagMagic(std::string_view head) {
  return head.size() >= kMagicSize && head.compare(0, kMagicSize, std::string_view(kMagic, kMagicSize)) == 0;
}

Result<std::unique_ptr<BagReader>> OpenRos1Bag(std::unique_ptr<ByteSource> source, const BagReadOptions& options) {
  auto reader = std::make_unique<Ros1BagReader>(std::move(source), options);
  Status s = reader->Open();
  if (!s.ok()) return s;
  return std::unique_ptr<BagReader>(std::move(reader));
}

}  // namespace lmd
