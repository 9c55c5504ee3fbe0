#include "core/place/place_index.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <tuple>

#include "core/util/fnv1a.h"

namespace lmd {
namespace {

// Which code bits key each table: a fixed shuffle of the 128 bits, 16 per
// table, so that no table sees only one projection group.
const std::array<std::array<uint8_t, PlaceIndex::kKeyBits>, PlaceIndex::kTables>& TableBits() {
  static const auto bits = [] {
    std::array<uint8_t, 128> order;
    for (int i = 0; i < 128; ++i) order[i] = static_cast<uint8_t>(i);
    uint64_t state = 0x9e3779b97f4a7c15ULL;
    for (int i = 127; i > 0; --i) {  // Fisher-Yates with a fixed xorshift stream
      state ^= state << 13, state ^= state >> 7, state ^= state << 17;
      std::swap(order[i], order[state % static_cast<uint64_t>(i + 1)]);
    }
    std::array<std::array<uint8_t, PlaceIndex::kKeyBits>, PlaceIndex::kTables> t;
    for (int table = 0; table < PlaceIndex::kTables; ++table) {
      for (int b = 0; b < PlaceIndex::kKeyBits; ++b) t[table][b] = order[table * PlaceIndex::kKeyBits + b];
    }
    return t;
  }();
  return bits;
}

// Memory fetched this many items ahead of its use: stored codes ahead of
// their comparison (Search), bucket lists ahead of their write (Add).
constexpr size_t kPrefetch = 8;

// Open-addressing accumulator of votes per (slot, turn, cell x, cell y).
class VoteTable {
 public:
  struct Cell {
    uint64_t key = kEmpty;
    float weight = 0, sum_x = 0, sum_y = 0;
  };
  static constexpr uint64_t kEmpty = ~uint64_t{0};
  static constexpr int kCellBits = 20;
  static constexpr int32_t kCellLimit = 1 << (kCellBits - 1);

  explicit VoteTable(size_t expected) {
    size_t n = 64;
    while (n < 2 * expected) n <<= 1;
    cells_.resize(n);
    mask_ = n - 1;
  }
  static uint64_t KeyOf(uint32_t slot, int turn, int32_t cx, int32_t cy) {
    const uint64_t ux = static_cast<uint64_t>(cx + kCellLimit) & ((1u << kCellBits) - 1);
    const uint64_t uy = static_cast<uint64_t>(cy + kCellLimit) & ((1u << kCellBits) - 1);
    return static_cast<uint64_t>(slot) << 42 | static_cast<uint64_t>(turn) << 40 | ux << kCellBits | uy;
  }
  void Add(uint64_t key, float w, float tx, float ty) {
    Cell& c = Find(key);
    if (c.key == kEmpty) {
      c.key = key;
      ++size_;
    }
    c.weight += w, c.sum_x += w * tx, c.sum_y += w * ty;
  }
  const Cell* Get(uint64_t key) const {
    for (size_t i = Hash(key) & mask_;; i = (i + 1) & mask_) {
      if (cells_[i].key == key) return &cells_[i];
      if (cells_[i].key == kEmpty) return nullptr;
    }
  }
  const std::vector<Cell>& cells() const { return cells_; }
  size_t size() const { return size_; }

 private:
  static size_t Hash(uint64_t k) { return static_cast<size_t>((k * 0x9e3779b97f4a7c15ULL) >> 17); }
  Cell& Find(uint64_t key) {
    for (size_t i = Hash(key) & mask_;; i = (i + 1) & mask_) {
      if (cells_[i].key == key || cells_[i].key == kEmpty) return cells_[i];
    }
  }
  std::vector<Cell> cells_;
  size_t mask_ = 0;
  size_t size_ = 0;
};

}  // namespace

Pose2 HypothesisPose(const PlaceHypothesis& h, double query_heading) {
  const double c = std::cos(h.db_heading), s = std::sin(h.db_heading);
  const double theta = std::remainder(h.db_heading + h.quarter_turns * (M_PI / 2) - query_heading, 2 * M_PI);
  return {c * h.translation.x - s * h.translation.y, s * h.translation.x + c * h.translation.y, theta};
}

PlaceIndex::PlaceIndex() : buckets_(static_cast<size_t>(kTables) << kKeyBits) {}

uint32_t PlaceIndex::Key(const PlaceCode& code, int table) {
  uint32_t key = 0;
  const auto& bits = TableBits()[table];
  for (int b = 0; b < kKeyBits; ++b) key |= static_cast<uint32_t>((code[bits[b] >> 6] >> (bits[b] & 63)) & 1) << b;
  return key;
}

Status PlaceIndex::Add(uint64_t id, PlaceFeatures features) {
  if (id_to_slot_.count(id) != 0) return Status::AlreadyExists("map " + std::to_string(id) + " is already indexed");
  if (features.features.size() > kMaxFeaturesPerMap) {
    return Status::InvalidArgument(std::to_string(features.features.size()) + " place features exceed " +
                                   std::to_string(kMaxFeaturesPerMap) + " per map");
  }
  uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    if (slot_id_.size() >= kMaxMaps) return Status::ResourceExhausted("the place index holds its most maps");
    slot = static_cast<uint32_t>(slot_id_.size());
    slot_id_.push_back(0);
    slot_hash_.push_back(0);
    slot_heading_.push_back(0.0);
    slot_count_.push_back(0);
    slot_chunks_.emplace_back();
  }
  std::vector<uint32_t>& chunks = slot_chunks_[slot];
  chunks.clear();
  while (chunks.size() * kChunk < features.features.size()) {
    uint32_t chunk;
    if (!free_chunks_.empty()) {
      chunk = free_chunks_.back();
      free_chunks_.pop_back();
    } else {
      chunk = static_cast<uint32_t>(chunk_slot_.size());
      chunk_slot_.push_back(kNoSlot);
      codes_.resize(codes_.size() + kChunk);
      xs_.resize(xs_.size() + kChunk), ys_.resize(ys_.size() + kChunk);
    }
    chunk_slot_[chunk] = slot;
    chunks.push_back(chunk);
  }
  std::vector<size_t> buckets;  // of each feature's handle, kTables in a row
  buckets.reserve(features.features.size() * kTables);
  for (size_t i = 0; i < features.features.size(); ++i) {
    const PlaceFeature& f = features.features[i];
    const uint32_t handle = HandleOf(slot, i);
    codes_[handle] = f.code, xs_[handle] = f.x, ys_[handle] = f.y;
    for (int t = 0; t < kTables; ++t) buckets.push_back((static_cast<size_t>(t) << kKeyBits) | Key(f.code, t));
  }
  // The buckets lie anywhere in kTables x 2^kKeyBits lists: each list's
  // header, then its end, fetched ahead of the write (a fifth of a fleet's
  // insert waited on those two cache misses, lmd-bench load --mode fleet).
  for (size_t k = 0; k < buckets.size(); ++k) {
    if (k + 2 * kPrefetch < buckets.size()) __builtin_prefetch(&buckets_[buckets[k + 2 * kPrefetch]]);
    if (k + kPrefetch < buckets.size()) {
      const std::vector<uint32_t>& ahead = buckets_[buckets[k + kPrefetch]];
      __builtin_prefetch(ahead.data() + ahead.size(), 1);
    }
    buckets_[buckets[k]].push_back(HandleOf(slot, k / kTables));
  }
  feature_count_ += features.features.size();
  uint64_t hash = kFnv1aOffset;  // over the codes and positions, a word at a time
  for (const PlaceFeature& f : features.features) {
    uint32_t x, y;
    std::memcpy(&x, &f.x, 4), std::memcpy(&y, &f.y, 4);
    for (uint64_t word : {f.code[0], f.code[1], uint64_t{x} << 32 | y}) hash = Fnv1aMix(hash, word);
  }
  slot_hash_[slot] = hash;
  slot_id_[slot] = id;
  slot_heading_[slot] = features.heading;
  slot_count_[slot] = static_cast<uint32_t>(features.features.size());
  id_to_slot_[id] = slot;
  return Status::Ok();
}

bool PlaceIndex::Remove(uint64_t id) {
  const auto it = id_to_slot_.find(id);
  if (it == id_to_slot_.end()) return false;
  const uint32_t slot = it->second;
  for (size_t i = 0; i < slot_count_[slot]; ++i) {
    const uint32_t handle = HandleOf(slot, i);
    for (int t = 0; t < kTables; ++t) {
      std::vector<uint32_t>& bucket = buckets_[(static_cast<size_t>(t) << kKeyBits) | Key(codes_[handle], t)];
      const auto at = std::find(bucket.begin(), bucket.end(), handle);
      if (at != bucket.end()) {
        *at = bucket.back();
        bucket.pop_back();
      }
    }
  }
  feature_count_ -= slot_count_[slot];
  slot_count_[slot] = 0;
  for (uint32_t chunk : slot_chunks_[slot]) chunk_slot_[chunk] = kNoSlot, free_chunks_.push_back(chunk);
  slot_chunks_[slot].clear();
  free_slots_.push_back(slot);
  id_to_slot_.erase(it);
  return true;
}

std::optional<PlaceFeatures> PlaceIndex::Features(uint64_t id) const {
  const auto it = id_to_slot_.find(id);
  if (it == id_to_slot_.end()) return std::nullopt;
  const uint32_t slot = it->second;
  PlaceFeatures out;
  out.heading = slot_heading_[slot];
  for (size_t i = 0; i < slot_count_[slot]; ++i) {
    const uint32_t handle = HandleOf(slot, i);
    out.features.push_back({xs_[handle], ys_[handle], codes_[handle]});
  }
  return out;
}

std::optional<double> PlaceIndex::Heading(uint64_t id) const {
  const auto it = id_to_slot_.find(id);
  if (it == id_to_slot_.end()) return std::nullopt;
  return slot_heading_[it->second];
}

size_t PlaceIndex::MemoryBytes() const {
  size_t bytes = buckets_.size() * sizeof(std::vector<uint32_t>);
  for (const auto& b : buckets_) bytes += b.capacity() * sizeof(uint32_t);
  bytes += slot_heading_.capacity() * 8 + slot_count_.capacity() * 4;
  for (const auto& chunks : slot_chunks_) bytes += sizeof(chunks) + chunks.capacity() * 4;
  bytes += id_to_slot_.size() * 32 + slot_id_.capacity() * 8;
  bytes += codes_.capacity() * sizeof(PlaceCode) + (xs_.capacity() + ys_.capacity()) * sizeof(float) +
           chunk_slot_.capacity() * 4;
  return bytes;
}

std::vector<PlaceHypothesis> PlaceIndex::Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                                const std::function<bool(uint64_t)>& excluded,
                                                PlaceSearchStats* stats) const {
  PlaceSearchStats work;
  const size_t k_nearest = std::max<size_t>(1, options.neighbours);
  // Overfull buckets: beyond an absolute size, or many times the mean (the
  // mean grows with the collection; an absolute cap alone would end up
  // skipping every bucket of a large one).
  const double mean_bucket = static_cast<double>(feature_count_) / static_cast<double>(size_t{1} << kKeyBits);
  const size_t max_bucket = options.max_bucket == 0 ? 0
                                : std::max(options.max_bucket, static_cast<size_t>(options.max_bucket_share * mean_bucket));
  const double cell = options.vote_cell_m > 0 ? options.vote_cell_m : 1.0;
  VoteTable votes(query.features.size() * 4 * k_nearest);
  // Ties of distance are broken by the stored feature's code, then by its
  // map's content and its place in the map, so that answers depend on the
  // maps' content, not on the order they were added in.
  struct Near {
    int distance;
    uint64_t code, map_hash;
    uint32_t handle;
    bool operator<(const Near& o) const {
      return std::tie(distance, code, map_hash, handle) < std::tie(o.distance, o.code, o.map_hash, o.handle);
    }
  };
  std::vector<Near> nearest;
  nearest.reserve(k_nearest + 1);
  struct Pair {
    int distance;
    uint32_t handle;
    int turn;
  };
  std::vector<Pair> pairs;
  std::vector<char> allowed;  // by slot, when options.only is set
  if (options.only != nullptr) {
    allowed.assign(slot_id_.size(), 0);
    for (uint64_t id : *options.only) {
      const auto it = id_to_slot_.find(id);
      if (it != id_to_slot_.end()) allowed[it->second] = 1;
    }
  }
  // Rarest features first (fewest stored features in their buckets, over
  // the four turns): they are the cheapest to look up and, like rare words
  // in a text index, the most telling; a bound on the work then drops the
  // common ones, which cost most and tell least.
  const size_t n_query = query.features.size();
  constexpr size_t kBucketsPerFeature = 4 * kTables;  // every turn in every table
  std::vector<uint32_t> bucket_of(n_query * kBucketsPerFeature);  // kept for the search below
  std::vector<std::pair<size_t, size_t>> order;  // (stored features in its buckets, feature)
  order.reserve(n_query);
  for (size_t i = 0; i < n_query; ++i) {
    size_t crowd = 0;
    for (int turn = 0; turn < 4; ++turn) {
      const PlaceCode code = RotateCode(query.features[i].code, turn);
      for (int t = 0; t < kTables; ++t) {
        const uint32_t b = (static_cast<uint32_t>(t) << kKeyBits) | Key(code, t);
        bucket_of[i * kBucketsPerFeature + turn * kTables + t] = b;
        const size_t size = buckets_[b].size();
        if (max_bucket == 0 || size <= max_bucket) crowd += size;
      }
    }
    order.push_back({crowd, i});
  }
  const size_t bound =
      options.max_candidates == 0 ? 0 : std::max(options.max_candidates, options.min_candidates_per_map * size());
  if (bound > 0) std::sort(order.begin(), order.end());
  for (const auto& [crowd, index] : order) {
    if (bound > 0 && work.candidates >= bound) break;
    const PlaceFeature& qf = query.features[index];
    ++work.features_used;
    pairs.clear();
    for (int turn = 0; turn < 4; ++turn) {
      const PlaceCode code = RotateCode(qf.code, turn);
      nearest.clear();
      int worst = options.max_hamming;  // admits distance <= worst while not full
      for (int t = 0; t < kTables; ++t) {
        const std::vector<uint32_t>& bucket = buckets_[bucket_of[index * kBucketsPerFeature + turn * kTables + t]];
        ++work.lookups;
        if (max_bucket > 0 && bucket.size() > max_bucket) continue;
        work.candidates += bucket.size();
        const size_t count = bucket.size();
        for (size_t b = 0; b < count; ++b) {
          if (b + kPrefetch < count) __builtin_prefetch(&codes_[bucket[b + kPrefetch]]);
          const uint32_t handle = bucket[b];
          if (!allowed.empty() && !allowed[chunk_slot_[handle / kChunk]]) continue;
          const PlaceCode& stored = codes_[handle];
          const int d = HammingDistance(code, stored);
          if (d > worst) continue;
          const Near near{d, stored[0], slot_hash_[chunk_slot_[handle / kChunk]] ^ handle % kChunk, handle};
          if (nearest.size() == k_nearest && !(near < nearest.back())) continue;
          bool seen = false;  // the same feature from another table
          for (const Near& n : nearest) seen = seen || n.handle == handle;
          if (seen) continue;
          nearest.insert(std::upper_bound(nearest.begin(), nearest.end(), near), near);
          if (nearest.size() > k_nearest) nearest.pop_back();
          if (nearest.size() == k_nearest) worst = nearest.back().distance;
        }
      }
      for (const Near& n : nearest) pairs.push_back({n.distance, n.handle, turn});
    }
    if (pairs.empty()) continue;
    int closest = pairs[0].distance;
    for (const Pair& p : pairs) closest = std::min(closest, p.distance);
    double total = 0.0;
    if (options.vote_temperature > 0) {
      for (const Pair& p : pairs) total += std::exp(-(p.distance - closest) / options.vote_temperature);
    }
    for (const Pair& p : pairs) {
      const float w = options.vote_temperature > 0
                          ? static_cast<float>(std::exp(-(p.distance - closest) / options.vote_temperature) / total)
                          : 1.0f;
      const Point2 turned = TurnQuarters({qf.x, qf.y}, p.turn);
      const uint32_t slot = chunk_slot_[p.handle / kChunk];
      const double tx = xs_[p.handle] - turned.x, ty = ys_[p.handle] - turned.y;
      const double cx = std::floor(tx / cell), cy = std::floor(ty / cell);
      if (std::abs(cx) >= VoteTable::kCellLimit - 1 || std::abs(cy) >= VoteTable::kCellLimit - 1) continue;
      votes.Add(VoteTable::KeyOf(slot, p.turn, static_cast<int32_t>(cx), static_cast<int32_t>(cy)), w,
                static_cast<float>(tx), static_cast<float>(ty));
      ++work.votes;
    }
  }

  // Every cell's 2 x 2 block (the cell and its +x, +y, +xy neighbours).
  struct Block {
    uint32_t slot;
    int turn;
    int32_t cx, cy;
    float weight, sum_x, sum_y;
  };
  std::vector<Block> blocks;
  blocks.reserve(votes.size());
  std::vector<uint32_t> voted;
  constexpr uint64_t kCellMask = (1u << VoteTable::kCellBits) - 1;
  for (const VoteTable::Cell& c : votes.cells()) {
    if (c.key == VoteTable::kEmpty) continue;
    const uint32_t slot = static_cast<uint32_t>(c.key >> 42);
    const int turn = static_cast<int>((c.key >> 40) & 3);
    const int32_t cx = static_cast<int32_t>((c.key >> VoteTable::kCellBits) & kCellMask) - VoteTable::kCellLimit;
    const int32_t cy = static_cast<int32_t>(c.key & kCellMask) - VoteTable::kCellLimit;
    Block b{slot, turn, cx, cy, 0, 0, 0};
    for (int dx = 0; dx < 2; ++dx) {
      for (int dy = 0; dy < 2; ++dy) {
        const VoteTable::Cell* n = dx == 0 && dy == 0 ? &c : votes.Get(VoteTable::KeyOf(slot, turn, cx + dx, cy + dy));
        if (n == nullptr) continue;
        b.weight += n->weight, b.sum_x += n->sum_x, b.sum_y += n->sum_y;
      }
    }
    blocks.push_back(b);
    voted.push_back(slot);
  }
  std::sort(voted.begin(), voted.end());
  work.maps_voted = static_cast<size_t>(std::unique(voted.begin(), voted.end()) - voted.begin());
  std::sort(blocks.begin(), blocks.end(), [&](const Block& a, const Block& b) {
    if (a.weight != b.weight) return a.weight > b.weight;
    if (slot_hash_[a.slot] != slot_hash_[b.slot]) return slot_hash_[a.slot] < slot_hash_[b.slot];
    if (slot_id_[a.slot] != slot_id_[b.slot]) return slot_id_[a.slot] < slot_id_[b.slot];
    return std::tie(a.turn, a.cx, a.cy) < std::tie(b.turn, b.cx, b.cy);
  });
  // Best blocks first; per map at most hypotheses_per_map blocks that do not
  // overlap one taken (another turn, or 2 cells apart on an axis).
  std::unordered_map<uint32_t, std::vector<const Block*>> taken;
  std::vector<PlaceHypothesis> out;
  const size_t per_map = std::max<size_t>(1, options.hypotheses_per_map);
  for (const Block& b : blocks) {
    if (out.size() >= options.max_hypotheses) break;
    std::vector<const Block*>& mine = taken[b.slot];
    if (mine.size() >= per_map) continue;
    bool overlaps = false;
    for (const Block* o : mine) overlaps = overlaps || (o->turn == b.turn && std::abs(o->cx - b.cx) < 2 && std::abs(o->cy - b.cy) < 2);
    if (overlaps) continue;
    const uint64_t id = slot_id_[b.slot];
    if (mine.empty() && excluded && excluded(id)) {
      mine.assign(per_map, &b);  // never again
      continue;
    }
    mine.push_back(&b);
    out.push_back({id, slot_heading_[b.slot], b.turn, {b.sum_x / b.weight, b.sum_y / b.weight}, b.weight});
  }
  if (stats != nullptr) *stats = work;
  return out;
}

}  // namespace lmd
