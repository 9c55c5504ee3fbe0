// The spatial pyramid match kernel between a query Lmd and one stored map,
// in integer pose words so that every caller computes bit-identical scores.
// The inverted file (index.h) and the exhaustive scorer (exhaustive.h) both
// score a map with ScoreLmdMap / ScoreBowMap; they differ only in which maps
// they score.
//
// Definition (method kLmd), for each orientation o in {0, 90, 180, 270} deg:
//  1. Rotate the query pose words: q' = R(o) q (exact in integers).
//  2. Matches = pairs (query feature, db feature) with the same appearance
//     word and d = db - q' inside the box [-max_offset, max_offset]^2.
//     No match: this orientation scores 0.
//  3. Offset t = mean of d over the matches in the mode bin of the histogram
//     of d (bins of offset_bin_m; ties: smallest (bin x, bin y)), rounded to
//     the nearest pose unit (halves up); |t| <= max_offset per axis.
//  4. Shift the query: q'' = q' + t. Level l cell of a pose p:
//     floor(p / (W 2^-l)), cells are anchored at the planned origin, so levels
//     nest. I^l = sum over (word, cell) of min(query count, db count).
//  5. K = I^0 / 2^L + sum_{l=1..L} I^l / 2^(L-l+1)  (L = 2: I0/4 + I1/4 + I2/2),
//     divided by the normalisation of |q|, |d| (retrieve_options.h).
// The map's score is the best orientation's (ties: the lowest o).
// Level 0 is one W x W cell (5 m), not the whole map: the paper's cell width
// W 2^-l at l = 0; plain word counts are the separate kBow baseline.
//
// Bounds used by the inverted file (index.h): cells nest, so I^2 <= I^1 <=
// I^0 <= min(|q|, |d|), and a query feature counts in I^l only if a db
// feature of its word lies in a level-l cell meeting its box (the shifted
// feature stays in the box).
#pragma once

#include <cstdint>
#include <vector>

#include "core/index/retrieve_options.h"
#include "core/types.h"

namespace lmd {

// A feature reduced to what retrieval uses: appearance word and pose word
// (position in the planned frame in units of IndexOptions::pose_quantum_m).
struct PoseFeature {
  uint32_t word = 0;
  int16_t x = 0;
  int16_t y = 0;
};

// Largest appearance word the index accepts (posting keys hold 16 bits).
inline constexpr uint32_t kMaxAppearanceWord = 0xFFFF;
// A feature's inner word (types.h) is indexed as one more pose feature at the
// same position, its word tagged with this bit so that it matches only inner
// words; both words of such a feature must then be below the tag.
inline constexpr uint32_t kInnerWordTag = 0x8000;

// The Lmd's features as pose features sorted by (word, x, y): one per
// feature, two for a feature with an inner word. InvalidArgument if a
// position is not finite or out of the int16 pose-word range, or a word
// exceeds kMaxAppearanceWord (kInnerWordTag - 1 for features with an inner word).
Result<std::vector<PoseFeature>> ToPoseFeatures(const Lmd& lmd, const IndexOptions& options);

// Pose features (= postings) ToPoseFeatures makes of `lmd`.
size_t PoseFeatureCount(const Lmd& lmd);

// `features` without those whose word is in `stop_words` (sorted).
std::vector<PoseFeature> WithoutStopWords(std::vector<PoseFeature> features, const std::vector<uint32_t>& stop_words);

// floor(a / b) for b > 0.
inline int32_t FloorDiv(int32_t a, int32_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// floor(x / d) by one multiplication (Granlund-Montgomery round-up method)
// for |x| < 2^17, falling back to FloorDiv outside; 1 <= d < 2^15.
class FloorDivider {
 public:
  FloorDivider() = default;
  explicit FloorDivider(int32_t d);
  int32_t operator()(int32_t x) const {
    if (x < -bias_ || x >= limit_) return FloorDiv(x, d_);
    return static_cast<int32_t>((static_cast<uint64_t>(x + bias_) * magic_) >> shift_) - bias_cells_;
  }

 private:
  int32_t d_ = 1;
  uint64_t magic_ = 1;
  int shift_ = 0;
  int32_t bias_ = 0, bias_cells_ = 0, limit_ = 0;
};

// A query prepared once and scored against many maps.
struct PreparedLmdQuery {
  std::vector<PoseFeature> features;  // sorted by (word, x, y)
  // rotated[o][i] = R(o * 90 deg) * features[i] (x, y), int32.
  std::vector<int32_t> rx[4];
  std::vector<int32_t> ry[4];
  // order[o] = feature indices sorted by (word, rx[o]): within a word's range
  // the features in increasing rotated x.
  std::vector<uint32_t> order[4];
  FloorDivider fine_div;  // by the finest cell width
  FloorDivider bin_div;   // by offset_bin
  int32_t max_offset = 0;   // pose units
  int32_t offset_bin = 1;   // pose units
  // Offset bins per axis inside the box, from bin_lo; 0 when the box holds too
  // many bins to count them in an array (the mode is then found by sorting).
  int32_t bin_lo = 0;
  int32_t bins = 0;
  int32_t cell0 = 1;        // pose units, level-0 cell width
  int levels = 2;
  Normalization normalization = Normalization::kSqrt;
};

// Prepares `query` (pose features sorted as ToPoseFeatures returns them).
PreparedLmdQuery PrepareLmdQuery(std::vector<PoseFeature> query, const IndexOptions& index_options,
                           const RetrieveOptions& options);

// raw / norm(nq, nd); 0 when either map is empty. The same expression is used
// for scores and bounds so that a bound is never below the score it bounds.
double NormalizeScore(double raw, size_t nq, size_t nd, Normalization normalization);

struct KernelScore {
  double score = 0.0;
  int orientation = 0;
  int32_t offset_x = 0;  // pose units
  int32_t offset_y = 0;
};

// Reusable buffers (one per thread) so that scoring allocates nothing.
struct KernelScratch {
  struct Group { uint32_t q_begin, q_end, d_begin, d_end; };  // one shared word
  struct Match { int64_t bin; int32_t dx, dy; };
  std::vector<Group> groups;
  std::vector<Match> matches;
  std::vector<uint32_t> bin_counts;  // matches per offset bin (when query.bins > 0); all zero between uses
  // Groups with several features on a side: their distinct db cells per level,
  // sorted (cells[offsets[k * (L + 1) + l] ...]).
  std::vector<uint32_t> multi;
  std::vector<int64_t> cells;
  std::vector<uint32_t> offsets;
  std::vector<uint32_t> run;   // db features in each (distinct) cell
  std::vector<uint32_t> used;  // how many of them are already matched
};

// kLmd score of one stored map (pose features sorted by (word, x, y)), over
// the orientations whose bit is set in `orientations` (bit o = o * 90 deg);
// the others are skipped (the inverted file skips those that cannot reach
// its top k).
KernelScore ScoreLmdMap(const PreparedLmdQuery& query, const PoseFeature* db, size_t db_size,
                        KernelScratch* scratch, unsigned orientations = 0xF);

// kBow score: sum over words of min(query count, db count), normalised.
double ScoreBowMap(const PreparedLmdQuery& query, const PoseFeature* db, size_t db_size);

}  // namespace lmd
