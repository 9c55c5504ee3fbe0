// Posting records: the inverted file as plain key/value byte strings, so that
// a store (the server's RocksDB) can persist a map's postings next to its
// encoded Lmd in one write batch, and load the index back. No store here.
//
// One record per (appearance word, level-0 cell) group of a map:
//   key   = word u16 big-endian | zigzag varint cx | zigzag varint cy |
//           varint map id  (7 bytes for a cell within +-320 m and an id
//           < 2^21). Varints are prefix-free, so the records of one posting
//           list share the key prefix PostingListPrefix(word, cx, cy) and a
//           prefix scan reads that list;
//   value = per feature the pose word's offset inside its cell, (x - cx W,
//           y - cy W) in pose units: 1 byte each when W <= 256 units (the
//           default W = 5 m / 0.05 m = 100), else 2 bytes little-endian.
// About 9 bytes per feature. The records of a map are a function of its Lmd
// and IndexOptions (the same options must be used to load them); an index can
// equally be rebuilt from (id, Lmd) pairs with Index::Add.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/index/index.h"

namespace lmd {

struct PostingRecord {
  std::string key;
  std::string value;
};

// The records of map `id`, sorted by key. InvalidArgument as ToPoseFeatures.
Result<std::vector<PostingRecord>> PostingsOf(uint64_t id, const Lmd& lmd, const IndexOptions& options);

// Key prefix shared by the records of list (word, cx, cy).
std::string PostingListPrefix(uint32_t word, int32_t cx, int32_t cy);

// Adds to `index` every map found in `records` (any order, several maps).
// Corruption if a record is malformed or a pose lies outside its key's cell;
// AlreadyExists if a map is already indexed. Maps before the failing one
// stay added.
Status LoadPostings(const std::vector<PostingRecord>& records, Index* index);

// Bytes of the records (keys + values), what a store writes for a map.
size_t PostingBytes(const std::vector<PostingRecord>& records);

}  // namespace lmd
