// Options and results of map retrieval (DESIGN.md §1 "Index.Retrieve"), shared
// by the inverted file (index.h) and the exhaustive scorer (exhaustive.h).
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/status.h"
#include "core/types.h"

namespace lmd {

// Which similarity ranks the maps.
enum class Method {
  kLmd,  // spatial pyramid match kernel over (appearance word, pose cell),
         // 4 orientation hypotheses, offset = mode of pose-word differences.
         // LMD+CoG and LMD+CoR differ only by the planner used upstream.
  kBow,  // baseline: histogram intersection of appearance-word counts, no pose.
};

// How the raw kernel value is divided by the map sizes (|q|, |d| = feature
// counts). Raw intersections grow with map size and favour big maps.
enum class Normalization {
  kNone,  // raw K (paper's formula as printed)
  kMin,   // K / min(|q|, |d|)
  kSqrt,  // K / sqrt(|q| |d|)  (default: symmetric, in [0, 1], cosine-like)
};

// Fixed when an index is created: they define the pose words and the
// posting keys, so they cannot change per query.
struct IndexOptions {
  double pose_quantum_m = 0.05;  // m; pose word = round(position / quantum).
  double pyramid_cell_m = 5.0;   // W, m: cell width at level 0 (paper: 5 m).
  int pyramid_levels = 2;        // L in [0, 4]: levels 0..L, cell width W * 2^-l (paper: 2).
};

// Per query.
struct RetrieveOptions {
  size_t top_k = 10;                 // hits returned (>= 1)
  Method method = Method::kLmd;
  // Largest |offset| (per axis, m) between the planned frames of two maps of
  // the same place. Only word matches whose pose difference (db minus rotated
  // query) lies in [-max_offset_m, max_offset_m]^2 vote for the offset, so the
  // offset is inside that box too. Planned viewpoints of one place are close
  // (median error target < 0.5 m), which is what keeps queries local.
  // 1 m: on simulated re-observed maps (lmd-bench index, 1000 maps, 50
  // queries) the re-observed map was in the top 10 for 37 / 42 / 45 / 45
  // queries with 0.25 / 0.5 / 1 / 2 m, and a wider box costs time (each query
  // feature meets more db features). A small box also tightens the inverted
  // file's bound (index.h).
  double max_offset_m = 1.0;
  double offset_bin_m = 0.5;         // m; bin of the pose-difference histogram
  Normalization normalization = Normalization::kSqrt;
  // Stop list (Sivic & Zisserman's "Video Google"): appearance words that hold
  // more than this fraction of all indexed features are dropped from the
  // query (|q| counts the remaining features; |d| stays the db map's size).
  // A word on most features (e.g. a straight-wall word) matches every map,
  // adds little evidence and defeats any inverted file. In (0, 1];
  // 1 = no stop list (the paper's kernel, default).
  double max_word_share = 1.0;
  // Inverted file only: once top_k maps have a score, stop after this many
  // maps scored exactly (best bounds first) and rank those; 0 = no limit,
  // which makes retrieval exact (index.h). A limit trades exactness for time
  // in stores that hold many maps of every place, where the bound prunes little.
  size_t max_maps_scored = 0;
  // Inverted file only, approximate: the first pass does not read the lists
  // of words with more than this many postings per stored map; instead every
  // candidate's bound gets the most those words' query features could add.
  // Such words (a straight-wall context) occur in nearly every map: their
  // lists are most of what a query reads, yet they lift all bounds alike.
  // Exact scoring still counts them; a map that no other query word reaches
  // is no candidate. When fewer than top_k maps are reached, every list is
  // read after all. 0 = read every list.
  double bound_skip_postings_per_map = 0.0;
};

// One retrieved map. db planned position ~= R(orientation * 90 deg) * query
// planned position + offset.
struct MapHit {
  uint64_t map_id = 0;
  double score = 0.0;     // K (normalised as asked); BoW: word intersection
  int orientation = 0;    // 0..3, multiples of 90 deg, counter-clockwise
  Point2 offset;          // m, in the db map's planned frame (BoW: 0, 0)
  size_t rank = 0;        // 0 = best
};

// InvalidArgument naming the bad field, or OK.
Status ValidateIndexOptions(const IndexOptions& options);
Status ValidateRetrieveOptions(const RetrieveOptions& options);

}  // namespace lmd
