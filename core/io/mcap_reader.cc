#include "core/io/mcap_reader.h"

#include <zlib.h>

#include <algorithm>
#include <map>
#include <set>

#include "core/io/byte_cursor.h"
#include "core/io/compression.h"

namespace lmd {
namespace {

constexpr char kMagic[] = "\x89MCAP0\r\n";
constexpr size_t kMagicSize = 8;
constexpr size_t kRecordHead = 9;     // opcode u8 + length u64
constexpr size_t kFooterBody = 20;    // summary_start u64, summary_offset_start u64, summary_crc u32

enum Opcode : uint8_t {
  kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
  kMessageIndex = 0x07, kChunkIndex = 0x08, kStatistics = 0x0B, kDataEnd = 0x0F,
};

uint32_t Crc32(std::string_view bytes, uint32_t crc = 0) {
  return static_cast<uint32_t>(::crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()),
                                       static_cast<uInt>(bytes.size())));
}

struct ChunkRef {
  uint64_t offset = 0;   // of the Chunk record
  uint64_t length = 0;   // of the whole record
  std::set<uint16_t> channels;  // from message_index_offsets; empty = unknown
};

class McapReader : public BagReader {
 public:
  McapReader(std::unique_ptr<ByteSource> source, const BagReadOptions& options)
      : source_(std::move(source)), options_(options) {}

  const std::string& path() const override { return source_->name(); }
  std::string format() const override {
    std::string f = "MCAP";
    if (!profile_.empty()) f += " (" + profile_ + " profile)";
    f += chunk_compressions_.empty() ? ", unchunked" : ", chunks:";
    for (const std::string& c : chunk_compressions_) f += " " + c;
    f += has_summary_ ? ", summary" : ", no summary (scanned)";
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
    if (!HasMcapMagic(head)) return Status::InvalidArgument(path() + ": not an MCAP file (bad magic)");
    s = ReadSummary();
    if (!s.ok()) return s;
    if (!has_summary_ || channels_.empty()) {
      // No summary (or one without channels): one pass over the data section finds channels and counts.
      channels_from_summary_ = false;
      s = Scan({}, nullptr);
      if (!s.ok()) return s;
    }
    return BuildTopics();
  }

  Status ReadMessages(const std::vector<size_t>& wanted,
                      const std::function<Status(const BagMessage&)>& on_message) override {
    std::set<uint16_t> channels;
    for (const auto& [id, topic] : channel_topic_) {
      if (std::find(wanted.begin(), wanted.end(), topic) != wanted.end()) channels.insert(id);
    }
    if (channels.empty()) return Status::Ok();
    if (!chunks_.empty()) {
      for (const ChunkRef& chunk : chunks_) {
        bool needed = chunk.channels.empty();
        for (uint16_t c : chunk.channels) needed = needed || channels.count(c) > 0;
        if (!needed) continue;
        std::string record;
        Status s = source_->Read(chunk.offset, chunk.length, "a chunk the summary indexes", &record);
        if (!s.ok()) return s;
        ByteCursor in(record, chunk.offset);
        uint8_t op = 0;
        uint64_t len = 0;
        if (!in.U8(&op) || !in.U64(&len) || op != kChunk || len != chunk.length - kRecordHead) {
          return Error(chunk.offset, "the summary's chunk index points at no chunk record of its length");
        }
        std::string_view body;
        in.Bytes(static_cast<size_t>(len), &body);
        s = Chunk(body, chunk.offset, channels, &on_message);
        if (!s.ok()) return s;
      }
      return Status::Ok();
    }
    return Scan(channels, &on_message);
  }

 private:
  Status Error(uint64_t offset, const std::string& what) const {
    return Status::Corruption(path() + ": offset " + std::to_string(offset) + ": " + what);
  }

  // Footer and summary section, if the file ends with them.
  Status ReadSummary() {
    const uint64_t size = source_->size();
    const uint64_t footer_size = kRecordHead + kFooterBody;
    if (size < 2 * kMagicSize + footer_size) return Status::Ok();
    std::string tail;
    const uint64_t footer_at = size - kMagicSize - footer_size;
    Status s = source_->Read(footer_at, footer_size + kMagicSize, "the footer", &tail);
    if (!s.ok()) return s;
    if (tail.compare(footer_size, kMagicSize, kMagic, kMagicSize) != 0) return Status::Ok();  // no end magic
    ByteCursor f(tail, footer_at);
    uint8_t op = 0;
    uint64_t len = 0, summary_start = 0, summary_offset_start = 0;
    uint32_t summary_crc = 0;
    f.U8(&op), f.U64(&len);
    if (op != kFooter || len != kFooterBody) return Status::Ok();  // end magic without a footer: scan
    f.U64(&summary_start), f.U64(&summary_offset_start), f.U32(&summary_crc);
    if (summary_start == 0) return Status::Ok();
    if (summary_start < kMagicSize || summary_start > footer_at) {
      return Error(footer_at, "footer's summary_start " + std::to_string(summary_start) + " lies outside the file");
    }
    std::string summary;
    s = source_->Read(summary_start, footer_at - summary_start, "the summary section", &summary);
    if (!s.ok()) return s;
    if (summary_crc != 0) {
      const uint32_t crc = Crc32(std::string_view(tail).substr(0, kRecordHead + 16), Crc32(summary));
      if (crc != summary_crc) {
        return Error(summary_start, "summary CRC mismatch (recorded " + std::to_string(summary_crc) +
                                        ", computed " + std::to_string(crc) + ")");
      }
    }
    ByteCursor in(summary, summary_start);
    while (!in.done()) {
      const uint64_t at = in.offset();
      uint8_t rop = 0;
      uint64_t rlen = 0;
      std::string_view body;
      if (!in.U8(&rop) || !in.U64(&rlen) || rlen > in.left() || !in.Bytes(static_cast<size_t>(rlen), &body)) {
        return Error(at, "summary record runs past the summary section");
      }
      if (rop == kSchema) s = SchemaRecord(body, at);
      else if (rop == kChannel) s = ChannelRecord(body, at);
      else if (rop == kChunkIndex) s = ChunkIndexRecord(body, at, size);
      else if (rop == kStatistics) s = StatisticsRecord(body, at);
      if (!s.ok()) return s;
    }
    has_summary_ = true;
    channels_from_summary_ = true;
    std::sort(chunks_.begin(), chunks_.end(), [](const ChunkRef& a, const ChunkRef& b) { return a.offset < b.offset; });
    return Status::Ok();
  }

  Status SchemaRecord(std::string_view body, uint64_t at) {
    ByteCursor in(body, at + kRecordHead);
    uint16_t id = 0;
    std::string_view name, encoding, data;
    if (!in.U16(&id) || !in.PrefixedU32(&name) || !in.PrefixedU32(&encoding) || !in.PrefixedU32(&data)) {
      return Error(at, "schema record is truncated");
    }
    schemas_[id] = std::string(name);
    return Status::Ok();
  }

  Status ChannelRecord(std::string_view body, uint64_t at) {
    ByteCursor in(body, at + kRecordHead);
    uint16_t id = 0, schema = 0;
    std::string_view topic, encoding, metadata;
    if (!in.U16(&id) || !in.U16(&schema) || !in.PrefixedU32(&topic) || !in.PrefixedU32(&encoding) ||
        !in.PrefixedU32(&metadata)) {
      return Error(at, "channel record is truncated");
    }
    if (channels_.count(id) == 0) channels_[id] = {std::string(topic), std::string(encoding), schema};
    return Status::Ok();
  }

  Status ChunkIndexRecord(std::string_view body, uint64_t at, uint64_t file_size) {
    ByteCursor in(body, at + kRecordHead);
    uint64_t start_time, end_time, offset = 0, length = 0;
    std::string_view offsets;
    if (!in.U64(&start_time) || !in.U64(&end_time) || !in.U64(&offset) || !in.U64(&length) ||
        !in.PrefixedU32(&offsets)) {
      return Error(at, "chunk index record is truncated");
    }
    if (offset < kMagicSize || length < kRecordHead || offset > file_size || length > file_size - offset) {
      return Error(at, "chunk index points outside the file (chunk at " + std::to_string(offset) + ", " +
                           std::to_string(length) + " bytes)");
    }
    ChunkRef ref{offset, length, {}};
    ByteCursor map(offsets, in.offset() - offsets.size());
    while (!map.done()) {
      uint16_t channel = 0;
      uint64_t index_offset = 0;
      if (!map.U16(&channel) || !map.U64(&index_offset)) return Error(at, "chunk index's message index map is truncated");
      ref.channels.insert(channel);
    }
    uint64_t index_length = 0;
    std::string_view compression;
    if (in.U64(&index_length) && in.PrefixedU32(&compression)) NoteCompression(compression);
    chunks_.push_back(std::move(ref));
    return Status::Ok();
  }

  Status StatisticsRecord(std::string_view body, uint64_t at) {
    ByteCursor in(body, at + kRecordHead);
    uint64_t message_count = 0, start = 0, end = 0;
    uint16_t schema_count = 0;
    uint32_t channel_count = 0, attachment_count = 0, metadata_count = 0, chunk_count = 0;
    std::string_view counts;
    if (!in.U64(&message_count) || !in.U16(&schema_count) || !in.U32(&channel_count) ||
        !in.U32(&attachment_count) || !in.U32(&metadata_count) || !in.U32(&chunk_count) || !in.U64(&start) ||
        !in.U64(&end) || !in.PrefixedU32(&counts)) {
      return Error(at, "statistics record is truncated");
    }
    ByteCursor map(counts);
    while (!map.done()) {
      uint16_t channel = 0;
      uint64_t n = 0;
      if (!map.U16(&channel) || !map.U64(&n)) return Error(at, "statistics' channel message counts are truncated");
      counts_[channel] = n;
    }
    return Status::Ok();
  }

  // The records of one chunk (`body` = the Chunk record's body at `at`).
  Status Chunk(std::string_view body, uint64_t at, const std::set<uint16_t>& channels,
               const std::function<Status(const BagMessage&)>* on_message) {
    ByteCursor in(body, at + kRecordHead);
    uint64_t start_time = 0, end_time = 0, uncompressed_size = 0;
    uint32_t crc = 0;
    std::string_view compression, records;
    if (!in.U64(&start_time) || !in.U64(&end_time) || !in.U64(&uncompressed_size) || !in.U32(&crc) ||
        !in.PrefixedU32(&compression) || !in.PrefixedU64(&records)) {
      return Error(at, "chunk record is truncated");
    }
    Compression codec;
    if (compression.empty()) codec = Compression::kNone;
    else if (compression == "zstd") codec = Compression::kZstd;
    else if (compression == "lz4") codec = Compression::kLz4Frame;
    else return Error(at, "chunk has unknown compression '" + std::string(compression) + "' (known: zstd, lz4, none)");
    NoteCompression(compression);
    std::string_view data = records;
    if (codec != Compression::kNone || records.size() != uncompressed_size) {
      Status s = Decompress(codec, records, uncompressed_size, options_.max_chunk_bytes,
                            path() + ": chunk at offset " + std::to_string(at), &buffer_);
      if (!s.ok()) return s;
      data = buffer_;
    }
    if (crc != 0 && Crc32(data) != crc) {
      return Error(at, "chunk CRC mismatch (recorded " + std::to_string(crc) + ", computed " +
                           std::to_string(Crc32(data)) + ")");
    }
    return ChunkRecords(data, at, /*cut=*/false, channels, on_message);
  }

  // The complete records of a chunk the file's end cuts short (`head` = the
  // chunk's body up to the end of the file). Only an uncompressed chunk's
  // records can be read without the rest; its CRC cannot be checked.
  Status CutChunk(std::string_view head, uint64_t at, const std::set<uint16_t>& channels,
                  const std::function<Status(const BagMessage&)>* on_message) {
    ByteCursor in(head, at + kRecordHead);
    uint64_t start_time = 0, end_time = 0, uncompressed_size = 0, records_size = 0;
    uint32_t crc = 0;
    std::string_view compression;
    if (!in.U64(&start_time) || !in.U64(&end_time) || !in.U64(&uncompressed_size) || !in.U32(&crc) ||
        !in.PrefixedU32(&compression) || !in.U64(&records_size) || !compression.empty()) {
      return Status::Ok();
    }
    NoteCompression(compression);
    return ChunkRecords(in.Rest(), at, /*cut=*/true, channels, on_message);
  }

  void NoteCompression(std::string_view compression) {
    const std::string name = compression.empty() ? "none" : std::string(compression);
    if (std::find(chunk_compressions_.begin(), chunk_compressions_.end(), name) == chunk_compressions_.end()) {
      chunk_compressions_.push_back(name);
    }
  }

  // The records of a chunk's (uncompressed) data; `cut`: the data ends
  // inside a record, and the records before it are read.
  Status ChunkRecords(std::string_view data, uint64_t at, bool cut, const std::set<uint16_t>& channels,
                      const std::function<Status(const BagMessage&)>* on_message) {
    ByteCursor r(data);
    while (!r.done()) {
      const uint64_t inner = r.pos();
      uint8_t op = 0;
      uint64_t len = 0;
      std::string_view rec;
      if (!r.U8(&op) || !r.U64(&len) || len > r.left() || !r.Bytes(static_cast<size_t>(len), &rec)) {
        if (cut) return Status::Ok();
        return Error(at, "record at byte " + std::to_string(inner) + " of the chunk runs past its end");
      }
      Status s = Record(op, rec, at, inner, channels, on_message);
      if (!s.ok()) return s;
    }
    return Status::Ok();
  }

  // One record of the data section (in_chunk: byte offset inside the chunk at `at`, or npos).
  Status Record(uint8_t op, std::string_view body, uint64_t at, uint64_t in_chunk, const std::set<uint16_t>& channels,
                const std::function<Status(const BagMessage&)>* on_message) {
    auto where = [&] {
      return in_chunk == kNoChunk ? "offset " + std::to_string(at)
                                  : "byte " + std::to_string(in_chunk) + " of the chunk at offset " + std::to_string(at);
    };
    if (op == kSchema || op == kChannel) {
      if (channels_from_summary_) return Status::Ok();
      Status s = op == kSchema ? SchemaRecord(body, at) : ChannelRecord(body, at);
      if (!s.ok()) return Status::Corruption(path() + ": " + where() + ": " + (op == kSchema ? "schema" : "channel") +
                                             " record is truncated");
      return s;
    }
    if (op != kMessage) return Status::Ok();
    ByteCursor in(body);
    uint16_t channel = 0;
    uint32_t sequence = 0;
    uint64_t log_time = 0, publish_time = 0;
    if (!in.U16(&channel) || !in.U32(&sequence) || !in.U64(&log_time) || !in.U64(&publish_time)) {
      return Status::Corruption(path() + ": " + where() + ": message record is truncated");
    }
    if (on_message == nullptr) {  // the scan that finds channels
      if (!channels_from_summary_ || counts_.empty()) ++scanned_counts_[channel];
      return Status::Ok();
    }
    if (channels.count(channel) == 0) return Status::Ok();
    BagMessage m;
    m.topic = channel_topic_.at(channel);
    m.log_time_ns = static_cast<int64_t>(std::min<uint64_t>(log_time, INT64_MAX));
    m.data = in.Rest();
    m.where = where();
    return (*on_message)(m);
  }

  // The data section record by record, from the header to DataEnd (or the end of the file).
  Status Scan(const std::set<uint16_t>& channels, const std::function<Status(const BagMessage&)>* on_message) {
    const uint64_t size = source_->size();
    uint64_t at = kMagicSize;
    uint32_t crc = Crc32(std::string_view(kMagic, kMagicSize));
    std::string head, body;
    while (at < size) {
      if (size - at < kRecordHead) {
        if (options_.salvage_truncated) return SalvageCut(at, 0, channels, on_message);
        return Error(at, "truncated: " + std::to_string(size - at) + " bytes left, a record needs 9 (file cut short?)");
      }
      Status s = source_->Read(at, kRecordHead, "a record header", &head);
      if (!s.ok()) return s;
      ByteCursor h(head, at);
      uint8_t op = 0;
      uint64_t len = 0;
      h.U8(&op), h.U64(&len);
      if (len > size - at - kRecordHead) {
        if (options_.salvage_truncated) return SalvageCut(at, op, channels, on_message);
        return Error(at, "truncated: record (opcode " + std::to_string(op) + ") declares " + std::to_string(len) +
                             " bytes, " + std::to_string(size - at - kRecordHead) + " are left (file cut short?)");
      }
      if (op == kFooter) break;
      s = source_->Read(at + kRecordHead, len, "a record", &body);
      if (!s.ok()) return s;
      if (op == kDataEnd) {
        ByteCursor d(body);
        uint32_t recorded = 0;
        if (d.U32(&recorded) && recorded != 0 && recorded != crc) {
          return Error(at, "data section CRC mismatch (recorded " + std::to_string(recorded) + ", computed " +
                               std::to_string(crc) + ")");
        }
        break;
      }
      crc = Crc32(body, Crc32(head, crc));
      if (op == kHeader) {
        ByteCursor p(body);
        std::string_view profile;
        if (p.PrefixedU32(&profile)) profile_ = std::string(profile);
      } else if (op == kChunk) {
        s = Chunk(body, at, channels, on_message);
      } else {
        s = Record(op, body, at, kNoChunk, channels, on_message);
      }
      if (!s.ok()) return s;
      at += kRecordHead + len;
    }
    return Status::Ok();
  }

  // The file ends inside the record at `at` (opcode `op`): the records
  // before it are read; so are the complete ones of an uncompressed chunk.
  Status SalvageCut(uint64_t at, uint8_t op, const std::set<uint16_t>& channels,
                    const std::function<Status(const BagMessage&)>* on_message) {
    cut_at_ = at;
    if (op != kChunk) return Status::Ok();
    std::string head;
    Status s = source_->Read(at + kRecordHead, source_->size() - at - kRecordHead, "a cut-off chunk", &head);
    if (!s.ok()) return s;
    return CutChunk(head, at, channels, on_message);
  }

  Status BuildTopics() {
    if (cut_at_ != kNotCut && channels_.empty()) {
      return Error(cut_at_, "truncated (file cut short?): no complete channel record before the cut, so nothing "
                            "could be salvaged");
    }
    if (counts_.empty()) counts_ = scanned_counts_;
    for (const auto& [id, channel] : channels_) {
      const auto schema = schemas_.find(channel.schema);
      const auto n = counts_.find(id);
      channel_topic_[id] = topics_.Add(channel.topic, schema == schemas_.end() ? "" : schema->second,
                                       channel.encoding, n == counts_.end() ? 0 : n->second);
    }
    return Status::Ok();
  }

  struct Channel {
    std::string topic, encoding;
    uint16_t schema = 0;
  };
  static constexpr uint64_t kNoChunk = ~0ull;
  static constexpr uint64_t kNotCut = ~0ull;

  std::unique_ptr<ByteSource> source_;
  BagReadOptions options_;
  std::string profile_;
  bool has_summary_ = false;
  bool channels_from_summary_ = false;
  uint64_t cut_at_ = kNotCut;  // where a salvaged file ends inside a record
  std::map<uint16_t, uint64_t> scanned_counts_;
  std::map<uint16_t, std::string> schemas_;
  std::map<uint16_t, Channel> channels_;
  std::map<uint16_t, uint64_t> counts_;
  std::map<uint16_t, size_t> channel_topic_;
  std::vector<ChunkRef> chunks_;
  std::vector<std::string> chunk_compressions_;
  TopicTable topics_;
  std::string buffer_;
};

}  // namespace

bool HasMcapMagic(std::string_view head) {
  return head.size() >= kMagicSize && head.compare(0, kMagicSize, std::string_view(kMagic, kMagicSize)) == 0;
}

Result<std::unique_ptr<BagReader>> OpenMcap(std::unique_ptr<ByteSource> source, const BagReadOptions& options) {
  auto reader = std::make_unique<McapReader>(std::move(source), options);
  Status s = reader->Open();
  if (!s.ok()) return s;
  return std::unique_ptr<BagReader>(std::move(reader));
}

}  // namespace lmd
