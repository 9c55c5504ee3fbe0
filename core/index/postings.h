// Posting records: the inverted file as plain key/value byte strings, so that
// a store (the server's RocksDB) can persist a map's postings next to its
// encoded Lmd in one write batch, and load the index back. No store here.
//
// One record per (appearance word, level-0 cell) group of a map:
//   key   (14 bytes) = word u16 | cx + 32768 u16 | cy + 32768 u16 | map id u64,
//                      all big-endian, so keys sort by (word, cell, map) and a
//                      prefix scan of PostingListPrefix reads one posting list;
//   value (4 bytes per feature) = (x, y) pose words, int16 little-endian.
// The records of a map are a function of its Lmd and IndexOptions (the same
// options must be used to load them).
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

// 6-byte key prefix shared by the records of list (word, cx, cy).
std::string PostingListPrefix(uint32_t word, int32_t cx, int32_t cy);

// Adds to `index` every map found in `records` (any order, several maps).
// Corruption if a record is malformed or a pose lies outside its key's cell;
// AlreadyExists if a map is already indexed. Maps before the failing one
// stay added.
Status LoadPostings(const std::vector<PostingRecord>& records, Index* index);

// Bytes of the records (keys + values), what a store writes for a map.
size_t PostingBytes(const std::vector<PostingRecord>& records);

}  // namespace lmd
