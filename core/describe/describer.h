// Local map descriptor (paper sec. "Local Map Descriptor"): a bag of features,
// each an appearance word (B-bit code of a polestar / shape-context histogram
// around an interest point), a pose word source (the interest point's position
// in the planned frame) and a 60-bit change word.
//
// Interest points: the map's points are binned on an interest_cell_m grid laid
// in the PLANNED frame (so two maps of one place, whose frames agree, pick the
// same cells); one interest point per occupied cell = the point of that cell
// nearest to the cell centre. 0.1 m cells (the paper's) give 500-3000 features
// on real logs, 7-40 KB per map; 0.5 m cells keep the wall layout (one point
// every 0.5 m along each wall) at ~25x fewer features, and max_features (the
// cells nearest to the planned origin) caps the worst case so that a stored
// map stays under 2 KB with its postings.
//
// Histogram: points rasterised at 0.01 m (duplicates in a cell count once),
// those within radius R of the interest point counted in `shells` equal-width
// rings x A sectors, soft-binned (each point split linearly between the two
// nearest shells and sectors). Sectors are measured from the planned heading turned by
// k * 90 deg, k in 0..3 chosen per feature as the axis direction holding the
// most points (ties broken toward the next counter-clockwise axis). Because
// the planned heading is only defined modulo 90 deg, this canonical k makes
// the appearance and change words of a place the same under any of the 4
// orientation hypotheses the index tries, for every A (A = 3 and 6 sectors do
// not map onto themselves under a 90 deg turn, so a fixed sector origin would
// not). Sector boundaries sit 15 deg off the frame axes so that Manhattan
// walls never lie on a boundary.
//
// Appearance word: sign(W h) with W a B x D Gaussian matrix from
// projection_seed (std::mt19937_64 + Box-Muller, versioned by
// kProjectionVersion) and h the soft-binned histogram, not centred (centring
// put the flat profile of a straight wall on every bit boundary, so wall
// words flipped under millimetre noise). Inner word (inner_radius_m > 0): the
// same construction on the points within the inner radius. Change word: the (R, A) = (6, 6) histogram (10 x 6 = 60 bins),
// bit i = bin i > mean of the 60 bins.
#pragma once

#include <cstdint>
#include <string>

#include "core/describe/lmd_codec.h"
#include "core/types.h"

namespace lmd {

// Bumped whenever the projection matrix generation changes (words of
// different versions are not comparable).
inline constexpr uint32_t kProjectionVersion = 2;

struct DescriptorSetting {
  double radius_m = 1.0;  // R, m
  int sectors = 1;        // A
};

// The paper's settings #1..#8: (1,1) (6,3) (12,6) (1,6) (3,6) (6,6) (3,1)
// (6,1). Numbers outside 1..8 give #1.
DescriptorSetting PaperDescriptorSetting(int number);

struct DescriberOptions {
  DescriptorSetting setting = {1.0, 1};  // paper setting #1 (default)
  int shells = 10;                       // radial shells (paper: 10)
  int word_bits = 10;                    // B, 1..16 (paper: 10)
  uint64_t projection_seed = 0x6c6d64'70726f6aULL;  // "lmdproj"
  double raster_m = 0.01;                // m, temporary grid (paper: 0.01)
  double interest_cell_m = 0.5;          // m, interest point grid (paper: 0.1; see above)
  int max_features = 80;                 // cap, nearest the planned origin; 0 = none
  bool change_words = true;              // compute the (6, 6) change word
  // m; in (0, R): each feature also gets an inner word, the same histogram
  // within this smaller radius (only with word_bits <= 15: the index tags
  // inner words with bit 15, pyramid_kernel.h). 0 = none (the paper's descriptor).
  double inner_radius_m = 0.0;
};

// The product default (lmdd, lmd-bench; lmd-eval "best" adds inner words):
// paper setting #6 (R = 6 m, A = 6) with 13-bit words. Setting #1's 10-dimensional radial
// profile gives every straight wall the same word (47 % of all features on
// simulated buildings), so every stored map shares words with every query and
// no inverted file can skip any; #6 with 13 bits spreads features over ~4000
// words (the most frequent 4.7 %) while words stay stable enough to match on
// real logs. Measured: lmd-bench index, 10k maps, the inverted file 1.0x ->
// 7x faster than exhaustive; lmd-eval retrieval, six logs not used for tuning
// (seed 2, 40 queries each), best place@1 0.63 -> 0.67 (docs/results.md).
DescriberOptions ProductDescriberOptions();

// `options` with 3 m inner words and at most 64 features (two words each, so
// that a stored map stays under 2 KB with its postings): lmd-eval's best, and
// lmdd with inner_words = true. A 6 m context differs between two maps of
// one place when they saw different parts of it; the 3 m word of the same
// point often still matches. Measured (docs/results.md): the first stage's
// ANR 18.2 % -> 15.2 % and best's place@5 0.83 -> 0.84 (full run), at about
// 1.7x lmdd's CPU per query (retrieval 2.7x), which is why lmdd's default
// stays without them.
DescriberOptions WithInnerWords(DescriberOptions options);

// Describes `map` in `frame` (usually PlanViewpoint(map)). Features sorted by
// (y, x) of their interest cell; deterministic. An empty map gives an Lmd
// with no features and frame = `frame`.
Lmd Describe(const LocalMap& map, const Frame& frame, const DescriberOptions& options = {});

}  // namespace lmd
