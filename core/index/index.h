// Inverted file over local map descriptors (DESIGN.md §1 "Index.Retrieve").
//
// Posting key = (appearance word, level-0 pyramid cell of the feature's pose
// word in the db map's planned frame); a posting = 4 bytes: the map's slot
// (24 bits) and the finest pyramid cell (level L) inside the key's cell
// (8 bits). Exact poses live once per map, for exact scoring.
// Why: the kernel (pyramid_kernel.h) only counts a query feature against db
// features of the same word in the same level-0 cell as the shifted query
// feature, and the shift is at most max_offset per axis, so for orientation o
// a query feature can only gain from the lists keyed (its word, a level-0
// cell meeting the box R(o) q +- max_offset). With the paper's B = 10 bits there
// are only 1024 words, so word-only lists would hold ~every map; the pose cell lets a
// query skip the lists of cells its features cannot reach. How much that and
// the bound below save depends on the data: features spread over many cells
// and evenly used words prune well; features packed near the planned origin
// and a few words on most features (a "wall" word) make every map a close
// candidate. `lmd-bench index` reports both (postings read, maps scored).
//
// Retrieval is exact by default. Pass 1 reads, once per distinct query word,
// the lists of the level-0 cells that meet any of that word's boxes (4 orientations x
// the query features with the word) and gives every map an upper bound of its
// raw K per orientation. A query feature counts in K through the one level-0
// cell its shifted position falls in, at the finest level l where a same-word
// db feature shares its cell, adding w_0 + ... + w_l; such a db feature lies
// in a cell meeting the feature's box (the shift keeps it in the box). So a
// map's run of postings in one list can add at most the smallest of: the sum
// over its postings of the gains of the terms whose boxes meet the posting's
// finest cell; the sum over the list's terms of their best gain in the cell;
// and (w_0 + ... + w_L) * min(query features of the word, postings in the
// run), since I^l of one cell is at most that minimum. The bound is
// min(sum over lists, min(|q|, |d|)), normalised like K.
// Pass 2 scores maps exactly, best bound first, with the same ScoreLmdMap as
// the exhaustive scorer, until the next bound is below the k-th best score.
// Scores, orientations, offsets and ranks are therefore identical to
// RetrieveExhaustive's (tests/core/index_test.cc checks it on random data),
// unless RetrieveOptions::max_maps_scored stops pass 2 earlier or
// RetrieveOptions::bound_skip_postings_per_map leaves the lists of the most
// common words out of pass 1 (their most possible gain is then added to every
// bound, so scored maps keep exact scores but a map reached only through
// those words is no candidate, unless fewer than top_k maps are reached at
// all: then every list is read).
// The gains are tabulated per list and finest cell, so pass 1 costs one
// table look-up and a few adds per posting. Lists are kept sorted by slot
// and pass 1 reads them one block of slots at a time, so that the per-map
// accumulators of a block stay in cache (at 100k maps a query reads about a
// quarter of all postings, spread over every map).
// Hits are ordered by score (descending), then map id (ascending); maps
// scoring 0 are never returned.
//
// Thread safety: const methods may run concurrently; Add / Remove / Load need
// exclusive access (the caller's lock).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "core/index/pyramid_kernel.h"
#include "core/index/retrieve_options.h"
#include "core/status.h"
#include "core/types.h"

namespace lmd {

// What one Retrieve did (for benchmarks and tuning).
struct RetrieveStats {
  size_t lists_read = 0;     // posting lists scanned
  size_t postings_read = 0;  // postings scanned
  size_t maps_touched = 0;   // maps with at least one posting read (candidates)
  size_t maps_scored = 0;    // candidates scored exactly before the bound stopped
};

class Index {
 public:
  // The most maps one index holds (a posting's slot has 24 bits).
  static constexpr uint32_t kMaxMaps = (1u << 24) - 1;

  // InvalidArgument if the options are invalid (retrieve_options.h).
  static Result<Index> Create(const IndexOptions& options = {});

  // Indexes `lmd` under `id`. AlreadyExists if `id` is stored; InvalidArgument
  // if a feature cannot be a pose word (ToPoseFeatures); ResourceExhausted
  // beyond 2^24 - 1 maps. Nothing changes on error.
  Status Add(uint64_t id, const Lmd& lmd);
  // Same from pose features already sorted by (word, x, y) (e.g. decoded
  // posting records).
  Status AddPoseFeatures(uint64_t id, std::vector<PoseFeature> features);

  // Removes the map and every posting of it; false if `id` is not stored.
  bool Remove(uint64_t id);

  // Top options.top_k maps for `query`, ranked (MapHit::rank = 0 is best).
  // InvalidArgument for bad options or a query feature that is not a pose word.
  // `stats`, when not null, receives what the query read.
  Result<std::vector<MapHit>> Retrieve(const Lmd& query, const RetrieveOptions& options = {},
                                       RetrieveStats* stats = nullptr) const;

  size_t size() const { return id_to_slot_.size(); }
  bool Contains(uint64_t id) const { return id_to_slot_.count(id) != 0; }
  const IndexOptions& options() const { return options_; }

  // Words holding more than max_share of all postings (sorted); empty when
  // max_share >= 1. Retrieve and RetrieveExhaustive drop them from queries.
  std::vector<uint32_t> StopWords(double max_share) const;

  // Total postings (one per indexed feature), and the postings of `id`
  // found by scanning every list (for tests; slow).
  size_t PostingCount() const { return posting_count_; }
  size_t CountPostingsOfMap(uint64_t id) const;
  // Approximate heap bytes held (postings, lists, per-map features, id maps).
  size_t MemoryBytes() const;

  // Calls fn(id, features sorted by (word, x, y)) for every stored map, in
  // slot order (the exhaustive scorer walks maps with it).
  void ForEachMap(const std::function<void(uint64_t, const std::vector<PoseFeature>&)>& fn) const;

  // Posting key of a pose feature: word and level-0 cell (cx, cy).
  static uint64_t PostingKey(uint32_t word, int32_t cx, int32_t cy);

 private:
  explicit Index(const IndexOptions& options);
  std::vector<MapHit> RetrieveLmd(const PreparedLmdQuery& q, const RetrieveOptions& options,
                                  RetrieveStats* stats) const;
  std::vector<MapHit> RetrieveBow(const PreparedLmdQuery& q, size_t top_k, RetrieveStats* stats) const;

  struct Posting {
    uint32_t packed;  // slot << 8 | finest cell index (sx * 2^L + sy)
    uint32_t slot() const { return packed >> 8; }
    uint32_t sub() const { return packed & 0xFF; }
  };

  IndexOptions options_;
  int32_t cell0_ = 100;  // pose units
  std::unordered_map<uint64_t, std::vector<Posting>> lists_;  // PostingKey -> postings
  // A word's lists: Retrieve walks them instead of looking up every cell a
  // query box could meet (the lists_ nodes, hence the pointers, never move).
  struct WordList {
    uint64_t key;
    const std::vector<Posting>* postings;
  };
  std::unordered_map<uint32_t, std::vector<WordList>> word_lists_;
  std::unordered_map<uint32_t, size_t> word_postings_;              // word -> postings
  std::unordered_map<uint64_t, uint32_t> id_to_slot_;
  std::vector<uint64_t> slot_id_;                    // valid where slot_used_
  std::vector<uint8_t> slot_used_;
  std::vector<std::vector<PoseFeature>> slot_features_;
  std::vector<uint32_t> free_slots_;
  size_t posting_count_ = 0;
};

}  // namespace lmd
