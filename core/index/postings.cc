#include "core/index/postings.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace lmd {
namespace {

void PutVarint(std::string* s, uint64_t v) {
  while (v >= 0x80) {
    s->push_back(static_cast<char>((v & 0x7F) | 0x80));
    v >>= 7;
  }
  s->push_back(static_cast<char>(v));
}

bool GetVarint(const std::string& s, size_t* at, uint64_t* v) {
  *v = 0;
  for (int shift = 0; shift < 64 && *at < s.size(); shift += 7) {
    const uint8_t b = static_cast<uint8_t>(s[(*at)++]);
    *v |= static_cast<uint64_t>(b & 0x7F) << shift;
    if ((b & 0x80) == 0) return true;
  }
  return false;
}

uint64_t ZigZag(int32_t v) {
  return static_cast<uint32_t>((static_cast<uint32_t>(v) << 1) ^ static_cast<uint32_t>(v < 0 ? -1 : 0));
}
int64_t UnZigZag(uint64_t v) { return (v & 1) ? -static_cast<int64_t>(v >> 1) - 1 : static_cast<int64_t>(v >> 1); }

int32_t CellUnits(const IndexOptions& options) {
  return static_cast<int32_t>(std::lround(options.pyramid_cell_m / options.pose_quantum_m));
}

}  // namespace

std::string PostingListPrefix(uint32_t word, int32_t cx, int32_t cy) {
  std::string key;
  key.push_back(static_cast<char>((word >> 8) & 0xFF));
  key.push_back(static_cast<char>(word & 0xFF));
  PutVarint(&key, ZigZag(cx));
  PutVarint(&key, ZigZag(cy));
  return key;
}

Result<std::vector<PostingRecord>> PostingsOf(uint64_t id, const Lmd& lmd, const IndexOptions& options) {
  auto features = ToPoseFeatures(lmd, options);
  if (!features.ok()) return features.status();
  const int32_t cell0 = CellUnits(options);
  const bool wide = cell0 > 256;
  std::map<std::string, std::string> groups;
  for (const PoseFeature& f : *features) {
    const int32_t cx = FloorDiv(f.x, cell0), cy = FloorDiv(f.y, cell0);
    std::string& value = groups[PostingListPrefix(f.word, cx, cy)];
    for (int32_t v : {f.x - cx * cell0, f.y - cy * cell0}) {
      value.push_back(static_cast<char>(v & 0xFF));
      if (wide) value.push_back(static_cast<char>((v >> 8) & 0xFF));
    }
  }
  std::vector<PostingRecord> out;
  out.reserve(groups.size());
  for (auto& kv : groups) {
    PostingRecord r;
    r.key = kv.first;
    PutVarint(&r.key, id);
    r.value = std::move(kv.second);
    out.push_back(std::move(r));
  }
  return out;
}

Status LoadPostings(const std::vector<PostingRecord>& records, Index* index) {
  const int32_t cell0 = CellUnits(index->options());
  const size_t entry = cell0 > 256 ? 4 : 2;
  std::map<uint64_t, std::vector<PoseFeature>> maps;
  for (size_t r = 0; r < records.size(); ++r) {
    const PostingRecord& rec = records[r];
    const std::string where = "posting record " + std::to_string(r) + ": ";
    size_t at = 2;
    uint64_t zx = 0, zy = 0, id = 0;
    if (rec.key.size() < 5 || !GetVarint(rec.key, &at, &zx) || !GetVarint(rec.key, &at, &zy) ||
        !GetVarint(rec.key, &at, &id) || at != rec.key.size())
      return Status::Corruption(where + "malformed key");
    if (rec.value.empty() || rec.value.size() % entry != 0) return Status::Corruption(where + "bad value size");
    const uint32_t word = (static_cast<uint32_t>(static_cast<uint8_t>(rec.key[0])) << 8) |
                          static_cast<uint8_t>(rec.key[1]);
    const int64_t cx = UnZigZag(zx), cy = UnZigZag(zy);
    auto& features = maps[id];
    for (size_t v = 0; v < rec.value.size(); v += entry) {
      int64_t ox = static_cast<uint8_t>(rec.value[v]), oy = static_cast<uint8_t>(rec.value[v + entry / 2]);
      if (entry == 4) {
        ox |= static_cast<int64_t>(static_cast<uint8_t>(rec.value[v + 1])) << 8;
        oy |= static_cast<int64_t>(static_cast<uint8_t>(rec.value[v + 3])) << 8;
      }
      const int64_t x = cx * cell0 + ox, y = cy * cell0 + oy;
      if (ox >= cell0 || oy >= cell0 || x < -32768 || x > 32767 || y < -32768 || y > 32767)
        return Status::Corruption(where + "pose outside its key's cell");
      features.push_back({word, static_cast<int16_t>(x), static_cast<int16_t>(y)});
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
