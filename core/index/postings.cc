#include "core/index/postings.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace lmd {
namespace {

constexpr size_t kKeyBytes = 14;

void PutU16(std::string* s, uint32_t v) {
  s->push_back(static_cast<char>((v >> 8) & 0xFF));
  s->push_back(static_cast<char>(v & 0xFF));
}

uint32_t GetU16(const std::string& s, size_t at) {
  return (static_cast<uint32_t>(static_cast<uint8_t>(s[at])) << 8) | static_cast<uint8_t>(s[at + 1]);
}

}  // namespace

std::string PostingListPrefix(uint32_t word, int32_t cx, int32_t cy) {
  std::string key;
  PutU16(&key, word);
  PutU16(&key, static_cast<uint32_t>(cx + 32768));
  PutU16(&key, static_cast<uint32_t>(cy + 32768));
  return key;
}

Result<std::vector<PostingRecord>> PostingsOf(uint64_t id, const Lmd& lmd, const IndexOptions& options) {
  auto features = ToPoseFeatures(lmd, options);
  if (!features.ok()) return features.status();
  const int32_t cell0 = static_cast<int32_t>(std::lround(options.pyramid_cell_m / options.pose_quantum_m));
  // Features are sorted by (word, x, y); group by (word, cx, cy) via a sorted map.
  std::map<std::string, std::string> groups;
  for (const PoseFeature& f : *features) {
    std::string& value = groups[PostingListPrefix(f.word, FloorDiv(f.x, cell0), FloorDiv(f.y, cell0))];
    for (int16_t v : {f.x, f.y}) {
      const uint16_t u = static_cast<uint16_t>(v);
      value.push_back(static_cast<char>(u & 0xFF));
      value.push_back(static_cast<char>(u >> 8));
    }
  }
  std::vector<PostingRecord> out;
  out.reserve(groups.size());
  for (auto& kv : groups) {
    PostingRecord r;
    r.key = kv.first;
    for (int shift = 56; shift >= 0; shift -= 8) r.key.push_back(static_cast<char>((id >> shift) & 0xFF));
    r.value = std::move(kv.second);
    out.push_back(std::move(r));
  }
  return out;
}

Status LoadPostings(const std::vector<PostingRecord>& records, Index* index) {
  const IndexOptions& options = index->options();
  const int32_t cell0 = static_cast<int32_t>(std::lround(options.pyramid_cell_m / options.pose_quantum_m));
  std::map<uint64_t, std::vector<PoseFeature>> maps;
  for (size_t r = 0; r < records.size(); ++r) {
    const PostingRecord& rec = records[r];
    if (rec.key.size() != kKeyBytes || rec.value.empty() || rec.value.size() % 4 != 0)
      return Status::Corruption("posting record " + std::to_string(r) + ": bad key or value size");
    const uint32_t word = GetU16(rec.key, 0);
    const int32_t cx = static_cast<int32_t>(GetU16(rec.key, 2)) - 32768;
    const int32_t cy = static_cast<int32_t>(GetU16(rec.key, 4)) - 32768;
    uint64_t id = 0;
    for (size_t k = 6; k < kKeyBytes; ++k) id = (id << 8) | static_cast<uint8_t>(rec.key[k]);
    auto& features = maps[id];
    for (size_t at = 0; at < rec.value.size(); at += 4) {
      const auto x = static_cast<int16_t>(static_cast<uint16_t>(static_cast<uint8_t>(rec.value[at]) |
                                                                (static_cast<uint8_t>(rec.value[at + 1]) << 8)));
      const auto y = static_cast<int16_t>(static_cast<uint16_t>(static_cast<uint8_t>(rec.value[at + 2]) |
                                                                (static_cast<uint8_t>(rec.value[at + 3]) << 8)));
      if (FloorDiv(x, cell0) != cx || FloorDiv(y, cell0) != cy)
        return Status::Corruption("posting record " + std::to_string(r) + ": pose outside its key's cell");
      features.push_back({word, x, y});
    }
  }
  for (auto& kv : maps) {
    std::sort(kv.second.begin(), kv.second.end(), [](const PoseFeature& a, const PoseFeature& b) {
      if (a.word != b.word) return a.word < b.word;
      if (a.x != b.x) return a.x < b.x;
      return a.y < b.y;
    });
    Status st = index->AddPoseFeatures(kv.first, std::move(kv.second));
    if (!st.ok()) return st;
  }
  return Status::Ok();
}

size_t PostingBytes(const std::vector<PostingRecord>& records) {
  size_t n = 0;
  for (const auto& r : records) n += r.key.size() + r.value.size();
  return n;
}

}  // namespace lmd
