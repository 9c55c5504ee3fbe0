// The first stage of the localisation pipeline: an index over the stored
// maps' place features (place_features.h) that turns a query's features into
// ranked pose hypotheses (map, quarter turn, translation) without scoring
// every stored map.
//
// Nearest neighbours: multi-table hashing of the 128-bit codes (locality-
// sensitive hashing for the angle between descriptors). Table t keys a
// feature by 16 of its code's bits (each bit in one table); a query feature
// looks up its bucket in every table for each of the 4 quarter turns (its
// code turned by RotateCode) and keeps the `neighbours` stored features of
// smallest Hamming distance. Buckets holding more than max_bucket features
// are skipped: they hold the descriptors of plain walls, which every map
// has and which tell no place from another.
//
// Voting (generalised Hough transform): each kept pair (query feature q,
// stored feature d of map m, quarter turn k) votes for the translation
// t = d - R(k) q between the compass frames, in cells of vote_cell_m per
// axis. A map's hypotheses are its best 2 x 2 blocks of cells; their votes
// rank the maps, their mean translation is the pose guess that verification
// refines. Features of one place vote for one translation; a look-alike
// place collects votes too, which is why hypotheses are verified, not trusted.
//
// Thread safety: const methods may run concurrently; Add / Remove need
// exclusive access (the caller's lock).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/place/place_features.h"
#include "core/status.h"
#include "core/types.h"

namespace lmd {

struct PlaceSearchOptions {
  // Stored features kept per query feature and quarter turn.
  size_t neighbours = 10;
  // Codes farther than this (of 128 bits) do not vote.
  int max_hamming = 40;
  // Buckets with more features than the larger of max_bucket and
  // max_bucket_share times the mean bucket are not read (0 = read all).
  size_t max_bucket = 2000;
  double max_bucket_share = 16.0;
  double vote_cell_m = 1.0;  // m, translation cell
  // Each query feature casts one vote in all, shared among its kept pairs
  // (all 4 turns) in proportion to exp(-(distance - nearest) / temperature),
  // distances in bits: a distinctive feature (one close match) votes for its
  // match, a plain one (many alike) spreads its vote thin. 0: every kept pair
  // votes 1.
  double vote_temperature = 0.0;
  size_t max_hypotheses = 160;     // returned, best first
  // Distinct translations or turns per map. Along a corridor the votes of
  // one map spread over every stretch that looks alike, and the right one
  // need not be its strongest peak; each peak is a guess that verification
  // searches +-1 m around, so more peaks cover more of the corridor. On the
  // tuning logs (aces, fr079, intel, orebro; every map queried, 10 m
  // neighbours excluded, in process), 2 -> 8 (with max_hypotheses 40 -> 160,
  // so that as many maps are verified): place@1 .649/.892/.977/.600 ->
  // .701/.904/.979/.700 for 7-37 % more time per query; of aces' and
  // orebro's misses where a right map at its true pose would have won,
  // 80 -> 57 remain. 12 gained no more on three of the four.
  size_t hypotheses_per_map = 8;
  // Stored features read per query, at most (0 = no bound; with `only`, the
  // other maps' features passed over count too, as reading them is the
  // cost): the query's features are read rarest first (fewest stored
  // features in their buckets) and none is started once this many have been
  // read. The
  // search's cost grows with how crowded the query's buckets are: by a place
  // seen by hundreds of maps (a fleet passing one spot every second), or by
  // codes common all over a large site. Rare codes are the telling ones in
  // both cases. Measured: frcampus (held out, 1,631 maps) compares 767k per
  // query unbounded; bounded, place@1 0.760 -> 0.755 and search 8.0 -> 4.3 ms
  // (reading in any fixed order instead: 0.636); a dense fleet store of
  // 4,295 maps search 9.4 -> 2.0 ms, place .963 -> .972.
  size_t max_candidates = 100000;
  // ... but at least this many per stored map (0: the fixed bound only):
  // buckets fill in proportion to a collection's maps, so a fixed bound
  // reads an ever smaller share of the query's features. lmd-bench places,
  // 100k simulated maps: the fixed bound finds the place for 0.85 of the
  // queries at 24.8 ms median Localize CPU, 4 per map (400k) 0.96 at 34.8
  // ms. Below 25k maps the fixed bound decides (every real log here).
  size_t min_candidates_per_map = 4;
  // When set, only these maps are compared (a prior query's maps near its
  // prior): the others' stored features are passed over unread.
  const std::vector<uint64_t>* only = nullptr;
  // Only maps anchored in the collection's frame (a site map). Honoured by
  // the MapSource implementations, which know the anchors; PlaceIndex
  // itself does not read it.
  bool anchored_only = false;
};

// Pose hypothesis for one stored map: db compass = R(k * 90 deg) query compass + translation.
struct PlaceHypothesis {
  uint64_t map_id = 0;
  double db_heading = 0.0;  // rad, the stored map's compass heading
  int quarter_turns = 0;  // k in 0..3
  Point2 translation;     // m, in the db map's compass frame
  double votes = 0.0;
};

// The hypothesis as a pose of the query's own frame in the db map's own
// frame, given the query's compass heading.
Pose2 HypothesisPose(const PlaceHypothesis& hypothesis, double query_heading);

// What one search did (cost measures).
struct PlaceSearchStats {
  size_t lookups = 0;        // bucket reads
  size_t features_used = 0;  // query features looked up (max_candidates may stop earlier)
  size_t candidates = 0;  // stored features read (compared, or passed over as not among `only`)
  size_t votes = 0;
  size_t maps_voted = 0;  // maps that received a vote
};

class PlaceIndex {
 public:
  static constexpr int kTables = 8;
  static constexpr int kKeyBits = 16;
  static constexpr size_t kMaxFeaturesPerMap = 1023;
  static constexpr uint32_t kMaxMaps = (1u << 22) - 1;

  PlaceIndex();

  // Indexes `features` under `id`. AlreadyExists if `id` is stored;
  // InvalidArgument beyond kMaxFeaturesPerMap features; ResourceExhausted
  // beyond kMaxMaps maps. Nothing changes on error.
  Status Add(uint64_t id, PlaceFeatures features);
  // Removes the map; false if `id` is not stored.
  bool Remove(uint64_t id);

  // Ranked hypotheses (most votes first; ties by the maps' content, then
  // the smaller map id, so that the order maps were added in does not
  // matter) for `query`
  // (features with their unturned codes). Maps for which `excluded(id)` is
  // true are never returned. `stats` (optional) receives the work done.
  std::vector<PlaceHypothesis> Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                      const std::function<bool(uint64_t)>& excluded = {},
                                      PlaceSearchStats* stats = nullptr) const;

  // The stored features of `id` (a copy), or nothing.
  std::optional<PlaceFeatures> Features(uint64_t id) const;
  // The compass heading of `id`'s features, or nothing.
  std::optional<double> Heading(uint64_t id) const;
  size_t size() const { return id_to_slot_.size(); }
  size_t FeatureCount() const { return feature_count_; }
  size_t MemoryBytes() const;

 private:
  static uint32_t Key(const PlaceCode& code, int table);
  // Handle of a map's k-th feature: its place in the arena below.
  uint32_t HandleOf(uint32_t slot, size_t k) const {
    return slot_chunks_[slot][k / kChunk] * kChunk + static_cast<uint32_t>(k % kChunk);
  }

  std::vector<std::vector<uint32_t>> buckets_;  // kTables * 2^kKeyBits lists of handles
  // Every stored feature's code and position, in chunks of kChunk (a map's
  // features fill chunks of its own), so that a search reads a candidate's
  // code with one memory access, not two dependent ones: at 100k maps that
  // access is most of a search (docs/places_bench.md).
  static constexpr uint32_t kChunk = 64;
  static constexpr uint32_t kNoSlot = ~0u;
  std::vector<PlaceCode> codes_;       // by handle
  std::vector<float> xs_, ys_;         // by handle, compass frame
  std::vector<uint32_t> chunk_slot_;   // the slot owning each chunk, or kNoSlot
  std::vector<uint32_t> free_chunks_;
  std::vector<std::vector<uint32_t>> slot_chunks_;
  std::unordered_map<uint64_t, uint32_t> id_to_slot_;
  std::vector<uint64_t> slot_id_;
  std::vector<uint64_t> slot_hash_;  // of each map's features: orders equal votes by content, not insertion
  std::vector<double> slot_heading_;
  std::vector<uint32_t> slot_count_;  // features per slot
  std::vector<uint32_t> free_slots_;
  size_t feature_count_ = 0;
};

}  // namespace lmd
